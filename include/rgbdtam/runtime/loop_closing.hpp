#pragma once
// The loop module (paper sec. VI): every new keyframe is described (features, bag of words),
// matched against the remembered places, and remembered itself. A place found again by
// consecutive keyframes and verified in 3-D becomes a loop edge; when the loop disagrees with
// the map, the SE(3) pose graph of all remembered keyframes is optimised and the corrected
// poses go to the tracker as a LoopCorrection it adopts between frames.
// step() is the same code synchronously (replay) or on its own thread (WorkerThread).

#include "rgbdtam/core/pose_graph.hpp"
#include "rgbdtam/runtime/latency_stats.hpp"
#include "rgbdtam/runtime/mapping.hpp"
#include "rgbdtam/runtime/messages.hpp"
#include "rgbdtam/runtime/place_recognition.hpp"
#include "rgbdtam/runtime/spsc_ring.hpp"

namespace rgbdtam {

class LoopQueue : public SpscRing<LoopKeyframe> {
 public:
  void allocate(int slots, int width, int height);
};

class CorrectionQueue : public SpscRing<LoopCorrection> {
 public:
  void allocate(int slots, int places);
};

struct LoopCounters {
  uint32_t keyframes = 0;            // described and remembered
  uint32_t candidates = 0;           // places verified in 3-D
  uint32_t verified = 0;             // ... that passed
  uint32_t loops = 0;                // verified and consistent: loop edges
  uint32_t corrections = 0;          // loops that moved the map
  uint32_t corrections_dropped = 0;  // the tracker had not taken the previous one
};

// A place the loop module verified in 3-D for a new keyframe, for tools that check place
// recognition against ground truth. Called on the loop module's thread.
struct PlaceMatchEvent {
  uint32_t query_id = 0, place_id = 0;
  int64_t query_ns = 0, place_ns = 0;
  SE3 T_place_query;
  int inliers = 0;
  bool loop = false;  // it became a loop edge (consistent, and the best of its query)
};

class LoopObserver {
 public:
  virtual ~LoopObserver() = default;
  virtual void on_verified(const PlaceMatchEvent& event) = 0;
};

class LoopModule {
 public:
  Status init(const Params& params, const Vocabulary* vocabulary, PlaceStore* store,
              CorrectionQueue* corrections, ClockFn clock);
  void step(const LoopKeyframe& keyframe);
  void tick() {}
  void finish() {}
  void set_observer(LoopObserver* observer) { observer_ = observer; }
  const LoopCounters& counters() const { return counters_; }
  const LatencyStats& describe_time() const { return describe_time_; }
  const LatencyStats& query_time() const { return query_time_; }
  const LatencyStats& optimise_time() const { return optimise_time_; }

 private:
  struct LoopEdge {
    PlaceHandle from, to;
    SE3 T_from_to;
    Matrix6d information;
  };
  struct Found {
    PlaceHandle place;
    uint32_t keyframe_id = 0;
    SE3 T_place_query;
    RigidRansacResult fit;
  };
  bool detect(const LoopKeyframe& query, Found* found);
  void remember(const LoopKeyframe& keyframe, const SE3& T_w_k);
  void close_loop(const Found& found, uint32_t query_id);
  void optimise(uint32_t query_id, uint32_t match_id);

  Params params_;
  const Vocabulary* vocabulary_ = nullptr;
  PlaceStore* store_ = nullptr;
  CorrectionQueue* corrections_ = nullptr;
  ClockFn clock_ = nullptr;
  LoopObserver* observer_ = nullptr;
  PlaceRecognizer recognizer_;
  VerificationLimits limits_;
  PoseGraph graph_;
  FixedVector<LoopEdge> loops_;
  uint32_t segment_ = 0;
  // The last correction, for keyframes the tracker made before adopting it.
  uint32_t corrections_sent_ = 0;
  SE3 last_correction_;
  // Consistency over consecutive queries.
  uint32_t last_match_id_ = 0;
  int consistent_ = 0;
  LoopCounters counters_;
  LatencyStats describe_time_, query_time_, optimise_time_;
};

}  // namespace rgbdtam
