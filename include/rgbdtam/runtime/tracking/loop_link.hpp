#pragma once
// The tracker's side of loop closure: new keyframes and reuses out to the loop module, its
// corrections in, and the remembered places a lost frame is looked up in (relocalisation).
// Without a loop module connected, it offers nothing and finds nothing. Thread: the tracker's.

#include <cstdint>

#include "rgbdtam/runtime/loop_closing.hpp"
#include "rgbdtam/runtime/relocaliser.hpp"
#include "rgbdtam/runtime/tracking/keyframe_handover.hpp"
#include "rgbdtam/runtime/tracking/pose_search.hpp"

namespace rgbdtam {

struct LoopLinkCounters {
  uint32_t loop_dropped_keyframes = 0;  // the loop queue was full: not remembered (or a reuse lost)
};

class LoopLink {
 public:
  // Init time.
  void connect(const Params& params, LoopQueue* keyframes, CorrectionQueue* corrections,
               PlaceStore* places, const Vocabulary* vocabulary);
  bool has_places() const { return places_ != nullptr; }

  // A new keyframe, tied to the map's graph by link (how its pose was measured) and window
  // (further measurements, against earlier keyframes), with its level-0 images and view.
  void offer_keyframe(const Keyframe& kf, const KeyframeLink& link, const WindowLinks& window,
                      const FramePyramid& f);
  // The frame was tracked against both the keyframe it left and the one taken up: their
  // relative pose, for the graph.
  void offer_reuse(const Attempt& left, const Attempt& taken, double covariance_scale);

  // The loop module's next correction, or null; taken once applied (counted as taken even
  // when none of it applied here: the loop module corrects the keyframes it receives by what
  // the tracker has taken).
  const LoopCorrection* next_correction();
  void correction_taken();

  // The frame among the places, near the last valid pose where there is one.
  Relocalisation find(const FramePyramid& frame, const SE3* T_w_last);

  const LoopLinkCounters& counters() const { return counters_; }

 private:
  // A free slot of the loop module's queue, or null (no loop module, or full: counted).
  LoopKeyframe* slot();

  LoopQueue* loop_queue_ = nullptr;
  CorrectionQueue* corrections_ = nullptr;
  PlaceStore* places_ = nullptr;
  const Vocabulary* vocabulary_ = nullptr;
  Relocaliser relocaliser_;
  uint32_t corrections_adopted_ = 0;
  LoopLinkCounters counters_;
};

}  // namespace rgbdtam
