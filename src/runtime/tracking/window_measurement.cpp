#include "rgbdtam/runtime/tracking/window_measurement.hpp"

#include "rgbdtam/core/pose_graph.hpp"

namespace rgbdtam {

size_t WindowMeasurement::bytes_needed(const Params& p) {
  if (!p.loop.enabled || !p.loop.window) return 0;
  return static_cast<size_t>(p.loop.window_keyframes) *
             KeyframeBuilder::keyframe_bytes(p.camera, p.tracker) +
         Tracker::scratch_bytes(p.camera, p.tracker);
}

void WindowMeasurement::allocate(const Params& p, const KeyframeBuilder& builder) {
  if (!p.loop.enabled || !p.loop.window) return;
  capacity_ = p.loop.window_keyframes;
  RGBDTAM_ASSERT(capacity_ >= 1 && capacity_ <= kMaxWindowEdges,
                 "loop.window_keyframes outside 1..kMaxWindowEdges");
  for (int i = 0; i < capacity_; ++i) builder.allocate_keyframe(&references_[i]);
  search_.allocate(references_[0], p.tracker, p.health, alias_range_m(p));
  covariance_scale_ = p.covariance_scale;
}

void WindowMeasurement::order(const WindowRequest& request) {
  RGBDTAM_ASSERT(request.count <= capacity_, "more window keyframes ordered than allocated");
  request_ = request;
  links_ = WindowLinks();
  for (int i = 0; i < request.count; ++i) {
    const Keyframe& from = *request.references[i];
    Keyframe& copy = references_[i];
    copy.take_header_of(from);
    for (int l = 0; l < kPyramidLevels; ++l) {
      copy.photometric_sets[0][l].copy_from(from.photometric(l));
      copy.geometric[l].copy_from(from.geometric[l]);
    }
  }
}

void WindowMeasurement::measure(const FramePyramid& frame) {
  search_.use_scales(request_.typical);
  for (int i = 0; i < request_.count; ++i) {
    Keyframe* copy = &references_[i];
    const Attempt a = search_.track(copy, frame, request_.T_w_c, request_.motion, request_.t_ns);
    if (a.failed != 0) continue;
    KeyframeLink link;
    link.reference_id = copy->id;
    link.kind = EdgeKind::kCovisible;
    link.T_reference_keyframe = a.r.T_k_c;
    link.information = graph_information(a.r.information / covariance_scale_, a.r.T_k_c);
    links_.add(link);
  }
}

}  // namespace rgbdtam
