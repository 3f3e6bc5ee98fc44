#include "rgbdtam/hal/udp_link.hpp"

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstring>

namespace rgbdtam {

static_assert(sizeof(sockaddr_in) <= 16, "UdpLink::remote_ holds a sockaddr_in");

UdpLink::~UdpLink() {
  if (fd_ >= 0) ::close(fd_);
}

Status UdpLink::open(const char* remote_ip, uint16_t remote_port, uint16_t local_port) {
  sockaddr_in remote{};
  if (remote_ip != nullptr) {
    remote.sin_family = AF_INET;
    remote.sin_port = htons(remote_port);
    if (inet_pton(AF_INET, remote_ip, &remote.sin_addr) != 1 || remote_port == 0) {
      return Status::error(StatusCode::kInvalidArgument,
                           "UDP endpoint '%s:%u' is not a numeric IPv4 address and port", remote_ip,
                           remote_port);
    }
    std::memcpy(remote_, &remote, sizeof(remote));
    has_remote_ = true;
  }
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) return Status::error(StatusCode::kIoError, "UDP socket: %s", std::strerror(errno));
  // A ground station is often reached by broadcast (x.x.x.255, 255.255.255.255).
  const int on = 1;
  if (::setsockopt(fd_, SOL_SOCKET, SO_BROADCAST, &on, sizeof(on)) != 0) {
    return Status::error(StatusCode::kIoError, "UDP broadcast: %s", std::strerror(errno));
  }
  sockaddr_in local{};
  local.sin_family = AF_INET;
  local.sin_port = htons(local_port);
  local.sin_addr.s_addr = htonl(INADDR_ANY);
  // Bound now even to an ephemeral port, so that local_port() names where the autopilot's
  // replies arrive before the first send.
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&local), sizeof(local)) != 0) {
    return Status::error(StatusCode::kIoError, "UDP bind to port %u: %s", local_port,
                         std::strerror(errno));
  }
  socklen_t len = sizeof(local);
  if (::getsockname(fd_, reinterpret_cast<sockaddr*>(&local), &len) == 0) {
    local_port_ = ntohs(local.sin_port);
  }
  return Status::ok();
}

bool UdpLink::send(const uint8_t* bytes, size_t n) {
  if (!has_remote_) {
    ++counters_.errors;
    return false;
  }
  const ssize_t sent = ::sendto(fd_, bytes, n, MSG_DONTWAIT | MSG_NOSIGNAL,
                                reinterpret_cast<const sockaddr*>(remote_), sizeof(sockaddr_in));
  if (sent == static_cast<ssize_t>(n)) {
    ++counters_.tx_frames;
    counters_.tx_bytes += n;
    return true;
  }
  // Nobody listening (ECONNREFUSED from an earlier ICMP) loses the frame like a full buffer.
  if (sent < 0 &&
      (errno == EAGAIN || errno == EWOULDBLOCK || errno == ENOBUFS || errno == ECONNREFUSED)) {
    ++counters_.drops;
  } else {
    ++counters_.errors;
    counters_.last_error = errno;
  }
  return false;
}

size_t UdpLink::receive(uint8_t* bytes, size_t n) {
  const ssize_t got = ::recv(fd_, bytes, n, MSG_DONTWAIT);
  if (got <= 0) {
    if (got < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != ECONNREFUSED) {
      ++counters_.errors;
      counters_.last_error = errno;
    }
    return 0;
  }
  counters_.rx_bytes += static_cast<uint64_t>(got);
  return static_cast<size_t>(got);
}

}  // namespace rgbdtam
