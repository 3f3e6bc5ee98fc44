#pragma once
// Finds a lost frame among the remembered places: candidates by appearance (the bag of words'
// best places, the features' fit as the first guess) and by geometry (the places nearest the
// last valid pose), each verified by direct alignment of the views, as the loop module
// verifies a revisit. Tracker's thread; reads the place store under its lock. Sized in
// allocate(); find() never allocates.

#include "rgbdtam/runtime/place_recognition.hpp"

namespace rgbdtam {

struct Relocalisation {
  bool found = false;
  uint32_t place_id = 0;
  SE3 T_w_place;
  ViewAlignment alignment;  // view a is the place's, b the frame's: T_a_b is the frame in it
  SE3 T_w_c() const { return T_w_place * alignment.T_a_b; }
};

class Relocaliser {
 public:
  void allocate(const Params& params);
  // T_w_last: the last valid pose, or null when the map has no pose to search near.
  Relocalisation find(const FramePyramid& frame, const SE3* T_w_last, PlaceStore* places,
                      const Vocabulary& vocabulary);
  static size_t bytes_needed(const Params& params);

 private:
  static constexpr int kAppearance = 4;
  static constexpr int kGeometric = 2;
  Params params_;
  PlaceRecognizer recognizer_;
  VerificationLimits limits_;
  ViewAligner aligner_;
  View view_;
};

}  // namespace rgbdtam
