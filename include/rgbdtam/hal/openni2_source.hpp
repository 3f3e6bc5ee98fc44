#pragma once
// PrimeSense-family sensors (PrimeSense, Asus Xtion, Carmine, Orbbec Astra) through OpenNI2:
// depth in millimetres and RGB colour at the camera's size, depth registered to colour by the
// device and the two streams frame-synchronised where it supports them, mirroring off. Frames
// are paired by their device timestamps and copied out, so a SensorFrame stays valid until the
// next one; OpenNI2 keeps only each stream's newest frame, and colour frames never delivered
// (frame-index gaps) count as drops.
//
// OpenNI2 is a shared library that loads driver plugins: this backend is built when
// RGBDTAM_WITH_OPENNI2 is on (the host-dynamic preset), never into the static firmware.
// OpenNI::shutdown() is never called: Debian's drivers leave a thread running that crashes once
// shutdown unloads them; initialisation happens once per process, and exit releases the rest.

#include <cstdint>
#include <memory>

#include "rgbdtam/core/image.hpp"
#include "rgbdtam/port/sensor_source.hpp"

namespace openni {
class Device;
class VideoStream;
}  // namespace openni

namespace rgbdtam {

struct OpenNi2Capabilities {
  bool registered = false;  // the device registers depth to colour
  bool synchronised = false;
};

class OpenNi2Source : public LiveSensor {
 public:
  OpenNi2Source();
  ~OpenNi2Source() override;
  // uri: "default" for the first device, else an OpenNI URI ("Dummy", a device path, a .oni).
  // Both streams at width x height and fps; timeout_ms bounds the wait for a frame pair.
  Status open(const char* uri, int width, int height, int fps, int64_t max_pair_dt_ns,
              int timeout_ms);
  Status next(SensorFrame* frame, Status* warning) override;
  // The streams run from open(); start() and stop() have nothing more to do.
  Status start(const ThreadPlacement&) override { return Status::ok(); }
  void stop() override {}
  int64_t arrival_ns() const override { return arrival_ns_; }
  uint32_t dropped() const override { return dropped_; }
  void close();
  const OpenNi2Capabilities& capabilities() const { return capabilities_; }

 private:
  Status open_stream() override;
  void close_stream() override { close(); }
  Status receive(int stream, const void* data, int bytes, int stride, int width, int height,
                 int64_t stamp_ns, int index);

  // Each stream's last two frames, converted: the two streams may run a frame out of phase
  // (depth k+1 before colour k), so the partner of a new frame may be the one before the newest.
  struct Slot {
    int64_t stamp_ns = 0;
    int index = -1;
    bool pending = false;  // received and not yet delivered
  };
  std::unique_ptr<openni::Device> device_;
  std::unique_ptr<openni::VideoStream> depth_stream_, colour_stream_;
  char uri_[256] = {};
  int width_ = 0, height_ = 0, fps_ = 0;
  int64_t max_pair_dt_ns_ = 0;
  int timeout_ms_ = 0;
  ImageU16 depth_[2];
  ImageU8 gray_[2];
  Slot slots_[2][2];        // [depth, colour][slot]
  int newest_[2] = {0, 0};  // each stream's newest slot
  int last_colour_index_ = -1;
  OpenNi2Capabilities capabilities_;
  uint32_t sequence_ = 0;
  uint32_t dropped_ = 0;
  int64_t arrival_ns_ = 0;
};

}  // namespace rgbdtam
