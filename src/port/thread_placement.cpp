#include "rgbdtam/port/thread_placement.hpp"

#include <pthread.h>
#include <sched.h>

#include <cstring>

namespace rgbdtam {

namespace {
Status place(pthread_t handle, const ThreadPlacement& p, const char* name) {
  char short_name[16];  // the kernel keeps 15 characters
  std::strncpy(short_name, name, sizeof(short_name) - 1);
  short_name[sizeof(short_name) - 1] = '\0';
  (void)pthread_setname_np(handle, short_name);
  if (p.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(p.cpu, &set);
    const int err = pthread_setaffinity_np(handle, sizeof(set), &set);
    if (err != 0) {
      return Status::error(StatusCode::kInvalidArgument, "thread '%s' on CPU %d: %s", name, p.cpu,
                           std::strerror(err));
    }
  }
  if (p.priority > 0) {
    sched_param sp{};
    sp.sched_priority = p.priority;
    const int err = pthread_setschedparam(handle, SCHED_FIFO, &sp);
    if (err != 0) {
      return Status::error(StatusCode::kInvalidArgument,
                           "thread '%s' at SCHED_FIFO priority %d: %s (needs CAP_SYS_NICE or an "
                           "rtprio limit; set its priority to 0 in the board file)",
                           name, p.priority, std::strerror(err));
    }
  }
  return Status::ok();
}
}  // namespace

Status place_thread(std::thread& t, const ThreadPlacement& p, const char* name) {
  return place(t.native_handle(), p, name);
}

Status place_this_thread(const ThreadPlacement& p, const char* name) {
  return place(pthread_self(), p, name);
}

}  // namespace rgbdtam
