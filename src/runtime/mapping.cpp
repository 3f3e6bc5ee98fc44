#include "rgbdtam/runtime/mapping.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>

namespace rgbdtam {
namespace {
void copy_image(const ImageF& from, ImageF* to) {
  std::memcpy(to->data(), from.data(), sizeof(float) * static_cast<size_t>(from.size()));
}

// Median and nearest depth of the valid sensor pixels, from a sparse sample.
float median_depth_m(const ImageF& inverse_depth, float* nearest_m) {
  constexpr int kStride = 37;  // a prime, so the sample does not alias with image rows
  constexpr int kMaxSamples = 8192;
  float samples[kMaxSamples];
  int n = 0;
  for (int i = 0; i < inverse_depth.size() && n < kMaxSamples; i += kStride) {
    const float rho = inverse_depth.data()[i];
    if (rho > 0.f) samples[n++] = 1.f / rho;
  }
  *nearest_m = n > 0 ? *std::min_element(samples, samples + n) : 0.f;
  if (n == 0) return 1.f;
  std::nth_element(samples, samples + n / 2, samples + n);
  return samples[n / 2];
}
}  // namespace

void MapperQueue::allocate(int slots, int width, int height) {
  SpscRing<MapperFrame>::allocate(slots);
  for (int i = 0; i < slots; ++i) {
    slot(i).gray.allocate(width, height);
    slot(i).inverse_depth.allocate(width, height);
    slot(i).edges.allocate(width, height);
  }
}

Status MappingModule::init(const Params& params, const PinholeIntrinsics& k, ClockFn clock,
                           MapSink* sink, KeyframePool* keyframes) {
  params_ = params;
  keyframes_ = keyframes;
  clock_ = clock;
  sink_ = sink;
  mv_.max_seeds = params.map_seeds;
  mv_.max_inverse_depth = static_cast<float>(1.0 / (0.5 * params.sensor.depth_range.min_m));
  for (Job& job : jobs_) {
    job.seeds.allocate(k, mv_);
    job.gray.allocate(k.width_px, k.height_px);
    job.sensor_inverse_depth.allocate(k.width_px, k.height_px);
    job.edges.allocate(k.width_px, k.height_px);
  }
  for (EarlierFrame& e : earlier_) e.gray.allocate(k.width_px, k.height_px);
  builder_.allocate(k, params.tracker);
  fused_.allocate(k, params.sensor.depth_factor, params.sensor.depth_range);
  pixels_.reserve_once(mv_.max_seeds);
  return Status::ok();
}

void MappingModule::start(Job* job, const MapperFrame& frame) {
  job->handle = frame.new_keyframe;
  job->keyframe = keyframes_->get(frame.new_keyframe);  // pinned: it stays until unpinned
  RGBDTAM_ASSERT(job->keyframe != nullptr, "the tracker recycled a pinned keyframe");
  copy_image(frame.gray, &job->gray);
  copy_image(frame.inverse_depth, &job->sensor_inverse_depth);
  std::memcpy(job->edges.data(), frame.edges.data(), static_cast<size_t>(frame.edges.size()));
  float nearest_m = 0.f;
  job->median_depth_m = median_depth_m(job->sensor_inverse_depth, &nearest_m);
  const float max_rho =
      nearest_m > 0.f ? std::min(mv_.max_inverse_depth, 2.f / nearest_m) : mv_.max_inverse_depth;
  job->seeds.reset(job->gray, job->sensor_inverse_depth, job->edges, frame.T_w_c, max_rho);
  job->T_w_last_used = frame.T_w_c;
  job->frames_used = 0;
  job->started = ++arrivals_;
  job->spent_ns = 0;
  scene_depth_m_ = job->median_depth_m;
  // Newest first: the shortest baselines narrow each seed's interval before the longer ones.
  for (int i = 1; i <= earlier_count_; ++i) {
    const EarlierFrame& e = earlier_[(earlier_next_ + kEarlierFrames - i) % kEarlierFrames];
    if (spacing_m(e.T_w_c, frame.T_w_c) >= params_.map_min_baseline_ratio * job->median_depth_m) {
      observe(job, e.gray, e.T_w_c);
    }
  }
}

double MappingModule::spacing_m(const SE3& a, const SE3& b) const {
  return (a.translation() - b.translation()).norm();
}

void MappingModule::observe(Job* job, const ImageF& gray, const SE3& T_w_c) {
  job->seeds.observe(gray, T_w_c);
  ++job->frames_used;
  ++counters_.frames_observed;
}

void MappingModule::remember(const MapperFrame& frame) {
  if (earlier_count_ > 0) {
    const EarlierFrame& newest = earlier_[(earlier_next_ + kEarlierFrames - 1) % kEarlierFrames];
    if (spacing_m(newest.T_w_c, frame.T_w_c) < params_.map_min_baseline_ratio * scene_depth_m_) {
      return;
    }
  }
  EarlierFrame& e = earlier_[earlier_next_];
  copy_image(frame.gray, &e.gray);
  e.T_w_c = frame.T_w_c;
  earlier_next_ = (earlier_next_ + 1) % kEarlierFrames;
  earlier_count_ = std::min(earlier_count_ + 1, kEarlierFrames);
}

void MappingModule::step(const MapperFrame& frame) {
  if (!frame.map_frame.same_as(map_frame_)) {
    // The poses moved (a restart, a relocalisation, a loop correction): what is open was
    // measured in the old frame, so it is finished with the frames it has. Moved with a
    // correction instead, the open keyframes went on with frames from either side of it, and
    // fr3_teddy_200's dithered copies tracked at 0.92 cm instead of 0.67
    // (docs/tracking-and-mapping.md, "Mapping").
    map_frame_ = frame.map_frame;
    earlier_count_ = 0;
    for (Job& job : jobs_) {
      if (job.keyframe != nullptr) finalize(&job);
    }
  }
  if (frame.new_keyframe.slot >= 0) {
    // A free slot, or else the oldest open keyframe is finished first.
    Job* slot = nullptr;
    for (Job& job : jobs_) {
      if (job.keyframe == nullptr) {
        slot = &job;
        break;
      }
      if (slot == nullptr || job.started < slot->started) slot = &job;
    }
    if (slot->keyframe != nullptr) finalize(slot);
    const int64_t t0 = clock_();
    start(slot, frame);
    slot->spent_ns += clock_() - t0;
    return;
  }
  if (late()) {
    ++counters_.frames_skipped_late;
    remember(frame);
    return;
  }
  for (Job& job : jobs_) {
    if (job.keyframe == nullptr) continue;
    // A frame is used once it has moved far enough, relative to the scene, from the last one.
    if (spacing_m(frame.T_w_c, job.T_w_last_used) <
        params_.map_min_baseline_ratio * job.median_depth_m) {
      continue;
    }
    const int64_t t0 = clock_();
    observe(&job, frame.gray, frame.T_w_c);
    job.T_w_last_used = frame.T_w_c;
    job.spent_ns += clock_() - t0;
    if (job.frames_used >= params_.map_frames_per_keyframe) finalize(&job);
  }
  remember(frame);
}

bool MappingModule::late() const {
  if (queue_ == nullptr) return false;
  const int waiting = queue_->size() - 1;  // behind the frame in hand
  return waiting > 0 && waiting >= queue_->capacity() / 2;
}

void MappingModule::finish() {
  // Oldest first, as they arrived.
  for (;;) {
    Job* oldest = nullptr;
    for (Job& job : jobs_) {
      if (job.keyframe != nullptr && (oldest == nullptr || job.started < oldest->started)) {
        oldest = &job;
      }
    }
    if (oldest == nullptr) return;
    finalize(oldest);
  }
}

void MappingModule::finalize(Job* job) {
  const int64_t t0 = clock_();
  const float sigma_sensor = static_cast<float>(params_.sensor.inverse_depth_sigma());
  job->seeds.fuse(sigma_sensor, &pixels_);
  // The tracker's map: the sensor's inverse depth, with every edge pixel's fused estimate that
  // is certain enough for tracking.
  auto tracked = [this](const FusedPixel& p) {
    return p.source != DepthSource::kMultiView || mv_.usable_for_tracking(p.rho, p.sigma);
  };
  copy_image(job->gray, &fused_.gray(0));
  fused_.build_gray();
  ImageF& map = fused_.inverse_depth_level0();
  copy_image(job->sensor_inverse_depth, &map);
  for (const FusedPixel& p : pixels_) {
    if (tracked(p)) map.at(p.x, p.y) = p.rho;
    switch (p.source) {
      case DepthSource::kSensor:
        ++counters_.points_sensor;
        break;
      case DepthSource::kMultiView:
        ++counters_.points_multiview;
        break;
      case DepthSource::kFused:
        ++counters_.points_fused;
        counters_.fused_multiview_share_sum +=
            1.0 - (p.sigma * p.sigma) / (sigma_sensor * sigma_sensor);
        break;
      case DepthSource::kNone:
        break;
    }
  }
  fused_.build_inverse_depth_levels();
  Keyframe* kf = job->keyframe;
  fused_.set_row_motion(kf->row_motion);
  builder_.build_photometric(fused_, job->edges, kf->inactive_photometric());
  kf->map_points.clear();
  const Pinhole pinhole = fused_.intrinsics(0).pinhole();
  for (const FusedPixel& p : pixels_) {
    if (!tracked(p)) continue;
    MapPoint m;
    m.z = 1.f / p.rho;
    pinhole.back_project(p.x, p.y, m.z, &m.x, &m.y);
    (void)kf->map_points.push_back(m);
  }
  keyframes_->publish_map(job->handle);
  keyframes_->unpin(job->handle);
  if (sink_ != nullptr) {
    sink_->on_keyframe_map(kf->timestamp_ns, job->seeds.T_w_k(), fused_.intrinsics(0), pixels_);
  }
  ++counters_.keyframes_mapped;
  per_keyframe_.add(job->spent_ns + clock_() - t0);
  job->keyframe = nullptr;
}

}  // namespace rgbdtam
