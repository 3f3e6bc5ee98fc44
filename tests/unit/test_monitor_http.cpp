// The monitor's page server against clients that open connections and never finish a request:
// idle ones are closed, those beyond the cap wait, and the page is served again. The test waits
// on the server's events (a socket it closes or answers), never for the clock alone.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstring>
#include <mutex>
#include <string>

#include "monitor_http.hpp"

namespace rgbdtam {
namespace {

constexpr int kEventMs = 60'000;  // how long an event may take on a loaded machine

int connect_to(uint16_t port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(port);
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (fd < 0 || ::connect(fd, reinterpret_cast<sockaddr*>(&to), sizeof(to)) != 0) return -1;
  return fd;
}

bool send_all(int fd, const std::string& bytes) {
  return ::send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(bytes.size());
}

// Everything the server sends until it closes the connection, or until wait_ms pass.
std::string read_until_closed(int fd, int wait_ms, bool* closed) {
  std::string got;
  *closed = false;
  char buf[4096];
  pollfd p{fd, POLLIN, 0};
  while (::poll(&p, 1, wait_ms) == 1) {
    const ssize_t n = ::recv(fd, buf, sizeof(buf), 0);
    if (n <= 0) {
      *closed = true;
      break;
    }
    got.append(buf, static_cast<size_t>(n));
  }
  return got;
}

std::string get(uint16_t port, const char* path) {
  const int fd = connect_to(port);
  if (fd < 0) return "";
  bool closed = false;
  std::string response;
  if (send_all(fd, std::string("GET ") + path + " HTTP/1.0\r\n\r\n")) {
    response = read_until_closed(fd, kEventMs, &closed);
  }
  ::close(fd);
  return response;
}

// A port nobody listens on now (the kernel's choice for a socket bound to port 0).
std::string free_address() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in at{};
  at.sin_family = AF_INET;
  at.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t size = sizeof(at);
  if (::bind(fd, reinterpret_cast<sockaddr*>(&at), sizeof(at)) != 0 ||
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&at), &size) != 0) {
    at.sin_port = 0;
  }
  ::close(fd);
  return "127.0.0.1:" + std::to_string(ntohs(at.sin_port));
}

const char kPartialRequest[] = "GET /state.json HTTP/1.1\r\nHost: robot\r\n";  // never ended

TEST(MonitorHttp, AClientThatNeverFinishesItsRequestIsClosedOnceIdle) {
  MonitorState state(0);
  std::mutex lock;
  MonitorHttp http;
  HttpLimits limits;
  limits.idle_s = 1;
  const Status started = http.start(free_address().c_str(), &state, &lock, limits);
  ASSERT_TRUE(started.is_ok()) << started.message();
  const int idle = connect_to(http.port());
  ASSERT_GE(idle, 0);
  ASSERT_TRUE(send_all(idle, kPartialRequest));
  bool closed = false;
  const std::string answer = read_until_closed(idle, kEventMs, &closed);
  ::close(idle);
  EXPECT_TRUE(closed) << "the server closes an idle partial request";
  EXPECT_EQ(answer.find("200 OK"), std::string::npos) << "and does not answer it";
  EXPECT_NE(get(http.port(), "/state.json").find("200 OK"), std::string::npos);
}

TEST(MonitorHttp, ConnectionsBeyondTheCapWaitAndAreServedOnceTheIdleOnesGo) {
  MonitorState state(0);
  std::mutex lock;
  MonitorHttp http;
  HttpLimits limits;
  limits.connections = 4;
  limits.per_client = 4;
  limits.idle_s = 0;  // none: only the cap is at work
  const Status started = http.start(free_address().c_str(), &state, &lock, limits);
  ASSERT_TRUE(started.is_ok()) << started.message();
  int idle[4];
  for (int& fd : idle) {
    fd = connect_to(http.port());
    ASSERT_GE(fd, 0);
    ASSERT_TRUE(send_all(fd, kPartialRequest));
  }
  const int fifth = connect_to(http.port());
  ASSERT_GE(fifth, 0);
  ASSERT_TRUE(send_all(fifth, "GET /state.json HTTP/1.0\r\n\r\n"));
  // Not served while the four hold every slot. (A slow server passes this too; it cannot fail
  // because the machine is busy.)
  bool closed = false;
  EXPECT_EQ(read_until_closed(fifth, 200, &closed).find("200 OK"), std::string::npos);
  for (const int fd : idle) ::close(fd);
  const std::string answer = read_until_closed(fifth, kEventMs, &closed);
  ::close(fifth);
  EXPECT_NE(answer.find("200 OK"), std::string::npos) << "served once the idle clients left";
}

}  // namespace
}  // namespace rgbdtam
