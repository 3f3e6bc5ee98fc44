#pragma once
// Kinect v1 through libfreenect (libusb): colour and depth frames with the device's
// timestamps, delivered on the caller's thread (it runs libfreenect's event loop). Only the
// camera subdevice is opened, so the tilt motor and the LED stay as they were.
//
// Depth: `registered` asks libfreenect for millimetres registered to the colour camera (the
// device's own calibration); `raw` takes 11-bit disparity and converts it with the OpenKinect
// approximation z = 1 / (3.3309495161 - 0.0030711016 d) m (unregistered), the one mode
// fakenect (libfreenect's recording player) can play back.
//
// Built when RGBDTAM_WITH_FREENECT is on: static builds link libfreenect and libusb built from
// Debian's sources (tools/build_kinect_libs.sh) and hold fakenect beside them
// (RGBDTAM_WITH_FAKENECT: kFakenectDriver plays the dump in $FAKENECT_PATH; it allocates per frame,
// so it is for emulation and tests, never a robot); dynamic builds link Debian's libfreenect.

#include <cstdint>

#include "rgbdtam/core/image.hpp"
#include "rgbdtam/port/sensor_source.hpp"

struct _freenect_context;
struct _freenect_device;

namespace rgbdtam {

// Which libfreenect the backend calls: the USB driver, or fakenect (static builds).
struct FreenectDriver;
extern const FreenectDriver kFreenectUsbDriver;
#if RGBDTAM_WITH_FAKENECT
extern const FreenectDriver kFakenectDriver;
#endif

enum class FreenectDepth { kRegistered, kRaw };

class FreenectSource : public LiveSensor {
 public:
  static constexpr int kWidth = 640, kHeight = 480;
  ~FreenectSource() override;
  // max_pair_ticks: the largest device-timestamp gap between paired depth and colour frames.
  Status open(const FreenectDriver& driver, int device_index, FreenectDepth depth,
              uint32_t max_pair_ticks);
  Status next(SensorFrame* frame, Status* warning) override;
  // libfreenect's event loop runs inside next(), on the caller's thread.
  Status start(const ThreadPlacement&) override { return Status::ok(); }
  void stop() override {}
  int64_t arrival_ns() const override { return arrival_ns_; }
  uint32_t dropped() const override { return dropped_; }
  void close();

  // The device timestamps of the last frame next() delivered.
  uint32_t depth_device_timestamp() const { return depth_ticks_; }
  uint32_t colour_device_timestamp() const { return colour_ticks_; }
  // Raw 11-bit disparity to millimetres (0 = no data), as the raw mode converts it.
  static uint16_t raw_to_mm(uint16_t raw);

  // libfreenect's callbacks; public only so the C callbacks can reach them.
  void on_depth(const void* data, uint32_t ticks);
  void on_video(const void* data, uint32_t ticks);

 private:
  Status open_stream() override;
  void close_stream() override { close(); }

  const FreenectDriver* driver_ = nullptr;
  _freenect_context* ctx_ = nullptr;
  int device_index_ = 0;
  _freenect_device* dev_ = nullptr;
  FreenectDepth depth_mode_ = FreenectDepth::kRegistered;
  uint32_t max_pair_ticks_ = 0;
  ImageU8 gray_;
  ImageU16 depth_;
  uint16_t raw_lut_[2048] = {};
  bool have_depth_ = false, have_video_ = false;
  uint32_t depth_ticks_ = 0, colour_ticks_ = 0;
  uint32_t sequence_ = 0;
  uint32_t dropped_ = 0;
  int64_t arrival_ns_ = 0;
};

}  // namespace rgbdtam
