#include "rgbdtam/runtime/keyframe_building.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>

namespace rgbdtam {

size_t KeyframeBuildTask::bytes_needed(const Params& p, int map_points) {
  // The builder's scratch (Canny's and each level's edges and gradients) and the two pyramids,
  // per pixel of the camera; measured by test_allocations (it counts what init allocates).
  constexpr size_t kImageBytesPerPixel = 44;
  const size_t pixels = static_cast<size_t>(p.camera.width_px) * p.camera.height_px;
  return pixels * kImageBytesPerPixel + KeyframeBuilder::keyframe_bytes(p.camera, p.tracker) +
         KeyframeAliasFinder::bytes_needed(p.camera, p.tracker) +
         static_cast<size_t>(kLocalMaps) * static_cast<size_t>(map_points) * sizeof(MapPoint) +
         WindowMeasurement::bytes_needed(p);
}

void KeyframeBuildTask::allocate(const Params& p, int map_points, ClockFn clock) {
  clock_ = clock;
  builder_.allocate(p.camera, p.tracker);
  builder_.allocate_keyframe(&keyframe_);
  aliases_.allocate(keyframe_, p.tracker);
  alias_range_m_ = alias_range_m(p);
  frame_.allocate(p.camera, p.sensor.depth_factor, p.sensor.depth_range);
  propagated_.allocate(p.camera, p.sensor.depth_factor, p.sensor.depth_range);
  for (LocalMap& m : local_maps_) m.points.reserve_once(map_points);
  window_.allocate(p, builder_);
}

void KeyframeBuildTask::submit(const KeyframeOrder& order, bool at_once) {
  RGBDTAM_ASSERT(!in_flight_, "a keyframe is ordered while another is in flight");
  in_flight_ = true;
  if (queue_ == nullptr || at_once) {
    step(order);
    return;
  }
  KeyframeOrder* slot = queue_->begin_push();
  RGBDTAM_ASSERT(slot != nullptr, "the keyframe order ring is full with nothing in flight");
  *slot = order;
  queue_->publish();
}

void KeyframeBuildTask::step(const KeyframeOrder& order) {
  const int64_t t0 = clock_ != nullptr ? clock_() : 0;
  frame_.build_gray();
  frame_.build_inverse_depth_levels();
  frame_.set_T_c_d(order.T_c_d);
  frame_.set_row_motion(order.row_motion);
  frame_.set_depth_row_motion(order.depth_row_motion);
  if (order.with_local_maps) fill_sensor_blind_pixels(order.T_w_k);
  builder_.build(frame_, order.id, order.timestamp_ns, order.T_w_k, &keyframe_,
                 order.with_local_maps ? &propagated_ : nullptr);
  aliases_.find(frame_, keyframe_, alias_range_m_, &keyframe_.aliases);
  window_.measure(frame_);
  if (clock_ != nullptr) {
    last_build_ns_ = clock_() - t0;
    per_keyframe_.add(last_build_ns_);
  }
  built_.store(true, std::memory_order_release);
}

void KeyframeBuildTask::hand_over(Keyframe* kf) {
  RGBDTAM_ASSERT(built(), "a keyframe is handed over before it is built");
  kf->take_header_of(keyframe_);
  // Swapped, not copied: the slot's old buffers are the next build's.
  for (int l = 0; l < kPyramidLevels; ++l) {
    kf->photometric_sets[0][l].swap(keyframe_.photometric_sets[0][l]);
    kf->geometric[l].swap(keyframe_.geometric[l]);
  }
}

void KeyframeBuildTask::release() {
  built_.store(false, std::memory_order_relaxed);
  in_flight_ = false;
}

void KeyframeBuildTask::fill_sensor_blind_pixels(const SE3& T_w_c) {
  ImageF& map = propagated_.inverse_depth_level0();
  const ImageF& sensor = frame_.inverse_depth(0);
  std::memcpy(map.data(), sensor.data(), sizeof(float) * static_cast<size_t>(map.size()));
  const Pinhole pinhole = frame_.intrinsics(0).pinhole();
  for (const LocalMap& local : local_maps_) {
    const SE3 T_c_k = T_w_c.inverse() * local.T_w_k;
    for (const MapPoint& p : local.points) {
      const Eigen::Vector3f q = (T_c_k * Vector3d(p.x, p.y, p.z)).cast<float>();
      if (q.z() < 0.05f) continue;
      float u_px, v_px;
      pinhole.project(q.x(), q.y(), q.z(), &u_px, &v_px);
      const long u = std::lround(u_px);
      const long v = std::lround(v_px);
      if (u < 0 || v < 0 || u >= map.width() || v >= map.height()) continue;
      if (sensor.at(u, v) > 0.f) continue;                 // the sensor's own reading wins
      map.at(u, v) = std::max(map.at(u, v), 1.f / q.z());  // nearest wins
    }
  }
  propagated_.build_inverse_depth_levels();
}

}  // namespace rgbdtam
