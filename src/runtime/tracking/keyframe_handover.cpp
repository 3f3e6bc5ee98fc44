#include "rgbdtam/runtime/tracking/keyframe_handover.hpp"

#include <algorithm>
#include <cstring>

#include "rgbdtam/core/pose_graph.hpp"

namespace rgbdtam {

void KeyframeHandover::init(const Params& params, KeyframePool* pool, KeyframeBuildTask* building,
                            ClockFn clock) {
  pool_ = pool;
  building_ = building;
  builder_.allocate(params.camera, params.tracker);
  Keyframe model;
  builder_.allocate_keyframe(&model);
  aliases_.allocate(model, params.tracker);
  alias_range_m_ = alias_range_m(params);
  const int map_points = params.map_enabled ? params.map_seeds : 0;
  pool_->allocate(params.keyframe_pool_size, builder_, map_points);
  building_->allocate(params, map_points, clock);
  for (LocalMap& m : local_maps_) m.points.reserve_once(map_points);
}

void KeyframeHandover::track_against(Keyframe* kf) {
  reference_ = kf;
  fallback_ = nullptr;
}

void KeyframeHandover::take_up(Keyframe* kf) {
  left_ = pool_->handle(reference_);
  taken_up_ = kf;
  reference_ = kf;
  ++counters_.reused;
}

Keyframe* KeyframeHandover::left() const {
  if (taken_up_ == nullptr || reference_ != taken_up_) return nullptr;
  Keyframe* kf = pool_->get(left_);
  return kf != nullptr && kf->id >= oldest_in_frame_id_ ? kf : nullptr;
}

Keyframe* KeyframeHandover::from_last_valid_frame(const FrameBuffers& frames, const SE3& T_w_last,
                                                  int64_t last_ns) {
  if (fallback_ != nullptr) return fallback_;
  const FramePyramid* last = frames.last_valid();
  if (last == nullptr || reference_->timestamp_ns == last_ns) return nullptr;
  if (!last->has_depth()) return nullptr;
  fallback_ = pool_->acquire(reference_);
  // Sensor depth only: the mapper never saw this frame's images as a keyframe's.
  builder_.build(*last, next_keyframe_id_++, last_ns, T_w_last, fallback_);
  aliases_.find(*last, *fallback_, alias_range_m_, &fallback_->aliases);
  ++counters_.keyframes;
  return fallback_;
}

KeyframeLink KeyframeHandover::odometry_link(const SE3& T_w_c,
                                             const Matrix6d& tracker_information) const {
  KeyframeLink link;
  link.reference_id = reference_->id;
  link.kind = EdgeKind::kOdometry;
  link.T_reference_keyframe = reference_->T_w_k.inverse() * T_w_c;
  link.information = graph_information(tracker_information, link.T_reference_keyframe);
  return link;
}

KeyframeLink KeyframeHandover::restart_link() const {
  KeyframeLink link;
  link.reference_id = reference_ != nullptr ? reference_->id : next_keyframe_id_;
  return link;
}

bool KeyframeHandover::ask(const SE3& T_w_k, const KeyframeLink& link, bool to_mapper,
                           int frame_slot, PoseEstimate* out, const KeyframeLink& window,
                           const WindowRequest& window_later) {
  if (building()) return false;
  building_->window().order(window_later);
  // Ordered after the pose is out (order_pending), from this frame's buffer, which the next
  // frame leaves alone until then.
  out->flags |= kNewKeyframe;
  out->keyframe_id = next_keyframe_id_;
  pending_.due = true;
  pending_.frame_buffer = frame_slot;
  pending_.T_w_k = T_w_k;
  pending_.link = link;
  pending_.window = window;
  pending_.to_mapper = to_mapper;
  return true;
}

void KeyframeHandover::order_pending(const FrameBuffers& frames, const MapFrame& map) {
  if (!pending_.due) return;
  pending_.due = false;
  const FramePyramid& f = frames.slot(pending_.frame_buffer);
  const size_t pixels = static_cast<size_t>(f.gray(0).size());
  std::memcpy(building_->gray_level0().data(), f.gray(0).data(), sizeof(float) * pixels);
  std::memcpy(building_->inverse_depth_level0().data(), f.inverse_depth(0).data(),
              sizeof(float) * pixels);
  // With mapping, the new keyframe starts with the local maps where its sensor is blind, until
  // its own multi-view map replaces them.
  const bool with_local_maps = mapping();
  for (int i = 0; with_local_maps && i < KeyframeBuildTask::kLocalMaps; ++i) {
    LocalMap& m = building_->local_map(i);
    m.T_w_k = local_maps_[i].T_w_k;
    m.points.clear();
    for (const MapPoint& p : local_maps_[i].points) (void)m.points.push_back(p);
  }
  pending_.map = map;
  KeyframeOrder order;
  order.id = next_keyframe_id_++;
  order.timestamp_ns = pending_.pose.timestamp_ns;
  order.T_w_k = pending_.T_w_k;
  order.T_c_d = f.T_c_d();
  order.row_motion = f.fixed_row_motions().colour;
  order.depth_row_motion = f.fixed_row_motions().depth;
  order.with_local_maps = with_local_maps;
  // With nothing to track against yet (the first keyframe, or the first in a loaded map), the
  // tracker has nothing else to do: it is built at once.
  building_->submit(order, reference_ == nullptr);
}

Keyframe* KeyframeHandover::adopt_built(const MapFrame& map) {
  if (!building_->built()) return nullptr;
  SE3 T_now_then;
  if (!map.moved_from(pending_.map, &T_now_then)) {
    // Its pose is from before the camera's world jumped (a restart or relocalisation).
    ++counters_.keyframes_stale;
    building_->release();
    return nullptr;
  }
  Keyframe* kf = pool_->acquire(reference_);
  building_->hand_over(kf);
  // A loop correction meanwhile moved the world its pose was measured in, and its reference.
  kf->T_w_k = T_now_then * kf->T_w_k;
  pending_.pose.T_w_c = T_now_then * pending_.pose.T_w_c;
  pending_.map = map;
  reference_ = kf;
  fallback_ = nullptr;
  ++counters_.keyframes;
  return kf;
}

WindowLinks KeyframeHandover::adopted_window_links() const {
  WindowLinks links;
  if (pending_.window.kind != EdgeKind::kRestart) links.add(pending_.window);
  const WindowLinks& built = building_->window().links();
  for (int i = 0; i < built.count; ++i) links.add(built.link[i]);
  return links;
}

void KeyframeHandover::release_adopted() {
  if (pending_.to_mapper) {
    offer_to_mapper(pending_.pose, pending_.map, building_->frame(), &building_->edges());
  }
  building_->release();
}

void KeyframeHandover::adopt_map(Keyframe* kf) {
  if (!pool_->adopt_map(kf)) return;
  LocalMap& m = local_maps_[next_local_map_];
  next_local_map_ = (next_local_map_ + 1) % 2;
  m.T_w_k = kf->T_w_k;
  m.points.clear();
  for (const MapPoint& p : kf->map_points) (void)m.points.push_back(p);
}

void KeyframeHandover::adopt_all_maps() {
  for (int i = 0; i < pool_->size(); ++i) adopt_map(&pool_->at(i));
}

void KeyframeHandover::offer_to_mapper(const PoseEstimate& pose, const MapFrame& map,
                                       const FramePyramid& f, const ImageU8* keyframe_edges) {
  if (mapper_queue_ == nullptr) return;
  const bool new_keyframe = keyframe_edges != nullptr;
  MapperFrame* slot = mapper_queue_->begin_push();
  if (slot == nullptr) {
    ++counters_.mapper_dropped_frames;
    if (new_keyframe) ++counters_.mapper_dropped_keyframes;
    return;
  }
  slot->sequence = pose.sequence;
  slot->map_frame = map;
  slot->timestamp_ns = pose.timestamp_ns;
  slot->T_w_c = pose.T_w_c;
  std::memcpy(slot->gray.data(), f.gray(0).data(), sizeof(float) * slot->gray.size());
  slot->new_keyframe = KeyframeHandle();
  if (new_keyframe) {
    std::memcpy(slot->inverse_depth.data(), f.inverse_depth(0).data(),
                sizeof(float) * slot->inverse_depth.size());
    std::memcpy(slot->edges.data(), keyframe_edges->data(), slot->edges.size());
    slot->new_keyframe = pool_->handle(reference_);
    pool_->pin(slot->new_keyframe);
  }
  mapper_queue_->publish();
}

bool KeyframeHandover::move_by(const LoopCorrection& c, SE3* camera_delta) {
  if (c.poses.empty()) return false;
  auto corrected = [&](uint32_t id) -> const KeyframePose* {
    const KeyframePose* p =
        std::lower_bound(c.poses.begin(), c.poses.end(), id,
                         [](const KeyframePose& k, uint32_t key) { return k.keyframe_id < key; });
    return p != c.poses.end() && p->keyframe_id == id ? p : nullptr;
  };
  // Each remembered keyframe moves to its corrected pose; a keyframe newer than the correction
  // moves with the newest one the correction knows.
  SE3 newest_delta;
  uint32_t newest_id = 0;
  bool have_newest = false;
  SE3 reference_delta;
  bool have_reference = false;
  for (int i = 0; i < pool_->size(); ++i) {
    Keyframe& kf = pool_->at(i);
    const KeyframePose* p = corrected(kf.id);
    if (p == nullptr) continue;
    const SE3 delta = p->T_w_k * kf.T_w_k.inverse();
    if (!have_newest || kf.id > newest_id)
      newest_delta = delta, newest_id = kf.id, have_newest = true;
    if (&kf == reference_) reference_delta = delta, have_reference = true;
    kf.T_w_k = p->T_w_k;
  }
  if (!have_newest) return false;
  const uint32_t last_known = c.poses[c.poses.size() - 1].keyframe_id;
  for (int i = 0; i < pool_->size(); ++i) {
    Keyframe& kf = pool_->at(i);
    if (kf.id > last_known) kf.T_w_k = newest_delta * kf.T_w_k;
    if (&kf == reference_ && kf.id > last_known)
      reference_delta = newest_delta, have_reference = true;
  }
  for (LocalMap& m : local_maps_) m.T_w_k = newest_delta * m.T_w_k;
  *camera_delta = have_reference ? reference_delta : newest_delta;
  return true;
}

Keyframe* KeyframeHandover::find(uint32_t id) {
  for (int i = 0; i < pool_->size(); ++i) {
    if (pool_->at(i).id == id) return &pool_->at(i);
  }
  return nullptr;
}

bool KeyframeHandover::pose_of(uint32_t id, SE3* T_w_k) const {
  for (int i = 0; i < pool_->size(); ++i) {
    if (pool_->at(i).id == id) {
      *T_w_k = pool_->at(i).T_w_k;
      return true;
    }
  }
  return false;
}

int KeyframeHandover::nearest(const SE3& T_w_c, int wanted, Keyframe** out) {
  auto distance = [&](const Keyframe& kf) {
    return ranking_distance_m(kf.T_w_k.inverse() * T_w_c);
  };
  int count = 0;
  while (count < wanted) {
    Keyframe* nearest = nullptr;
    double nearest_distance = 0.0;
    for (int i = 0; i < pool_->size(); ++i) {
      Keyframe* kf = &pool_->at(i);
      if (kf == reference_ || kf->id < oldest_in_frame_id_ ||
          std::find(out, out + count, kf) != out + count) {
        continue;
      }
      const double d = distance(*kf);
      if (nearest == nullptr || d < nearest_distance) {
        nearest = kf;
        nearest_distance = d;
      }
    }
    if (nearest == nullptr) break;
    out[count++] = nearest;
  }
  return count;
}

}  // namespace rgbdtam
