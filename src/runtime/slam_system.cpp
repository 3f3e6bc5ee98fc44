#include "rgbdtam/runtime/slam_system.hpp"

namespace rgbdtam {

MemoryNeed memory_need(const Params& p, int vocabulary_words) {
  // The pyramids, undistortion maps and scratch images of the tracker and of the mapper, per
  // pixel of the camera; measured by test_allocations (it counts what init allocates).
  constexpr size_t kTrackerImageBytesPerPixel = 83, kMapperImageBytesPerPixel = 86;
  const size_t pixels = static_cast<size_t>(p.camera.width_px) * p.camera.height_px;
  const size_t seeds = p.map_enabled ? static_cast<size_t>(p.map_seeds) : 0;
  MemoryNeed m;
  m.per_keyframe = KeyframeBuilder::keyframe_bytes(p.camera, p.tracker) + seeds * sizeof(MapPoint);
  m.keyframe_pool = m.per_keyframe * static_cast<size_t>(p.keyframe_pool_size);
  if (p.map_enabled) {
    MultiViewOptions mv;
    mv.max_seeds = p.map_seeds;
    constexpr size_t kQueueBytesPerPixel = sizeof(float) * 2 + 1;  // MapperFrame's images
    m.mapper = static_cast<size_t>(p.map_queue_frames) * pixels * kQueueBytesPerPixel +
               MappingModule::kOpenKeyframes * SeedMap::bytes_needed(mv) +
               seeds * (sizeof(FusedPixel) + 2 * sizeof(MapPoint));  // + the local maps
  }
  // The tracker's own alias finder (for the keyframe it builds at once from the last valid frame).
  m.images =
      pixels * (kTrackerImageBytesPerPixel + (p.map_enabled ? kMapperImageBytesPerPixel : 0)) +
      KeyframeBuildTask::bytes_needed(p, static_cast<int>(seeds)) +
      KeyframeAliasFinder::bytes_needed(p.camera, p.tracker) + DepthInColour::bytes_needed(p);
  if (p.loop.enabled && vocabulary_words > 0) {
    // The places, the loop module (its recogniser, view aligner and graph) and the tracker's
    // relocaliser, the keyframe queue's images and the corrections.
    constexpr size_t kQueueBytesPerPixel = 2 * sizeof(float);
    m.loop = PlaceStore::bytes_needed(p.loop.places, p.loop.features, vocabulary_words, p.camera) +
             PlaceRecognizer::bytes_needed(p) + LoopModule::bytes_needed(p) +
             Relocaliser::bytes_needed(p) +
             static_cast<size_t>(p.loop.queue_keyframes) *
                 (pixels * kQueueBytesPerPixel + View::bytes(p.camera)) +
             static_cast<size_t>(p.loop.places) * 2 * sizeof(KeyframePose);
  }
  return m;
}

Status SlamSystem::init(const Params& params, ClockFn clock, MapSink* sink,
                        const Vocabulary* vocabulary) {
  params_ = params;
  clock_ = clock;
  depth_in_colour_.init(params);
  RGBDTAM_RETURN_IF_ERROR(tracking_.init(params, &keyframes_, &building_, clock));
  if (params.map_threaded) {
    constexpr int kOrdersInFlight = 1;
    build_queue_.allocate(kOrdersInFlight);
    building_.connect_queue(&build_queue_);
  }
  loop_on_ = params.loop.enabled && vocabulary != nullptr;
  vocabulary_ = vocabulary;
  if (loop_on_) {
    constexpr int kCorrectionSlots = 2;
    loop_queue_.allocate(params.loop.queue_keyframes, params.camera);
    corrections_.allocate(kCorrectionSlots, params.loop.places);
    places_.allocate(params.loop.places, params.loop.features, vocabulary->words(), params.camera);
    RGBDTAM_RETURN_IF_ERROR(loop_.init(params, vocabulary, &places_, &corrections_, clock));
    tracking_.connect_loop(&loop_queue_, &corrections_, &places_, vocabulary);
  }
  if (params.map_enabled) {
    queue_.allocate(params.map_queue_frames, params.camera.width_px, params.camera.height_px);
    RGBDTAM_RETURN_IF_ERROR(mapper_.init(params, params.camera, clock, sink, &keyframes_));
    mapper_.connect_queue(&queue_);
    tracking_.connect_mapper(&queue_);
  }
  return Status::ok();
}

Status SlamSystem::load_map(const uint8_t* data, size_t size, MapFileInfo* info) {
  if (!loop_on_) {
    return Status::error(StatusCode::kInvalidArgument,
                         "a map file needs loop closure (loop.enabled and its vocabulary)");
  }
  RGBDTAM_RETURN_IF_ERROR(
      rgbdtam::load_map(data, size, params_, *vocabulary_, &places_, &loop_, info));
  if (params_.map_mode == MapMode::kLocalise) {
    // The map's places stay; the frames' own keyframes come and go in what is left.
    constexpr int kMinWorkingPlaces = 8;
    const uint32_t needed = info->places + kMinWorkingPlaces;
    if (static_cast<uint32_t>(places_.capacity()) < needed) {
      return Status::error(StatusCode::kOutOfRange,
                           "map.mode = localise keeps the map's %u places and needs room for %d "
                           "more: loop.places is %d, set it to at least %u",
                           info->places, kMinWorkingPlaces, places_.capacity(), needed);
    }
    std::lock_guard<std::mutex> lock(places_.mutex());
    places_.keep_oldest(static_cast<int>(info->places));
  }
  tracking_.start_in_loaded_map(info->next_keyframe_id);
  return Status::ok();
}

MapFileInfo SlamSystem::map_meta(MapFileInfo meta) const {
  RGBDTAM_ASSERT(loop_on_, "a map file needs loop closure on");
  meta.camera = params_.camera;
  meta.vocabulary_checksum = vocabulary_->checksum();
  meta.vocabulary_words = static_cast<uint32_t>(vocabulary_->words());
  return meta;
}

Status SlamSystem::write_map(MapFileInfo meta, ByteSink* out) const {
  RGBDTAM_ASSERT(loop_on_ && finished_, "a map is written after finish(), with loop closure on");
  meta = map_meta(meta);
  meta.next_keyframe_id = tracking_.next_keyframe_id();
  return rgbdtam::write_map(places_, loop_.edges(), meta, out);
}

Status SlamSystem::set_checkpoint(MapCheckpoint* checkpoint) {
  if (!loop_on_ || !params_.loop.threaded || params_.map_mode != MapMode::kSlam) {
    return Status::error(StatusCode::kInvalidArgument,
                         "saving the map while running needs loop closure on its own thread "
                         "(loop.enabled, loop.threaded) and map.mode = slam");
  }
  loop_.set_checkpoint(checkpoint);
  return Status::ok();
}

Status SlamSystem::start(const ThreadPlacement& mapper, const ThreadPlacement& loop,
                         const ThreadPlacement& builder) {
  if (loop_on_ && params_.loop.threaded) {
    RGBDTAM_RETURN_IF_ERROR(loop_thread_.start(&loop_queue_, &loop_, loop, "rgbdtam-loop"));
  }
  if (!params_.map_threaded) return Status::ok();
  RGBDTAM_RETURN_IF_ERROR(
      build_thread_.start(&build_queue_, &building_, builder, "rgbdtam-keyframe"));
  if (!params_.map_enabled) return Status::ok();
  return thread_.start(&queue_, &mapper_, mapper, "rgbdtam-mapper");
}

PoseEstimate SlamSystem::process(const SensorFrame& frame) {
  const PoseEstimate pose = track(frame);
  map_pending();
  return pose;
}

bool SlamSystem::keyframe_pose(uint32_t keyframe_id, SE3* T_w_k) {
  if (tracking_.keyframe_pose(keyframe_id, T_w_k)) return true;
  if (!loop_on_) return false;
  std::lock_guard<std::mutex> lock(places_.mutex());
  const int order = places_.order_of(keyframe_id);
  if (order < 0) return false;
  *T_w_k = places_.in_order(order).T_w_k;
  return true;
}

void SlamSystem::map_pending() {
  build_pending_keyframe();
  if (params_.map_threaded) build_thread_.notify();
  auto timed_drain = [this](auto* queue, auto* module) {
    auto now = [this] { return clock_ != nullptr ? clock_() : 0; };
    const int64_t t0 = now();
    const int items = drain(queue, module);
    return Steps{items, now() - t0};
  };
  if (loop_on_) {
    if (params_.loop.threaded) {
      loop_thread_.notify();
    } else {
      last_loop_ = timed_drain(&loop_queue_, &loop_);
    }
  }
  if (!params_.map_enabled) return;
  if (params_.map_threaded) {
    thread_.notify();
  } else {
    // Deterministic replay: the mapper takes its step here, between frames.
    last_mapper_ = timed_drain(&queue_, &mapper_);
  }
}

void SlamSystem::finish() {
  if (finished_) return;
  finished_ = true;
  if (build_thread_.running()) build_thread_.stop();
  if (loop_on_ && params_.loop.threaded && loop_thread_.running()) loop_thread_.stop();
  if (!params_.map_enabled) return;
  if (params_.map_threaded) {
    thread_.stop();
  } else {
    mapper_.finish();
  }
}

}  // namespace rgbdtam
