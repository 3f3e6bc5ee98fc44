#include "rgbdtam/core/keyframe_aliases.hpp"

#include <algorithm>
#include <cmath>

#include "rgbdtam/core/symmetric_eigen.hpp"

namespace rgbdtam {
namespace {
// The self-fit is probed at 160x120, half a pixel apart at the keyframe's median depth: a
// grout line or seam a few pixels wide at 640x480 is a pixel wide there.
constexpr int kLevel = 2;
constexpr double kSpacingPx = 0.5;
// The image is fitted at kProbeSigma; the depth is checked where a shift is refined, as the health
// checks judge a term (HealthLimits: 70 % inliers, agreement under 1).
constexpr double kMinDepthInliers = 0.7;
// An alias fits itself better than half as badly as a typical misaligned shift does; the
// pose's own basin (a few centimetres) is not an alias.
constexpr double kAliasFraction = 0.5;
constexpr double kOwnBasinM = 0.02;
// ... and keeps at least half of the keyframe's points in view (a frame must overlap the
// keyframe to be tracked against it, there as here).
constexpr double kMinOverlap = 0.5;
// Textures repeat along surfaces: the two directions the depth determines least.
constexpr int kSurfaceDirections = 2;
// Profile minima below this fraction of the typical fit are refined, at most kMaxRefined per
// direction (a lattice of aliases repeats: the nearest few are enough).
constexpr double kPromising = 0.8;
constexpr int kMaxRefined = 4;
// An alias is a shift: a refinement that turns the camera found something else.
constexpr double kMaxAliasTurnRad = 2.0 * M_PI / 180.0;

double median_depth(const TrackPoints& pts) {
  constexpr int kSample = 256;
  float z[kSample];
  const int stride = std::max(1, pts.size() / kSample);
  int n = 0;
  for (int i = 0; i < pts.size() && n < kSample; i += stride) z[n++] = pts.z()[i];
  std::nth_element(z, z + n / 2, z + n);
  return z[n / 2];
}
}  // namespace

Matrix3d depth_translation_axes(const TrackPoints& geometric) {
  Matrix3d H = Matrix3d::Zero();
  for (int i = 0; i < geometric.size(); ++i) {
    const Vector3d j(geometric.J(0)[i], geometric.J(1)[i], geometric.J(2)[i]);
    H += j * j.transpose();
  }
  if (!(H.trace() > 0.0)) return Matrix3d::Identity();
  return symmetric_eigen(H).vectors;
}

void KeyframeAliasFinder::allocate(const Keyframe& capacity_model, const TrackerOptions& opt) {
  tracker_.allocate(capacity_model, opt);
}

void KeyframeAliasFinder::find(const FramePyramid& own, const Keyframe& kf, double range_m,
                               KeyframeAliases* out) {
  out->count = 0;
  const TrackPoints& pts = kf.photometric(kLevel);
  if (pts.size() == 0 || !(range_m > 0.0)) return;
  const double depth = median_depth(kf.photometric(0));
  const double spacing =
      std::max(kSpacingPx * depth / own.intrinsics(kLevel).fx_px, 2.0 * range_m / (kMaxProbes - 1));
  const int n = std::min(kMaxProbes, static_cast<int>(2.0 * range_m / spacing) + 1);
  for (int i = 0; i < n; ++i) offsets_[i] = -range_m + i * spacing;
  const Matrix3d axes = depth_translation_axes(kf.geometric[0]);
  ReferenceScales scales;
  for (float& s : scales.photometric) s = kProbeSigma;
  for (int axis = 0; axis < kSurfaceDirections; ++axis) {
    Vector6d d = Vector6d::Zero();
    d.head<3>() = axes.col(axis);
    tracker_.profile(kf, own, SE3(), d, offsets_, n, kLevel, scales, kPhotometricTerm, costs_,
                     overlap_);
    // A typical misaligned shift's fit: the median over the shifts that overlap.
    double sorted[kMaxProbes];
    int m = 0;
    for (int i = 0; i < n; ++i) {
      if (overlap_[i] >= kMinOverlap) sorted[m++] = costs_[i];
    }
    if (m == 0) continue;
    std::nth_element(sorted, sorted + m / 2, sorted + m);
    const double typical = sorted[m / 2];
    // Each promising minimum is refined by tracking the keyframe against itself from there
    // (the probing line is only nearly along the surface); an alias is where that converges
    // away from the keyframe's own pose, to a shift that fits itself better than half as badly
    // as a typical one and keeps half of the points in view.
    int tried = 0;
    for (int i = 1; i + 1 < n && out->count < KeyframeAliases::kMax && tried < kMaxRefined; ++i) {
      const bool minimum = costs_[i] <= costs_[i - 1] && costs_[i] <= costs_[i + 1];
      if (!minimum || std::fabs(offsets_[i]) < kOwnBasinM || overlap_[i] < kMinOverlap ||
          !(costs_[i] < kPromising * typical)) {
        continue;
      }
      ++tried;
      const TrackResult r =
          tracker_.track(kf, own, SE3(Eigen::Quaterniond::Identity(), axes.col(axis) * offsets_[i]),
                         scales, kAllTerms);
      const Vector3d shift = r.T_k_c.translation();
      if (shift.norm() < kOwnBasinM || so3_log(r.T_k_c.quaternion()).norm() > kMaxAliasTurnRad) {
        continue;
      }
      const double zero = 0.0;
      double cost = 0.0, overlap = 0.0;
      tracker_.profile(kf, own, r.T_k_c, Vector6d::Zero(), &zero, 1, kLevel, scales,
                       kPhotometricTerm, &cost, &overlap);
      if (!(cost < kAliasFraction * typical) || overlap < kMinOverlap) continue;
      // The depth must repeat too: a structure in view that does not breaks the alias.
      const bool depth_fits =
          (r.terms & kGeometricTerm) == 0 ||
          (r.geometric_inliers >= kMinDepthInliers && r.geometric_agreement <= 1.0);
      if (!depth_fits) continue;
      bool known = false;
      for (int k = 0; k < out->count; ++k) {
        known = known || (out->shift_k[k] - shift).norm() < kOwnBasinM ||
                (out->shift_k[k] + shift).norm() < kOwnBasinM;
      }
      if (!known) out->shift_k[out->count++] = shift;
    }
  }
}

}  // namespace rgbdtam
