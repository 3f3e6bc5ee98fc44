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

void DepthInColour::init(const Params& params) {
  on_ = params.depth_camera.register_to_colour;
  if (!on_) return;
  const CameraModel depth = depth_camera(params);
  depth_width_px_ = depth.intrinsics.width_px;
  depth_height_px_ = depth.intrinsics.height_px;
  registration_.init(depth, CameraModel{params.camera, params.distortion},
                     params.depth_camera.T_c_d, params.sensor.depth_factor);
  registered_.allocate(params.camera.width_px, params.camera.height_px);
}

const SensorFrame& DepthInColour::apply(const SensorFrame& frame) {
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
  out->depth_width_px = registered_.width();
  out->depth_height_px = registered_.height();
}

size_t DepthInColour::bytes_needed(const Params& params) {
  if (!params.depth_camera.register_to_colour) return 0;
  const SensorImageSize size = sensor_image_size(params);
  return DepthRegistration::bytes_needed(size.depth_width_px, size.depth_height_px) +
         static_cast<size_t>(params.camera.width_px) * params.camera.height_px * sizeof(uint16_t);
}

}  // namespace rgbdtam
