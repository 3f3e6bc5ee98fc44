#include "rgbdtam/runtime/depth_in_colour.hpp"

namespace rgbdtam {
namespace {
CameraModel depth_camera(const Params& params) {
  CameraModel depth;
  depth.intrinsics = params.depth_camera.intrinsics;
  depth.intrinsics.width_px = params.camera.width_px;  // the sensors deliver it at that size
  depth.intrinsics.height_px = params.camera.height_px;
  depth.distortion = params.depth_camera.distortion;
  return depth;
}
}  // namespace

void DepthInColour::init(const Params& params) {
  on_ = params.depth_camera.register_to_colour;
  if (!on_) return;
  registration_.init(depth_camera(params), CameraModel{params.camera, params.distortion},
                     params.depth_camera.T_c_d, params.sensor.depth_factor);
  registered_.allocate(params.camera.width_px, params.camera.height_px);
}

const SensorFrame& DepthInColour::apply(const SensorFrame& frame) {
  frame_ = frame;
  if (on_ && frame.depth != nullptr) {
    registration_.apply(frame.depth, registered_.data());
    frame_.depth = registered_.data();
  }
  return frame_;
}

size_t DepthInColour::bytes_needed(const Params& params) {
  if (!params.depth_camera.register_to_colour) return 0;
  return DepthRegistration::bytes_needed(params.camera.width_px, params.camera.height_px) +
         static_cast<size_t>(params.camera.width_px) * params.camera.height_px * sizeof(uint16_t);
}

}  // namespace rgbdtam
