#pragma once
// The pose link over UDP: datagrams to one numeric IPv4 endpoint, each frame one datagram.
// Non-blocking; a datagram the socket cannot take now is dropped and counted.

#include <cstdint>

#include "rgbdtam/core/status.hpp"
#include "rgbdtam/port/byte_link.hpp"

namespace rgbdtam {

class UdpLink : public ByteLink {
 public:
  ~UdpLink() override;
  // remote_ip may be null (receive only); local_port 0 binds an ephemeral port.
  Status open(const char* remote_ip, uint16_t remote_port, uint16_t local_port);
  bool send(const uint8_t* bytes, size_t n) override;
  size_t receive(uint8_t* bytes, size_t n) override;
  uint16_t local_port() const { return local_port_; }

 private:
  int fd_ = -1;
  bool has_remote_ = false;
  uint8_t remote_[16] = {};  // sockaddr_in, kept opaque so the header needs no socket headers
  uint16_t local_port_ = 0;
};

}  // namespace rgbdtam
