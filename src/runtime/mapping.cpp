#include "rgbdtam/runtime/mapping.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>

namespace rgbdtam {
namespace {
void copy_image(const ImageF& from, ImageF* to) {
  std::memcpy(to->data(), from.data(), sizeof(float) * static_cast<size_t>(from.size()));
}

// Median depth of the valid sensor pixels, from a sparse sample.
float median_depth_m(const ImageF& inverse_depth) {
  constexpr int kStride = 37;  // a prime, so the sample does not alias with image rows
  constexpr int kMaxSamples = 8192;
  float samples[kMaxSamples];
  int n = 0;
  for (int i = 0; i < inverse_depth.size() && n < kMaxSamples; i += kStride) {
    const float rho = inverse_depth.data()[i];
    if (rho > 0.f) samples[n++] = 1.f / rho;
  }
  if (n == 0) return 1.f;
  std::nth_element(samples, samples + n / 2, samples + n);
  return samples[n / 2];
}
}  // namespace

void MapperQueue::allocate(int slots, int width, int height) {
  capacity_ = slots;
  slots_.reset(new MapperFrame[static_cast<size_t>(slots)]);
  for (int i = 0; i < slots; ++i) {
    slots_[i].gray.allocate(width, height);
    slots_[i].inverse_depth.allocate(width, height);
    slots_[i].edges.allocate(width, height);
  }
}

MapperFrame* MapperQueue::begin_push() {
  const uint32_t tail = tail_.load(std::memory_order_relaxed);
  if (tail - head_.load(std::memory_order_acquire) >= static_cast<uint32_t>(capacity_)) {
    return nullptr;
  }
  return &slots_[tail % static_cast<uint32_t>(capacity_)];
}

void MapperQueue::publish() {
  tail_.store(tail_.load(std::memory_order_relaxed) + 1, std::memory_order_release);
}

MapperFrame* MapperQueue::front() {
  const uint32_t head = head_.load(std::memory_order_relaxed);
  if (head == tail_.load(std::memory_order_acquire)) return nullptr;
  return &slots_[head % static_cast<uint32_t>(capacity_)];
}

void MapperQueue::pop() {
  head_.store(head_.load(std::memory_order_relaxed) + 1, std::memory_order_release);
}

Status MappingModule::init(const Params& params, const PinholeIntrinsics& k, ClockFn clock,
                           MapSink* sink) {
  params_ = params;
  clock_ = clock;
  sink_ = sink;
  mv_.max_seeds = params.map_seeds;
  mv_.max_inverse_depth = static_cast<float>(1.0 / (0.5 * params.sensor.depth_range.min_m));
  seeds_.allocate(k, mv_);
  builder_.allocate(k, params.tracker);
  fused_.allocate(k, params.sensor.depth_factor, params.sensor.depth_range);
  sensor_inverse_depth_.allocate(k.width_px, k.height_px);
  pixels_.reserve_once(mv_.max_seeds);
  return Status::ok();
}

void MappingModule::step(const MapperFrame& frame) {
  const int64_t t0 = clock_();
  if (frame.new_keyframe != nullptr) {
    if (keyframe_ != nullptr) finalize();
    keyframe_ = frame.new_keyframe;
    copy_image(frame.gray, &fused_.gray(0));
    fused_.build_gray();
    copy_image(frame.inverse_depth, &sensor_inverse_depth_);
    seeds_.reset(fused_.gray(0), sensor_inverse_depth_, frame.edges, frame.T_w_c);
    median_depth_m_ = median_depth_m(sensor_inverse_depth_);
    T_w_last_used_ = frame.T_w_c;
    frames_used_ = 0;
    spent_ns_ = 0;
  } else if (keyframe_ != nullptr) {
    // A frame is used once it has moved far enough, relative to the scene, from the last one.
    const double baseline = (frame.T_w_c.translation() - T_w_last_used_.translation()).norm();
    if (baseline >= params_.map_min_baseline_ratio * median_depth_m_) {
      seeds_.observe(frame.gray, frame.T_w_c);
      T_w_last_used_ = frame.T_w_c;
      ++frames_used_;
      ++counters_.frames_observed;
    }
  }
  spent_ns_ += clock_() - t0;
  if (keyframe_ != nullptr && frames_used_ >= params_.map_frames_per_keyframe) finalize();
}

void MappingModule::finish() {
  if (keyframe_ != nullptr) finalize();
}

void MappingModule::finalize() {
  const int64_t t0 = clock_();
  const float sigma_sensor = static_cast<float>(params_.sensor.inverse_depth_sigma());
  seeds_.fuse(sigma_sensor, &pixels_);
  // The keyframe's map: the sensor's inverse depth, with every edge pixel's fused estimate.
  ImageF& map = fused_.inverse_depth_level0();
  copy_image(sensor_inverse_depth_, &map);
  for (const FusedPixel& p : pixels_) {
    map.at(p.x, p.y) = p.rho;
    switch (p.source) {
      case DepthSource::kSensor: ++counters_.points_sensor; break;
      case DepthSource::kMultiView: ++counters_.points_multiview; break;
      case DepthSource::kFused: ++counters_.points_fused; break;
      case DepthSource::kNone: break;
    }
  }
  fused_.build_inverse_depth_levels();
  builder_.build_photometric(fused_, keyframe_->inactive_photometric());
  keyframe_->map_ready.store(true, std::memory_order_release);
  keyframe_->being_mapped.store(false, std::memory_order_release);
  if (sink_ != nullptr) sink_->on_keyframe_map(seeds_.T_w_k(), fused_.intrinsics(0), pixels_);
  ++counters_.keyframes_mapped;
  per_keyframe_.add(spent_ns_ + clock_() - t0);
  keyframe_ = nullptr;
}

MappingThread::~MappingThread() {
  if (thread_.joinable()) stop();
}

void MappingThread::start(MapperQueue* queue, MappingModule* mapper) {
  queue_ = queue;
  mapper_ = mapper;
  stopping_ = false;
  thread_ = std::thread([this] { run(); });
}

void MappingThread::notify() { wake_.notify_one(); }

void MappingThread::stop() {
  stopping_.store(true, std::memory_order_release);
  wake_.notify_one();
  thread_.join();
}

void MappingThread::run() {
  for (;;) {
    if (MapperFrame* f = queue_->front()) {
      mapper_->step(*f);
      queue_->pop();
      continue;
    }
    if (stopping_.load(std::memory_order_acquire)) break;
    std::unique_lock<std::mutex> lock(mutex_);
    // The timeout covers a notify that lands between the check above and this wait.
    wake_.wait_for(lock, std::chrono::milliseconds(5), [this] {
      return stopping_.load(std::memory_order_acquire) || queue_->front() != nullptr;
    });
  }
  mapper_->finish();
}

}  // namespace rgbdtam
