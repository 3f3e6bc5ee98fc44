#include "rgbdtam/hal/serial_link.hpp"

#include <errno.h>
#include <fcntl.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>

namespace rgbdtam {
namespace {
bool termios_speed(uint32_t baud, speed_t* speed) {
  struct Rate {
    uint32_t baud;
    speed_t speed;
  };
  static constexpr Rate kRates[] = {{9600, B9600},       {19200, B19200},     {38400, B38400},
                                    {57600, B57600},     {115200, B115200},   {230400, B230400},
                                    {460800, B460800},   {500000, B500000},   {921600, B921600},
                                    {1000000, B1000000}, {1500000, B1500000}, {2000000, B2000000},
                                    {3000000, B3000000}};
  for (const Rate& r : kRates) {
    if (r.baud == baud) {
      *speed = r.speed;
      return true;
    }
  }
  return false;
}
}  // namespace

SerialLink::~SerialLink() {
  if (fd_ >= 0) ::close(fd_);
}

Status SerialLink::open(const char* device, uint32_t baud) {
  speed_t speed;
  if (!termios_speed(baud, &speed)) {
    return Status::error(StatusCode::kInvalidArgument,
                         "serial baud %u is not a standard rate (9600 ... 3000000)", baud);
  }
  fd_ = ::open(device, O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) {
    return Status::error(StatusCode::kIoError, "serial port '%s': %s", device,
                         std::strerror(errno));
  }
  termios t{};
  if (::tcgetattr(fd_, &t) != 0) {
    return Status::error(StatusCode::kIoError, "serial port '%s' is not a terminal: %s", device,
                         std::strerror(errno));
  }
  ::cfmakeraw(&t);
  t.c_cflag |= CLOCAL | CREAD;
  t.c_cflag &= ~static_cast<tcflag_t>(CRTSCTS | CSTOPB);
  t.c_cc[VMIN] = 0;
  t.c_cc[VTIME] = 0;
  if (::cfsetispeed(&t, speed) != 0 || ::cfsetospeed(&t, speed) != 0 ||
      ::tcsetattr(fd_, TCSANOW, &t) != 0) {
    return Status::error(StatusCode::kIoError, "serial port '%s' at %u baud: %s", device, baud,
                         std::strerror(errno));
  }
  baud_ = baud;
  return Status::ok();
}

bool SerialLink::send(const uint8_t* bytes, size_t n) {
  flush();
  if (n > kTxRingBytes - used_) {
    ++counters_.drops;
    return false;
  }
  const size_t tail = (head_ + used_) % kTxRingBytes;
  const size_t first = std::min(n, kTxRingBytes - tail);
  std::memcpy(ring_ + tail, bytes, first);
  std::memcpy(ring_, bytes + first, n - first);
  used_ += n;
  ++counters_.tx_frames;
  flush();
  return true;
}

size_t SerialLink::flush() {
  while (used_ > 0) {
    const size_t chunk = std::min(used_, kTxRingBytes - head_);
    const ssize_t written = ::write(fd_, ring_ + head_, chunk);
    if (written < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) break;
      ++counters_.errors;  // the port failed: what was queued is lost
      counters_.last_error = errno;
      counters_.lost_bytes += used_;
      used_ = 0;
      break;
    }
    head_ = (head_ + static_cast<size_t>(written)) % kTxRingBytes;
    used_ -= static_cast<size_t>(written);
    counters_.tx_bytes += static_cast<uint64_t>(written);
    if (static_cast<size_t>(written) < chunk) break;
  }
  return used_;
}

size_t SerialLink::receive(uint8_t* bytes, size_t n) {
  const ssize_t got = ::read(fd_, bytes, n);
  if (got <= 0) {
    if (got < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
      ++counters_.errors;
      counters_.last_error = errno;
    }
    return 0;
  }
  counters_.rx_bytes += static_cast<uint64_t>(got);
  return static_cast<size_t>(got);
}

}  // namespace rgbdtam
