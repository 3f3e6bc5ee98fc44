#include "rgbdtam/hal/freenect_source.hpp"

#include <libfreenect.h>

#include <cmath>
#include <cstring>

#include "rgbdtam/hal/clock.hpp"

// The libfreenect calls the backend makes, as a table: the firmware can hold the USB driver and
// fakenect (libfreenect's recording player, its symbols renamed fakenect_*) side by side.
// clang-format off
#define RGBDTAM_FREENECT_CALLS(X)                                                          \
  X(init) X(shutdown) X(select_subdevices) X(num_devices) X(open_device) X(close_device)   \
  X(set_user) X(get_user) X(find_video_mode) X(find_depth_mode) X(set_video_mode)          \
  X(set_depth_mode) X(set_depth_callback) X(set_video_callback) X(start_depth)             \
  X(start_video) X(stop_depth) X(stop_video) X(process_events_timeout)
// clang-format on

#if RGBDTAM_WITH_FAKENECT
#define RGBDTAM_DECLARE_FAKENECT(call) extern "C" decltype(freenect_##call) fakenect_##call;
RGBDTAM_FREENECT_CALLS(RGBDTAM_DECLARE_FAKENECT)
#endif

namespace rgbdtam {

struct FreenectDriver {
#define RGBDTAM_DRIVER_FIELD(call) decltype(&freenect_##call) call;
  RGBDTAM_FREENECT_CALLS(RGBDTAM_DRIVER_FIELD)
  freenect_depth_cb depth_callback;
  freenect_video_cb video_callback;
};

namespace {
template <const FreenectDriver& driver>
void depth_callback(freenect_device* dev, void* data, uint32_t ticks) {
  static_cast<FreenectSource*>(driver.get_user(dev))->on_depth(data, ticks);
}
template <const FreenectDriver& driver>
void video_callback(freenect_device* dev, void* data, uint32_t ticks) {
  static_cast<FreenectSource*>(driver.get_user(dev))->on_video(data, ticks);
}
constexpr uint16_t kRawNoData = 2047;
// Both streams are stamped by the device's 60 MHz clock (libfreenect's own OpenNI2 driver divides
// its stamps by 60 for microseconds): 50 ns every three ticks.
constexpr int64_t kNsPerThreeTicks = 50;
// A frame pair takes many USB transfers: the event loop turns until one is complete, for at
// most this long (a silent device is then an error the stall recovery sees).
constexpr int64_t kFrameTimeoutNs = 1'000'000'000;
constexpr int kEventWaitUs = 50'000;
}  // namespace

#define RGBDTAM_USB_CALL(call) freenect_##call,
extern const FreenectDriver kFreenectUsbDriver = {RGBDTAM_FREENECT_CALLS(RGBDTAM_USB_CALL)
                                                      depth_callback<kFreenectUsbDriver>,
                                                  video_callback<kFreenectUsbDriver>};
#if RGBDTAM_WITH_FAKENECT
#define RGBDTAM_FAKENECT_CALL(call) fakenect_##call,
extern const FreenectDriver kFakenectDriver = {RGBDTAM_FREENECT_CALLS(RGBDTAM_FAKENECT_CALL)
                                                   depth_callback<kFakenectDriver>,
                                               video_callback<kFakenectDriver>};
#endif

uint16_t FreenectSource::raw_to_mm(uint16_t raw) {
  if (raw >= kRawNoData) return 0;
  const double inverse_m = 3.3309495161 - 0.0030711016 * raw;
  if (inverse_m <= 1e-3) return 0;
  const double mm = 1000.0 / inverse_m;
  return mm > 65535.0 ? 0 : static_cast<uint16_t>(std::lround(mm));
}

FreenectSource::~FreenectSource() { close(); }

Status FreenectSource::open(const FreenectDriver& driver, int device_index, FreenectDepth depth,
                            uint32_t max_pair_ticks) {
  driver_ = &driver;
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
  if (driver_->init(&ctx_, nullptr) < 0) {
    ctx_ = nullptr;
    return Status::error(StatusCode::kIoError, "libfreenect: cannot initialise (libusb)");
  }
  driver_->select_subdevices(ctx_, FREENECT_DEVICE_CAMERA);
  const int devices = driver_->num_devices(ctx_);
  if (device_index < 0 || device_index >= devices) {
    return Status::error(StatusCode::kNotFound, "libfreenect: Kinect %d not found (%d attached)",
                         device_index, devices);
  }
  if (driver_->open_device(ctx_, &dev_, device_index) < 0) {
    dev_ = nullptr;
    return Status::error(StatusCode::kIoError, "libfreenect: cannot open Kinect %d", device_index);
  }
  driver_->set_user(dev_, this);
  const freenect_frame_mode video =
      driver_->find_video_mode(FREENECT_RESOLUTION_MEDIUM, FREENECT_VIDEO_RGB);
  const freenect_frame_mode depth_mode = driver_->find_depth_mode(
      FREENECT_RESOLUTION_MEDIUM,
      depth == FreenectDepth::kRegistered ? FREENECT_DEPTH_REGISTERED : FREENECT_DEPTH_11BIT);
  if (!video.is_valid || !depth_mode.is_valid || driver_->set_video_mode(dev_, video) < 0 ||
      driver_->set_depth_mode(dev_, depth_mode) < 0) {
    return Status::error(StatusCode::kInvalidArgument,
                         "libfreenect: 640x480 RGB and %s depth modes refused",
                         depth == FreenectDepth::kRegistered ? "registered" : "11-bit");
  }
  driver_->set_depth_callback(dev_, driver_->depth_callback);
  driver_->set_video_callback(dev_, driver_->video_callback);
  if (driver_->start_depth(dev_) < 0 || driver_->start_video(dev_) < 0) {
    return Status::error(StatusCode::kIoError, "libfreenect: cannot start the streams");
  }
  return Status::ok();
}

void FreenectSource::on_depth(const void* data, uint32_t ticks) {
  if (have_depth_) ++dropped_;  // overtaken before it was paired: the newest is kept
  // Bytes, not uint16_t: fakenect hands over its file buffer just past an odd-length header.
  const auto* in = static_cast<const uint8_t*>(data);
  uint16_t* out = depth_.data();
  const int n = kWidth * kHeight;
  if (depth_mode_ == FreenectDepth::kRegistered) {
    std::memcpy(out, in, sizeof(uint16_t) * static_cast<size_t>(n));
  } else {
    for (int i = 0; i < n; ++i) {
      uint16_t raw;
      std::memcpy(&raw, in + 2 * i, sizeof(raw));
      out[i] = raw_lut_[raw & 2047];
    }
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
    if (driver_->process_events_timeout(ctx_, &wait) < 0) {
      return Status::error(StatusCode::kEndOfStream, "libfreenect: the stream ended");
    }
    if (!have_depth_ || !have_video_) continue;
    // Modulo 2^32: the clock wraps every 71.6 s.
    const int32_t depth_after_colour_ticks = static_cast<int32_t>(depth_ticks_ - colour_ticks_);
    const uint32_t gap = depth_after_colour_ticks < 0
                             ? 0u - static_cast<uint32_t>(depth_after_colour_ticks)
                             : static_cast<uint32_t>(depth_after_colour_ticks);
    if (gap > max_pair_ticks_) {
      // The older one waits for a newer partner.
      if (depth_after_colour_ticks < 0)
        have_depth_ = false;
      else
        have_video_ = false;
      continue;
    }
    arrival_ns_ = monotonic_ns();
    frame->sequence = sequence_++;
    frame->timestamp_ns = arrival_ns_;
    // The depth keeps its own instant: depth.at_its_instant tracks it from where the camera was.
    frame->depth_timestamp_ns =
        frame->timestamp_ns + depth_after_colour_ticks * kNsPerThreeTicks / 3;
    frame->gray = gray_.data();
    frame->depth = depth_.data();
    frame->width_px = frame->depth_width_px = kWidth;
    frame->height_px = frame->depth_height_px = kHeight;
    return Status::ok();
  }
  return Status::error(StatusCode::kIoError,
                       "libfreenect: no paired colour and depth frame for %lld ms",
                       static_cast<long long>(kFrameTimeoutNs / 1'000'000));
}

void FreenectSource::close() {
  if (dev_ != nullptr) {
    driver_->stop_depth(dev_);
    driver_->stop_video(dev_);
    driver_->close_device(dev_);
    dev_ = nullptr;
  }
  if (ctx_ != nullptr) {
    driver_->shutdown(ctx_);
    ctx_ = nullptr;
  }
}

}  // namespace rgbdtam
