#pragma once
// The pose link over a serial port (termios, raw 8N1, non-blocking). Frames wait in a fixed
// transmit ring and are written as the port accepts them; a frame that does not fit in the
// ring is refused whole and counted as a drop, so the caller never waits.

#include <cstdint>

#include "rgbdtam/core/status.hpp"
#include "rgbdtam/port/byte_link.hpp"

namespace rgbdtam {

class SerialLink : public ByteLink {
 public:
  static constexpr size_t kTxRingBytes = 4096;
  ~SerialLink() override;
  // A baud rate termios does not define is an error naming it.
  Status open(const char* device, uint32_t baud);
  bool send(const uint8_t* bytes, size_t n) override;
  size_t flush() override;
  size_t receive(uint8_t* bytes, size_t n) override;
  uint32_t line_rate_bytes_per_s() const override { return baud_ / 10; }  // 8N1: 10 bits a byte

 private:
  int fd_ = -1;
  uint32_t baud_ = 0;
  uint8_t ring_[kTxRingBytes] = {};
  size_t head_ = 0;  // next byte to write out
  size_t used_ = 0;
};

}  // namespace rgbdtam
