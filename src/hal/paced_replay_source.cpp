#include "rgbdtam/hal/paced_replay_source.hpp"

#include <errno.h>
#include <time.h>

#include <algorithm>

#include "rgbdtam/hal/clock.hpp"

namespace rgbdtam {
namespace {
void sleep_until_ns(int64_t t_ns) {
  timespec ts;
  ts.tv_sec = static_cast<time_t>(t_ns / 1000000000);
  ts.tv_nsec = static_cast<long>(t_ns % 1000000000);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}
}  // namespace

int64_t PacedReplaySource::due_ns(int index) const {
  return start_ns_ + (source_->rgb_list().entries[index].timestamp_ns - first_stamp_ns_);
}

Status PacedReplaySource::next(SensorFrame* frame, Status* warning) {
  const int n = source_->frame_count();
  int i = source_->position();
  if (i >= n) return source_->next(frame, warning);  // end of stream
  const int64_t now = monotonic_ns();
  if (start_ns_ < 0) {
    start_ns_ = now;
    first_stamp_ns_ = source_->rgb_list().entries[i].timestamp_ns;
  }
  // The newest frame already due; the ones before it were overtaken.
  int newest = i;
  while (newest + 1 < n && due_ns(newest + 1) <= now) ++newest;
  dropped_ += static_cast<uint32_t>(newest - i);
  source_->skip_to(newest);
  if (due_ns(newest) > now) sleep_until_ns(due_ns(newest));
  arrival_ns_ = std::max(now, due_ns(newest));
  return source_->next(frame, warning);
}

}  // namespace rgbdtam
