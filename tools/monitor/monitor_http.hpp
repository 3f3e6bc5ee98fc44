#pragma once
// The monitor's live page over HTTP (Debian's libmicrohttpd): GET / is one self-contained page
// (tools/monitor/monitor_page.html, no external scripts, fonts or CDNs: a robot's network has no
// internet); GET /state.json?since=N is the state with the trajectory from point N on.
#include <mutex>

#include "monitor_state.hpp"
#include "rgbdtam/core/status.hpp"

struct MHD_Daemon;

namespace rgbdtam {

// A page on a robot's network must outlive clients that open connections and never finish a
// request: beyond these, new connections are refused until idle ones are closed.
struct HttpLimits {
  unsigned connections = 64;  // open at once, from everyone ...
  unsigned per_client = 32;   // ... and from one address
  unsigned idle_s = 10;       // a connection idle this long (a partial request too) is closed
};

class MonitorHttp {
 public:
  ~MonitorHttp() { stop(); }
  // address: ip:port, e.g. 127.0.0.1:8080. The state is read under `lock`.
  Status start(const char* address, const MonitorState* state, std::mutex* lock,
               const HttpLimits& limits = HttpLimits());
  void stop();
  uint16_t port() const { return port_; }

  // For libmicrohttpd's C callback.
  const MonitorState* state_ = nullptr;
  std::mutex* lock_ = nullptr;

 private:
  MHD_Daemon* daemon_ = nullptr;
  uint16_t port_ = 0;
};

}  // namespace rgbdtam
