#include "rgbdtam/core/view_alignment.hpp"

#include <algorithm>
#include <cmath>

namespace rgbdtam {
namespace {
// The two directions' estimates compose to identity within this: a fifth of the false-valid
// tolerance (10 cm, 5 degrees). A wrong minimum found one way is rarely found the other way.
constexpr double kMaxDisagreementM = 0.02;
constexpr double kMaxDisagreementRad = 1.0 * M_PI / 180.0;
// Each view sees at least half of the other's points for the place to be believed; 60 % for
// the relative pose to be measured well enough for the map: of the fr1_xyz pairs verified at
// 50-60 %, four were 4.1-5.5 cm off the ground truth, none at 60 % and above
// (docs/loop-closure.md).
constexpr double kMinVisibleSamePlace = 0.5;
constexpr double kMinVisibleMeasured = 0.6;
}  // namespace

int View::level(const PinholeIntrinsics& camera) {
  constexpr int kPreferred = 2;
  constexpr int kSide = 1 << (kPyramidLevels - 1);
  int l = kPreferred;
  while (l > 0 && ((camera.width_px >> l) % kSide != 0 || (camera.height_px >> l) % kSide != 0))
    --l;
  return l;
}

PinholeIntrinsics View::intrinsics(const PinholeIntrinsics& camera) {
  PinholeIntrinsics k = camera;
  for (int l = 0; l < level(camera); ++l) k = k.half();
  return k;
}

void View::allocate(const PinholeIntrinsics& camera) {
  const PinholeIntrinsics k = intrinsics(camera);
  gray.allocate(k.width_px, k.height_px);
  inverse_depth.allocate(k.width_px, k.height_px);
}

size_t View::bytes(const PinholeIntrinsics& camera) {
  const PinholeIntrinsics k = intrinsics(camera);
  return static_cast<size_t>(k.width_px) * k.height_px * (sizeof(uint8_t) + sizeof(uint16_t));
}

void capture_view(const FramePyramid& frame, View* out) {
  const int level = View::level(frame.intrinsics(0));
  const ImageF& gray = frame.gray(level);
  const ImageF& inverse_depth = frame.inverse_depth(level);
  RGBDTAM_ASSERT(gray.width() == out->gray.width() && gray.height() == out->gray.height(),
                 "view size differs from the frame's view level");
  for (int i = 0; i < gray.size(); ++i) {
    out->gray.data()[i] =
        static_cast<uint8_t>(std::lround(std::clamp(gray.data()[i], 0.f, 1.f) * 255.f));
    const long q = std::lround(inverse_depth.data()[i] / kViewInverseDepthStep);
    out->inverse_depth.data()[i] = static_cast<uint16_t>(q > 65535 ? 0 : q);
  }
}

TrackerOptions view_tracker_options(const TrackerOptions& tracking, int view_level) {
  TrackerOptions o = tracking;
  // The view is the pyramid's level view_level: its levels are the tracker's from there down,
  // with as many points; the coarser levels below the tracker's coarsest widen the basin.
  for (int l = 0; l < view_level; ++l) o.photometric_points_finest /= 3;
  for (int l = 0; l < kPyramidLevels; ++l) {
    const int from = std::min(l + view_level, kPyramidLevels - 1);
    o.geometric_step[l] = tracking.geometric_step[from];
    o.max_iterations[l] = tracking.max_iterations[from];
  }
  return o;
}

bool shows_same_place(const ViewAlignment& a) {
  return a.forward_failed == 0 && a.backward_failed == 0 && a.disagreement_m <= kMaxDisagreementM &&
         a.disagreement_rad <= kMaxDisagreementRad &&
         std::min(a.forward.visible, a.backward.visible) >= kMinVisibleSamePlace;
}

bool measures_pose(const ViewAlignment& a) {
  return shows_same_place(a) &&
         std::min(a.forward.visible, a.backward.visible) >= kMinVisibleMeasured;
}

size_t ViewAligner::bytes_needed(const PinholeIntrinsics& camera, const TrackerOptions& tracking) {
  const PinholeIntrinsics k = View::intrinsics(camera);
  // The four levels of a view's pyramid hold under 4/3 of its pixels.
  const size_t pixels = static_cast<size_t>(k.width_px) * k.height_px * 4 / 3;
  constexpr size_t kRawDepthTable = 65536 * sizeof(float);
  // Per side a pyramid (grey, inverse depth) with its raw-depth table, and a keyframe; the
  // builder's images (edges, four gradients) and Canny's scratch; the tracker's point scratch.
  const size_t side =
      kRawDepthTable + 2 * sizeof(float) * pixels +
      KeyframeBuilder::keyframe_bytes(k, view_tracker_options(tracking, View::level(camera)));
  constexpr size_t kBuilderBytesPerPixel = 1 + 4 * sizeof(float) + 12;
  constexpr size_t kTrackerBytesPerPoint = 17 * sizeof(float);
  return 2 * side + kBuilderBytesPerPixel * pixels + kTrackerBytesPerPoint * pixels;
}

void ViewAligner::allocate(const PinholeIntrinsics& camera, double depth_factor,
                           const DepthRange& range, const TrackerOptions& tracking) {
  const PinholeIntrinsics k = View::intrinsics(camera);
  const TrackerOptions options = view_tracker_options(tracking, View::level(camera));
  builder_.allocate(k, options);
  for (Side& s : sides_) {
    s.pyramid.allocate(k, depth_factor, range);
    builder_.allocate_keyframe(&s.keyframe);
  }
  tracker_.allocate(sides_[0].keyframe, options);
}

void ViewAligner::set(int side, const View& view) {
  Side& s = sides_[side];
  ImageF& gray = s.pyramid.gray(0);
  ImageF& inverse_depth = s.pyramid.inverse_depth_level0();
  for (int i = 0; i < gray.size(); ++i) {
    gray.data()[i] = static_cast<float>(view.gray.data()[i]) * (1.f / 255.f);
    inverse_depth.data()[i] =
        static_cast<float>(view.inverse_depth.data()[i]) * kViewInverseDepthStep;
  }
  s.pyramid.build_gray();
  s.pyramid.build_inverse_depth_levels();
  builder_.build(s.pyramid, 0, 0, SE3(), &s.keyframe);
}

ViewAlignment ViewAligner::align(const SE3* T_a_b_guesses, int count, const HealthLimits& limits) {
  // Each side's own residual scale is its yardstick: two views have no shared history.
  const ReferenceScales none;
  const HealthContext no_motion;
  ViewAlignment out;
  // The first guess as it is (the best-informed one); when that fails, the wider basin: every
  // guess, and each turned about the camera's x and y axes (panned and tilted, which at a
  // view's distance also stands for a sideways shift; the coarsest level's basin is some 5
  // degrees wide), screened at the coarsest level. Screening first would sometimes prefer a
  // turned copy of a good guess (fr1_xyz pairs: 5 % fewer verified from the map's guesses).
  out.forward = tracker_.track(sides_[0].keyframe, sides_[1].pyramid, T_a_b_guesses[0], none);
  out.forward_failed = failed_health_checks(out.forward, no_motion, limits);
  if (out.forward_failed != 0) {
    constexpr double kTurnRad = 5.0 * M_PI / 180.0;
    constexpr int kTurns = 2;
    SE3 guesses[kMaxGuesses * (1 + 4 * kTurns)];
    int n = 0;
    for (int g = 0; g < std::min(count, kMaxGuesses); ++g) {
      guesses[n++] = T_a_b_guesses[g];
      for (int step = 1; step <= kTurns; ++step) {
        for (int axis = 0; axis < 2; ++axis) {
          for (const double sign : {-1.0, 1.0}) {
            const Vector3d turn = Vector3d::Unit(axis) * (sign * step * kTurnRad);
            guesses[n++] = T_a_b_guesses[g] * SE3(so3_exp(turn), Vector3d::Zero());
          }
        }
      }
    }
    out.forward = tracker_.track_best(sides_[0].keyframe, sides_[1].pyramid, guesses, n, none);
    out.forward_failed = failed_health_checks(out.forward, no_motion, limits);
  }
  out.T_a_b = out.forward.T_k_c;
  out.backward = tracker_.track(sides_[1].keyframe, sides_[0].pyramid, out.T_a_b.inverse(), none);
  out.backward_failed = failed_health_checks(out.backward, no_motion, limits);
  const SE3 loop = out.T_a_b * out.backward.T_k_c;
  out.disagreement_m = loop.translation().norm();
  out.disagreement_rad = so3_log(loop.quaternion()).norm();
  return out;
}

}  // namespace rgbdtam
