#include "rgbdtam/hal/openni2_source.hpp"

#include <OpenNI.h>

#include <cstdio>
#include <cstring>

#include "rgbdtam/hal/clock.hpp"

namespace rgbdtam {
namespace {
constexpr int kDepth = 0, kColour = 1;

// OpenNI's last error on one line (it ends its messages with tabs and newlines).
const char* last_error() {
  static thread_local char text[256];
  std::snprintf(text, sizeof(text), "%s", openni::OpenNI::getExtendedError());
  for (char* c = text; *c != '\0'; ++c) {
    if (*c == '\n' || *c == '\t') *c = ' ';
  }
  size_t n = std::strlen(text);
  while (n > 0 && text[n - 1] == ' ') text[--n] = '\0';
  return n > 0 ? text : "no detail";
}

// The stream's mode of exactly this size, rate and pixel format, or an error listing those it
// offers.
Status select_mode(openni::VideoStream* stream, const char* what, const char* uri, int width,
                   int height, int fps, openni::PixelFormat format) {
  auto matches = [&](const openni::VideoMode& m) {
    return m.getResolutionX() == width && m.getResolutionY() == height && m.getFps() == fps &&
           m.getPixelFormat() == format;
  };
  // Some devices (the Dummy one) refuse to be set even to the mode they are in.
  if (matches(stream->getVideoMode())) return Status::ok();
  const openni::Array<openni::VideoMode>& modes = stream->getSensorInfo().getSupportedVideoModes();
  char offered[160] = "";
  size_t used = 0;
  for (int i = 0; i < modes.getSize(); ++i) {
    const openni::VideoMode& m = modes[i];
    if (matches(m)) {
      if (stream->setVideoMode(m) != openni::STATUS_OK) {
        return Status::error(StatusCode::kIoError, "OpenNI2 '%s': %s mode refused: %s", uri, what,
                             last_error());
      }
      return Status::ok();
    }
    if (m.getPixelFormat() == format && used + 24 < sizeof(offered)) {
      used += static_cast<size_t>(
          std::snprintf(offered + used, sizeof(offered) - used, "%s%dx%d@%d", used > 0 ? " " : "",
                        m.getResolutionX(), m.getResolutionY(), m.getFps()));
    }
  }
  return Status::error(StatusCode::kInvalidArgument,
                       "OpenNI2 '%s': no %s mode %dx%d at %d Hz; it offers %s", uri, what, width,
                       height, fps, used > 0 ? offered : "none in this pixel format");
}

}  // namespace

OpenNi2Source::OpenNi2Source()
    : device_(new openni::Device),
      depth_stream_(new openni::VideoStream),
      colour_stream_(new openni::VideoStream) {}

OpenNi2Source::~OpenNi2Source() { close(); }

Status OpenNi2Source::open(const char* uri, int width, int height, int fps, int64_t max_pair_dt_ns,
                           int timeout_ms) {
  std::snprintf(uri_, sizeof(uri_), "%s", uri);
  width_ = width;
  height_ = height;
  fps_ = fps;
  max_pair_dt_ns_ = max_pair_dt_ns;
  timeout_ms_ = timeout_ms;
  for (int i = 0; i < 2; ++i) {
    gray_[i].allocate(width, height);
    depth_[i].allocate(width, height);
  }
  if (openni::OpenNI::initialize() != openni::STATUS_OK) {
    return Status::error(StatusCode::kIoError, "OpenNI2: cannot initialise: %s", last_error());
  }
  return open_stream();
}

Status OpenNi2Source::open_stream() {
  const bool any = std::strcmp(uri_, "default") == 0;
  if (device_->open(any ? openni::ANY_DEVICE : uri_) != openni::STATUS_OK) {
    return Status::error(StatusCode::kNotFound, "OpenNI2: cannot open '%s': %s", uri_,
                         last_error());
  }
  if (depth_stream_->create(*device_, openni::SENSOR_DEPTH) != openni::STATUS_OK ||
      colour_stream_->create(*device_, openni::SENSOR_COLOR) != openni::STATUS_OK) {
    return Status::error(StatusCode::kInvalidArgument,
                         "OpenNI2 '%s': needs depth and colour streams: %s", uri_, last_error());
  }
  RGBDTAM_RETURN_IF_ERROR(select_mode(depth_stream_.get(), "depth (mm)", uri_, width_, height_,
                                      fps_, openni::PIXEL_FORMAT_DEPTH_1_MM));
  RGBDTAM_RETURN_IF_ERROR(select_mode(colour_stream_.get(), "colour (RGB888)", uri_, width_,
                                      height_, fps_, openni::PIXEL_FORMAT_RGB888));
  // Devices without a mirror switch deliver unmirrored images; one stuck on is refused.
  for (openni::VideoStream* s : {depth_stream_.get(), colour_stream_.get()}) {
    (void)s->setMirroringEnabled(false);
    if (s->getMirroringEnabled()) {
      return Status::error(StatusCode::kInvalidArgument,
                           "OpenNI2 '%s': mirroring cannot be turned off", uri_);
    }
  }
  capabilities_.registered =
      device_->isImageRegistrationModeSupported(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) &&
      device_->setImageRegistrationMode(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) ==
          openni::STATUS_OK;
  capabilities_.synchronised = device_->setDepthColorSyncEnabled(true) == openni::STATUS_OK;
  if (depth_stream_->start() != openni::STATUS_OK || colour_stream_->start() != openni::STATUS_OK) {
    return Status::error(StatusCode::kIoError, "OpenNI2 '%s': cannot start the streams: %s", uri_,
                         last_error());
  }
  for (auto& stream : slots_) stream[0] = stream[1] = Slot();
  last_colour_index_ = -1;
  return Status::ok();
}

Status OpenNi2Source::receive(int stream, const void* data, int bytes, int stride, int width,
                              int height, int64_t stamp_ns, int index) {
  const int bytes_per_pixel = stream == kDepth ? 2 : 3;
  const int row_bytes = width_ * bytes_per_pixel;
  // A frame of exactly width x height pixels is packed, whatever stride it reports (Debian's
  // Dummy driver reports the other stream's once a device was opened twice).
  if (bytes == row_bytes * height_) stride = row_bytes;
  if (width != width_ || height != height_ || stride < row_bytes ||
      bytes < stride * (height_ - 1) + row_bytes) {
    return Status::error(
        StatusCode::kCorrupt, "OpenNI2 '%s': %s frame %dx%d (%d bytes, stride %d), want %dx%d",
        uri_, stream == kDepth ? "depth" : "colour", width, height, bytes, stride, width_, height_);
  }
  const int slot = newest_[stream] ^ 1;  // the older one goes
  const auto* rows = static_cast<const uint8_t*>(data);
  for (int y = 0; y < height_; ++y) {
    const uint8_t* row = rows + static_cast<size_t>(y) * static_cast<size_t>(stride);
    const size_t at = static_cast<size_t>(y) * static_cast<size_t>(width_);
    if (stream == kDepth) {
      std::memcpy(depth_[slot].data() + at, row, static_cast<size_t>(row_bytes));
    } else {
      rgb_to_gray(row, gray_[slot].data() + at, width_);
    }
  }
  slots_[stream][slot] = {stamp_ns, index, true};
  newest_[stream] = slot;
  return Status::ok();
}

Status OpenNi2Source::next(SensorFrame* frame, Status* warning) {
  *warning = Status::ok();
  if (!device_->isValid()) return Status::error(StatusCode::kIoError, "OpenNI2: not open");
  openni::VideoStream* streams[2] = {depth_stream_.get(), colour_stream_.get()};
  const int64_t deadline = monotonic_ns() + static_cast<int64_t>(timeout_ms_) * 1'000'000;
  for (;;) {
    // The newest pending colour frame with a pending depth partner close enough in time.
    for (int c : {newest_[kColour], newest_[kColour] ^ 1}) {
      const Slot& colour = slots_[kColour][c];
      for (int d = 0; d < 2 && colour.pending; ++d) {
        const Slot& depth = slots_[kDepth][d];
        const int64_t dt = depth.stamp_ns - colour.stamp_ns;
        if (!depth.pending || dt > max_pair_dt_ns_ || -dt > max_pair_dt_ns_) continue;
        if (last_colour_index_ >= 0 && colour.index > last_colour_index_ + 1) {
          dropped_ += static_cast<uint32_t>(colour.index - last_colour_index_ - 1);
        }
        last_colour_index_ = colour.index;
        // Delivered, and so is everything older.
        for (Slot& s : slots_[kColour]) s.pending &= s.stamp_ns > colour.stamp_ns;
        for (Slot& s : slots_[kDepth]) s.pending &= s.stamp_ns > depth.stamp_ns;
        arrival_ns_ = monotonic_ns();
        frame->sequence = sequence_++;
        frame->timestamp_ns = colour.stamp_ns;
        frame->depth_timestamp_ns = depth.stamp_ns;
        frame->gray = gray_[c].data();
        frame->depth = depth_[d].data();
        frame->width_px = frame->depth_width_px = width_;
        frame->height_px = frame->depth_height_px = height_;
        return Status::ok();
      }
    }
    const int64_t remaining_ms = (deadline - monotonic_ns()) / 1'000'000;
    if (remaining_ms <= 0) {
      return Status::error(StatusCode::kIoError, "OpenNI2 '%s': no frame pair for %d ms", uri_,
                           timeout_ms_);
    }
    int ready = -1;
    const openni::Status rc =
        openni::OpenNI::waitForAnyStream(streams, 2, &ready, static_cast<int>(remaining_ms));
    if (rc == openni::STATUS_TIME_OUT) continue;
    openni::VideoFrameRef f;
    if (rc != openni::STATUS_OK || ready < 0 || ready > 1 ||
        streams[ready]->readFrame(&f) != openni::STATUS_OK) {
      return Status::error(StatusCode::kIoError, "OpenNI2 '%s': %s", uri_, last_error());
    }
    RGBDTAM_RETURN_IF_ERROR(
        receive(ready, f.getData(), f.getDataSize(), f.getStrideInBytes(), f.getWidth(),
                f.getHeight(), static_cast<int64_t>(f.getTimestamp()) * 1000, f.getFrameIndex()));
  }
}

void OpenNi2Source::close() {
  openni::VideoStream* streams[] = {depth_stream_.get(), colour_stream_.get()};
  bool stopped = false;
  for (openni::VideoStream* s : streams) {
    if (s->isValid()) {
      s->stop();
      stopped = true;
    }
  }
  // Some drivers (Debian's Dummy) do not join their frame threads on stop: they notice within
  // a frame period, and destroying the stream before that crashes them.
  if (stopped) sleep_until_ns(monotonic_ns() + 3 * 1'000'000'000LL / (fps_ > 0 ? fps_ : 30));
  for (openni::VideoStream* s : streams) {
    if (s->isValid()) s->destroy();
  }
  if (device_->isValid()) device_->close();
}

}  // namespace rgbdtam
