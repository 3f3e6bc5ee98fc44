#include "rgbdtam/runtime/tracking/window_measurement.hpp"

#include "rgbdtam/core/pose_graph.hpp"

namespace rgbdtam {

size_t WindowMeasurement::bytes_needed(const Params& p) {
  if (!p.loop.enabled || !p.loop.window) return 0;
  return KeyframeBuilder::keyframe_bytes(p.camera, p.tracker) +
         Tracker::scratch_bytes(p.camera, p.tracker);
}

void WindowMeasurement::allocate(const Params& p, const KeyframeBuilder& builder) {
  if (!p.loop.enabled || !p.loop.window) return;
  builder.allocate_keyframe(&reference_);
  search_.allocate(reference_, p.tracker, p.health, alias_range_m(p));
  covariance_scale_ = p.covariance_scale;
  allocated_ = true;
}

void WindowMeasurement::order(const WindowRequest& request) {
  request_ = request;
  link_ = KeyframeLink();
  if (request.reference == nullptr) return;
  RGBDTAM_ASSERT(allocated_, "a window measurement is ordered with loop.window off");
  const Keyframe& from = *request.reference;
  reference_.id = from.id;
  reference_.timestamp_ns = from.timestamp_ns;
  reference_.T_w_k = from.T_w_k;
  reference_.aliases = from.aliases;
  reference_.active_photometric = 0;
  for (int l = 0; l < kPyramidLevels; ++l) {
    reference_.photometric_sets[0][l].copy_from(from.photometric(l));
    reference_.geometric[l].copy_from(from.geometric[l]);
  }
  request_.reference = &reference_;
}

void WindowMeasurement::measure(const FramePyramid& frame) {
  if (!ordered()) return;
  search_.use_scales(request_.typical);
  const Attempt a =
      search_.track(&reference_, frame, request_.T_w_c, request_.motion, request_.t_ns);
  if (a.failed != 0) return;
  link_.reference_id = reference_.id;
  link_.kind = EdgeKind::kCovisible;
  link_.T_reference_keyframe = a.r.T_k_c;
  link_.information = graph_information(a.r.information / covariance_scale_, a.r.T_k_c);
}

}  // namespace rgbdtam
