#pragma once
// The loop module (paper sec. VI) and its keyframe graph. Every new keyframe is remembered as a
// place (features, bag of words, coarse view) and tied into the graph: by the tracker's
// measurement against its reference, and by direct alignment of its view with the views of
// chosen places (core/view_alignment.hpp), each verified alignment an edge:
//   - a covisible neighbour, a few edges away in the graph (the keyframe is aligned to more
//     than its predecessor);
//   - revisits by geometry: places the map puts near the keyframe but which the graph joins
//     only through a long path (drift lies along it), the longest first;
//   - revisits by appearance: the bag of words' best places outside the keyframe's
//     neighbourhood, or in a stretch the graph does not join at all (after a restart), with
//     the features' RANSAC as the first guess.
// The tracker's reuse of an earlier keyframe is an edge too, and so is its local window's second
// measurement of a keyframe, against an earlier one, at full resolution. An edge that disagrees
// with the map optimises the SE(3) pose graph of all places, and the corrected poses go to the
// tracker as a LoopCorrection it adopts between frames.
// step() is the same code synchronously (replay) or on its own thread (WorkerThread); after
// init() nothing allocates.

#include "rgbdtam/core/pose_graph.hpp"
#include "rgbdtam/port/latency_stats.hpp"
#include "rgbdtam/port/messages.hpp"
#include "rgbdtam/port/spsc_ring.hpp"
#include "rgbdtam/runtime/mapping.hpp"
#include "rgbdtam/runtime/place_recognition.hpp"

namespace rgbdtam {

class LoopQueue : public SpscRing<LoopKeyframe> {
 public:
  void allocate(int slots, const PinholeIntrinsics& camera);
};

class CorrectionQueue : public SpscRing<LoopCorrection> {
 public:
  void allocate(int slots, int places);
};

struct LoopCounters {
  uint32_t revisits_disagreeing = 0;  // keyframes whose revisits put them in different places
  uint32_t look_alikes = 0;      // revisits asking more correction than odometry drifts: not loops
  uint32_t keyframes = 0;        // described and remembered
  uint32_t candidates = 0;       // places whose views were aligned with a keyframe's
  uint32_t covisible_edges = 0;  // ... verified: a neighbour
  uint32_t window_edges = 0;     // the tracker's second measurement of a keyframe (local window)
  uint32_t revisit_edges = 0;    // ... verified: a revisit (a loop)
  uint32_t reuse_edges = 0;      // the tracker took up an earlier keyframe
  uint32_t edges_dropped = 0;    // the graph's edge store was full
  uint32_t corrections = 0;      // optimisations that moved the map
  uint32_t corrections_dropped = 0;  // the tracker had not taken the previous one
};

constexpr int kEdgeKinds = static_cast<int>(EdgeKind::kReuse) + 1;
const char* edge_kind_name(EdgeKind kind);

// An edge of the keyframe graph, for tools that check it against ground truth. Called on the
// loop module's thread when the edge enters the graph.
struct GraphEdgeEvent {
  uint32_t from_id = 0, to_id = 0;  // keyframe ids
  SE3 T_from_to;
  EdgeKind kind = EdgeKind::kOdometry;
};

class LoopObserver {
 public:
  virtual ~LoopObserver() = default;
  virtual void on_edge(const GraphEdgeEvent& event) = 0;
  // A place moved by the correction numbered `correction` (from 1), under the store's lock.
  virtual void on_place_moved(uint32_t /*correction*/, uint32_t /*keyframe_id*/,
                              const SE3& /*T_w_before*/, const SE3& /*T_w_after*/) {}
};

// The revisit candidates a keyframe's view is aligned with, at most.
struct CandidateBudget {
  static constexpr int kCovisible = 1;
  static constexpr int kGeometric = 2;
  static constexpr int kAppearance = 3;
  static constexpr int kTotal = kCovisible + kGeometric + kAppearance;
};

class MapCheckpoint;

class LoopModule {
 public:
  // Edges the graph keeps per place: its measurement, and on average a few verified alignments.
  static constexpr int kEdgesPerPlace = 4;
  struct Edge {
    PlaceHandle from, to;
    SE3 T_from_to;
    Matrix6d information;  // of T_from_to exp(xi)
    EdgeKind kind;
  };
  Status init(const Params& params, const Vocabulary* vocabulary, PlaceStore* store,
              CorrectionQueue* corrections, ClockFn clock);
  void step(const LoopKeyframe& message);
  void tick();  // a periodic save, when one is due
  void finish() {}
  void set_observer(LoopObserver* observer) { observer_ = observer; }
  // Init time: saves while running (threaded loop module only: a save takes a while).
  void set_checkpoint(MapCheckpoint* checkpoint) { checkpoint_ = checkpoint; }
  const LoopCounters& counters() const { return counters_; }
  const LatencyStats& describe_time() const { return describe_time_; }
  const LatencyStats& search_time() const { return search_time_; }  // candidates and alignment
  const LatencyStats& optimise_time() const { return optimise_time_; }
  // Bytes init() takes besides the place store, for the memory budget.
  static size_t bytes_needed(const Params& params);
  // The graph's edges (some may name forgotten places); the loop module's thread, or after
  // finish().
  const FixedVector<Edge>& edges() const { return edges_; }
  // A loaded map's edge, after init and before the first step; false when the graph is full.
  bool restore_edge(const Edge& edge) { return edges_.push_back(edge); }

