#include "frontend_frames.hpp"

namespace rgbdtam {

Status FrontendFrames::open(const char* sequence, const Params& p) {
  RGBDTAM_RETURN_IF_ERROR(source_.open(sequence, sensor_image_size(p), p.sensor.max_rgb_depth_dt_ns,
                                       p.sensor.depth_time_offset_ns));
  depth_in_colour_.init(p);
  undistorter_.init(p.camera, p.distortion);
  frame_.allocate(p.camera, p.sensor.depth_factor, p.sensor.depth_range);
  return Status::ok();
}

bool FrontendFrames::load(int i) {
  if (i < source_.position()) return false;  // the source only goes forwards
  source_.skip_to(i);
  SensorFrame raw;
  Status warning;
  if (!source_.next(&raw, &warning).is_ok() || raw.depth == nullptr) return false;
  const SensorFrame& f = depth_in_colour_.apply(raw);
  undistorter_.undistort_gray(f.gray, &frame_.gray(0));
  frame_.build_gray();
  frame_.build_inverse_depth(f.depth, undistorter_);
  return true;
}

}  // namespace rgbdtam
