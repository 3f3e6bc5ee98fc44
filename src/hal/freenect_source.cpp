#include "rgbdtam/hal/freenect_source.hpp"

#include <libfreenect.h>

#include <cmath>
#include <cstring>

#include "rgbdtam/hal/clock.hpp"

namespace rgbdtam {
namespace {
void depth_callback(freenect_device* dev, void* data, uint32_t ticks) {
  static_cast<FreenectSource*>(freenect_get_user(dev))->on_depth(data, ticks);
}
void video_callback(freenect_device* dev, void* data, uint32_t ticks) {
  static_cast<FreenectSource*>(freenect_get_user(dev))->on_video(data, ticks);
}
constexpr uint16_t kRawNoData = 2047;
// A frame pair takes many USB transfers: the event loop turns until one is complete, for at
// most this long (a silent device is then an error the stall recovery sees).
constexpr int64_t kFrameTimeoutNs = 1'000'000'000;
constexpr int kEventWaitUs = 50'000;
}  // namespace

uint16_t FreenectSource::raw_to_mm(uint16_t raw) {
  if (raw >= kRawNoData) return 0;
  const double inverse_m = 3.3309495161 - 0.0030711016 * raw;
  if (inverse_m <= 1e-3) return 0;
  const double mm = 1000.0 / inverse_m;
  return mm > 65535.0 ? 0 : static_cast<uint16_t>(std::lround(mm));
}

FreenectSource::~FreenectSource() { close(); }

Status FreenectSource::open(int device_index, FreenectDepth depth, uint32_t max_pair_ticks) {
  depth_mode_ = depth;
  max_pair_ticks_ = max_pair_ticks;
  gray_.allocate(kWidth, kHeight);
  depth_.allocate(kWidth, kHeight);
  for (int raw = 0; raw < 2048; ++raw) raw_lut_[raw] = raw_to_mm(static_cast<uint16_t>(raw));
  device_index_ = device_index;
  return open_stream();
}

Status FreenectSource::open_stream() {
  const int device_index = device_index_;
  const FreenectDepth depth = depth_mode_;
  if (freenect_init(&ctx_, nullptr) < 0) {
    ctx_ = nullptr;
    return Status::error(StatusCode::kIoError, "libfreenect: cannot initialise (libusb)");
  }
  freenect_select_subdevices(ctx_, FREENECT_DEVICE_CAMERA);
  const int devices = freenect_num_devices(ctx_);
  if (device_index < 0 || device_index >= devices) {
    return Status::error(StatusCode::kNotFound, "libfreenect: Kinect %d not found (%d attached)",
                         device_index, devices);
  }
  if (freenect_open_device(ctx_, &dev_, device_index) < 0) {
    dev_ = nullptr;
    return Status::error(StatusCode::kIoError, "libfreenect: cannot open Kinect %d", device_index);
  }
  freenect_set_user(dev_, this);
  const freenect_frame_mode video =
      freenect_find_video_mode(FREENECT_RESOLUTION_MEDIUM, FREENECT_VIDEO_RGB);
  const freenect_frame_mode depth_mode = freenect_find_depth_mode(
      FREENECT_RESOLUTION_MEDIUM,
      depth == FreenectDepth::kRegistered ? FREENECT_DEPTH_REGISTERED : FREENECT_DEPTH_11BIT);
  if (!video.is_valid || !depth_mode.is_valid || freenect_set_video_mode(dev_, video) < 0 ||
      freenect_set_depth_mode(dev_, depth_mode) < 0) {
    return Status::error(StatusCode::kInvalidArgument,
                         "libfreenect: 640x480 RGB and %s depth modes refused",
                         depth == FreenectDepth::kRegistered ? "registered" : "11-bit");
  }
  freenect_set_depth_callback(dev_, depth_callback);
  freenect_set_video_callback(dev_, video_callback);
  if (freenect_start_depth(dev_) < 0 || freenect_start_video(dev_) < 0) {
    return Status::error(StatusCode::kIoError, "libfreenect: cannot start the streams");
  }
  return Status::ok();
}

void FreenectSource::on_depth(const void* data, uint32_t ticks) {
  if (have_depth_) ++dropped_;  // overtaken before it was paired: the newest is kept
  const auto* in = static_cast<const uint16_t*>(data);
  uint16_t* out = depth_.data();
  const int n = kWidth * kHeight;
  if (depth_mode_ == FreenectDepth::kRegistered) {
    std::memcpy(out, in, sizeof(uint16_t) * static_cast<size_t>(n));
  } else {
    for (int i = 0; i < n; ++i) out[i] = raw_lut_[in[i] & 2047];
  }
  depth_ticks_ = ticks;
  have_depth_ = true;
}

void FreenectSource::on_video(const void* data, uint32_t ticks) {
  if (have_video_) ++dropped_;
  rgb_to_gray(static_cast<const uint8_t*>(data), gray_.data(), kWidth * kHeight);
  colour_ticks_ = ticks;
  have_video_ = true;
}

Status FreenectSource::next(SensorFrame* frame, Status* warning) {
  *warning = Status::ok();
  if (dev_ == nullptr) return Status::error(StatusCode::kIoError, "libfreenect: not open");
  have_depth_ = have_video_ = false;
  for (const int64_t deadline = monotonic_ns() + kFrameTimeoutNs; monotonic_ns() < deadline;) {
    timeval wait{0, kEventWaitUs};  // libusb's own default would block for a minute
    if (freenect_process_events_timeout(ctx_, &wait) < 0) {
      return Status::error(StatusCode::kEndOfStream, "libfreenect: the stream ended");
    }
    if (!have_depth_ || !have_video_) continue;
    const uint32_t gap =
        depth_ticks_ > colour_ticks_ ? depth_ticks_ - colour_ticks_ : colour_ticks_ - depth_ticks_;
    if (gap > max_pair_ticks_) {
      // The older one waits for a newer partner.
      if (depth_ticks_ < colour_ticks_)
        have_depth_ = false;
      else
        have_video_ = false;
      continue;
    }
    arrival_ns_ = monotonic_ns();
    frame->sequence = sequence_++;
    frame->timestamp_ns = arrival_ns_;
    frame->depth_timestamp_ns = frame->timestamp_ns;
    frame->gray = gray_.data();
    frame->depth = depth_.data();
    frame->width_px = kWidth;
    frame->height_px = kHeight;
    return Status::ok();
  }
  return Status::error(StatusCode::kIoError,
                       "libfreenect: no paired colour and depth frame for %lld ms",
                       static_cast<long long>(kFrameTimeoutNs / 1'000'000));
}

void FreenectSource::close() {
  if (dev_ != nullptr) {
    freenect_stop_depth(dev_);
    freenect_stop_video(dev_);
    freenect_close_device(dev_);
    dev_ = nullptr;
  }
  if (ctx_ != nullptr) {
    freenect_shutdown(ctx_);
    ctx_ = nullptr;
  }
}

}  // namespace rgbdtam