 private:
  void add_keyframe(const LoopKeyframe& keyframe);
  void add_reuse(const LoopKeyframe& message);
  void remember(const LoopKeyframe& keyframe, const SE3& T_w_k);
  // How far the map must move to be refined (an edge disagreeing with it) or sent (a place moved).
  struct MoveLimit {
    double m, rad;
    bool exceeded_by(const SE3& d) const;
  };
  MoveLimit correction_limit() const;  // loop.min_correction
  MoveLimit window_limit() const;      // loop.min_window_correction
  // Adds the edge; returns whether it disagrees with the map by more than the limit.
  bool add_edge(const Edge& edge, const MoveLimit& limit);
  bool add_edge(const Edge& edge) { return add_edge(edge, correction_limit()); }
  // Graph distance (edges with a measurement) of every place from the one in `slot`; -1 where
  // the graph does not join them.
  // A revisit of the place at place_slot by the newest place (order query), aligned by a, asks
  // no more correction than odometry can have drifted since.
  bool within_drift(int place_slot, int query, const ViewAlignment& a) const;
  void measure_hops(int slot);
  int choose_candidates(int query_slot, PlaceCandidate* out);
  // Optimises the graph and sends the map if some place moved beyond the limit.
  void optimise(const MoveLimit& send_beyond);

  Params params_;
  const Vocabulary* vocabulary_ = nullptr;
  PlaceStore* store_ = nullptr;
  CorrectionQueue* corrections_ = nullptr;
  ClockFn clock_ = nullptr;
  LoopObserver* observer_ = nullptr;
  MapCheckpoint* checkpoint_ = nullptr;
  PlaceRecognizer recognizer_;
  VerificationLimits limits_;
  ViewAligner aligner_;
  PoseGraph graph_;
  FixedVector<Edge> edges_;
  // Breadth-first search over the graph: hops per slot, the queue, adjacency in CSR form.
  std::unique_ptr<int[]> hops_, queue_, first_neighbour_, neighbours_;
  // Per slot: the place's relation to its predecessor is unknown (a restart), so no drift
  // bound holds across it.
  std::unique_ptr<uint8_t[]> after_restart_;
  std::unique_ptr<int[]> node_of_slot_;  // the pose graph's node of each slot
  // The last correction, for keyframes the tracker made before adopting it.
  uint32_t corrections_sent_ = 0;
  SE3 last_correction_;
  LoopCounters counters_;
  LatencyStats describe_time_, search_time_, optimise_time_;
};

}  // namespace rgbdtam
