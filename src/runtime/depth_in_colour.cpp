#include "rgbdtam/runtime/depth_in_colour.hpp"

namespace rgbdtam {
namespace {
CameraModel depth_camera(const Params& params) {
  const SensorImageSize size = sensor_image_size(params);
  CameraModel depth;
  depth.intrinsics = params.depth_camera.intrinsics;
  depth.intrinsics.width_px = size.depth_width_px;
  depth.intrinsics.height_px = size.depth_height_px;
  depth.distortion = params.depth_camera.distortion;
  return depth;
}
}  // namespace

void DepthInColour::init(const Params& params, Buffer buffer) {
  on_ = params.depth_camera.register_to_colour;
  if (!on_) return;
  const CameraModel depth = depth_camera(params);
  depth_width_px_ = depth.intrinsics.width_px;
  depth_height_px_ = depth.intrinsics.height_px;
  registration_.init(depth, CameraModel{params.camera, params.distortion},
                     params.depth_camera.T_c_d, params.sensor.depth_factor);
  colour_width_px_ = params.camera.width_px;
  colour_height_px_ = params.camera.height_px;
  if (buffer == Buffer::kOwn) registered_.allocate(colour_width_px_, colour_height_px_);
}

const SensorFrame& DepthInColour::apply(const SensorFrame& frame) {
  RGBDTAM_ASSERT(!on_ || registered_.data() != nullptr,
                 "apply() needs the buffer of its own that init(Buffer::kCallers) leaves out");
  apply_into(frame, registered_.data(), &frame_);
  return frame_;
}

void DepthInColour::apply_into(const SensorFrame& frame, uint16_t* depth, SensorFrame* out) {
  *out = frame;
  if (!on_) return;
  RGBDTAM_ASSERT(
      frame.depth_width_px == depth_width_px_ && frame.depth_height_px == depth_height_px_,
      "sensor depth size differs from the configured depth camera");
  if (frame.depth != nullptr) {
    registration_.apply(frame.depth, depth);
    out->depth = depth;
  }
  out->depth_width_px = colour_width_px_;
  out->depth_height_px = colour_height_px_;
}

size_t DepthInColour::bytes_needed(const Params& params, Buffer buffer) {
  if (!params.depth_camera.register_to_colour) return 0;
  const SensorImageSize size = sensor_image_size(params);
  const size_t own = buffer == Buffer::kOwn ? static_cast<size_t>(params.camera.width_px) *
                                                  params.camera.height_px * sizeof(uint16_t)
                                            : 0;
  return DepthRegistration::bytes_needed(size.depth_width_px, size.depth_height_px) + own;
}

}  // namespace rgbdtam
