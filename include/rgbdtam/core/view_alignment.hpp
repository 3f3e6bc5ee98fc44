#pragma once
// Direct alignment of two views, for loop closure and relocalisation. A view is one coarse level
// of a frame's pyramid (View::level: 160x120 for a 640x480 camera), grey and inverse depth, small
// enough to keep for every remembered place (57.6 kB at 160x120). To compare two views, each
// becomes a small pyramid and keyframe of its own, and the tracker's alignment and health checks
// run at the view's resolution: the same evidence that makes a tracked pose valid makes a
// revisit believed. Each view is tracked against the other, and the two estimates must agree.
// Everything is sized in allocate(); nothing allocates after.

#include "rgbdtam/core/tracker.hpp"
#include "rgbdtam/core/tracking_health.hpp"

namespace rgbdtam {

// A view's inverse depth is stored in steps of 1/8192 per metre (a fortieth of the Kinect's own
// quantisation at 1 m); 0 means no depth, and nearer than 12.5 cm is out of range.
constexpr float kViewInverseDepthStep = 1.f / 8192.f;

struct View {
  ImageU8 gray;            // grey levels
  ImageU16 inverse_depth;  // kViewInverseDepthStep units; 0 = none
  // camera: the full-resolution camera whose pyramid the view is taken from.
  void allocate(const PinholeIntrinsics& camera);
  static size_t bytes(const PinholeIntrinsics& camera);
  // The pyramid level a view is: the second coarser (160x120 of 640x480), or finer where that
  // level is too small for a four-level pyramid of its own (sides divisible by 8).
  static int level(const PinholeIntrinsics& camera);
  static PinholeIntrinsics intrinsics(const PinholeIntrinsics& camera);
};

// The frame's pyramid level View::level, quantised into a view (no depth: all 0).
void capture_view(const FramePyramid& frame, View* out);

// The options of the tracker that compares views: the tracker's own, as it runs at the view's
// level of a full pyramid.
TrackerOptions view_tracker_options(const TrackerOptions& tracking, int view_level);

struct ViewAlignment {
  SE3 T_a_b;             // view b's camera in view a's: the forward estimate
  TrackResult forward;   // b tracked against a's keyframe
  TrackResult backward;  // a tracked against b's, from the forward estimate inverted
  uint32_t forward_failed = ~0u, backward_failed = ~0u;  // HealthCheck bits
  // The forward estimate composed with the backward one: 0 when they agree.
  double disagreement_m = 0.0, disagreement_rad = 0.0;
};

// Whether an alignment shows the same place: both directions pass the tracker's health checks,
// they agree with each other, and each view sees at least half of the other's points. Chosen by
// measurement on real pairs of views (docs/loop-closure.md, "Verification").
bool shows_same_place(const ViewAlignment& a);
// ... and measures the relative pose well enough for an edge of the map: the views share more.
bool measures_pose(const ViewAlignment& a);

class ViewAligner {
 public:
  void allocate(const PinholeIntrinsics& camera, double depth_factor, const DepthRange& range,
                const TrackerOptions& tracking);
  static size_t bytes_needed(const PinholeIntrinsics& camera, const TrackerOptions& tracking);
  // Side 0 is view a, side 1 view b; a side keeps its view until set again.
  void set(int side, const View& view);
  // Tracks b against a from the best of the guesses (at most kMaxGuesses, each widened by
  // turned copies, screened at the coarsest level), then a against b from that estimate.
  static constexpr int kMaxGuesses = 3;
  ViewAlignment align(const SE3* T_a_b_guesses, int count, const HealthLimits& limits);

 private:
  struct Side {
    FramePyramid pyramid;
    Keyframe keyframe;
  };
  Side sides_[2];
  KeyframeBuilder builder_;
  Tracker tracker_;
};

}  // namespace rgbdtam
