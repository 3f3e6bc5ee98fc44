#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "rgbdtam/core/tracker.hpp"

namespace rgbdtam {
namespace {
constexpr float kInvalid = -1.f;  // marks a point that projects outside or has no data
constexpr float kMinDepthM = 0.05f;
constexpr float kMadToSigma = 1.4826f;
constexpr float kMinPhotometricSigma = 1.f / 255.f;
constexpr float kGainInlier = 0.2f;   // |I_cur - I_kf| below which a point informs gain/brightness
constexpr float kInlierSigmas = 3.f;  // overlap counts points within 3 standard deviations
constexpr float kDepthAgreement = 0.9f;
constexpr int kMinScaleSamples = 10;
constexpr double kInitialDamping = 1e-3;  // Marquardt factor on diag(H) after a rejected step
constexpr double kMaxDamping = 1e2;

struct Projector {
  float r[9], t[3];
  Pinhole pinhole;
  Projector(const SE3& T, const PinholeIntrinsics& k) {
    const Matrix3d R = T.rotation();
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) r[3 * i + j] = static_cast<float>(R(i, j));
      t[i] = static_cast<float>(T.translation()[i]);
    }
    pinhole = k.pinhole();
  }
  // Returns false when the point is behind the camera.
  bool project(const TrackPoint& p, float* u, float* v, float* z) const {
    const float qx = r[0] * p.x + r[1] * p.y + r[2] * p.z + t[0];
    const float qy = r[3] * p.x + r[4] * p.y + r[5] * p.z + t[1];
    const float qz = r[6] * p.x + r[7] * p.y + r[8] * p.z + t[2];
    if (qz < kMinDepthM) return false;
    pinhole.project_inverse_depth(qx, qy, 1.f / qz, u, v);
    *z = qz;
    return true;
  }
};

// Normal equations J^T W J and J^T W r. Rows sqrt(w) J / sigma are gathered in blocks and each
// block's products are formed at once (a small matrix product that vectorises, instead of an
// outer product per point); blocks are summed in double, so ~10^4 terms lose no precision
// that matters.
class NormalEquations {
 public:
  // x is the normalised residual r / sigma, and j_scale = 1 / sigma normalises J alike.
  void add(const float J[6], float j_scale, float weight, float x) {
    const float s = std::sqrt(weight);
    const float sj = s * j_scale;
    for (int k = 0; k < 6; ++k) rows_(k, count_) = J[k] * sj;
    rows_(6, count_) = s * x;
    if (++count_ == kBlock) flush();
  }
  void write(Eigen::Matrix<double, 6, 6>* H, Vector6d* g, double scale) {
    flush();
    *H += scale * H_;
    *g += scale * g_;
  }

 private:
  static constexpr int kBlock = 256;
  void flush() {
    if (count_ == 0) return;
    for (int r = 0; r < 6; ++r) {
      const auto a = rows_.row(r).head(count_);
      for (int c = r; c < 6; ++c) {
        const double v = a.dot(rows_.row(c).head(count_));
        H_(r, c) += v;
        if (c != r) H_(c, r) += v;
      }
      g_(r) += a.dot(rows_.row(6).head(count_));
    }
    count_ = 0;
  }
  // Column i: sqrt(w) J^T / sigma, then sqrt(w) x; row-major, so each product is one dot.
  Eigen::Matrix<float, 7, kBlock, Eigen::RowMajor> rows_;
  Eigen::Matrix<double, 6, 6> H_ = Eigen::Matrix<double, 6, 6>::Zero();
  Vector6d g_ = Vector6d::Zero();
  int count_ = 0;
};

// Geman-McClure: rho(x) = x^2 / (2 (1 + x^2/c^2)), weight = rho'(x)/x = 1 / (1 + x^2/c^2)^2.
struct GemanMcClure {
  double inv_c2;
  explicit GemanMcClure(double c) : inv_c2(1.0 / (c * c)) {}
  double cost(double x) const { return 0.5 * x * x / (1.0 + x * x * inv_c2); }
  double weight(double x) const {
    const double d = 1.0 + x * x * inv_c2;
    return 1.0 / (d * d);
  }
  double saturated_cost() const { return 0.5 / inv_c2; }
};
}  // namespace

void Tracker::allocate(const Keyframe& model, const TrackerOptions& opt) {
  opt_ = opt;
  int ph = 0, geo = 0;
  for (int l = 0; l < kPyramidLevels; ++l) {
    ph = std::max(ph, model.photometric(l).capacity());
    geo = std::max(geo, model.geometric[l].capacity());
  }
  ph_sample_.reserve_once(std::max(ph, 1));
  ph_residual_.reserve_once(std::max(ph, 1));
  geo_residual_.reserve_once(std::max(geo, 1));
  geo_sigma_.reserve_once(std::max(geo, 1));
  scratch_.reserve_once(std::max(std::max(ph, geo), 1));
}

void Tracker::sample_photometric(const FixedVector<TrackPoint>& pts, const ImageF& img,
                                 const PinholeIntrinsics& k, const SE3& T_c_k) {
  const Projector proj(T_c_k, k);
  ph_sample_.clear();
  for (const TrackPoint& p : pts) {
    float u, v, z;
    float s = kInvalid;
    if (proj.project(p, &u, &v, &z) && img.contains(u, v, 1.f)) s = sample_bilinear(img, u, v);
    (void)ph_sample_.push_back(s);
  }
}

void Tracker::estimate_gain_brightness(const FixedVector<TrackPoint>& pts) {
  if (!opt_.gain_brightness) return;
  // Moment matching, a = std(I_kf) / std(I_cur), b = mean(I_kf) - a mean(I_cur): a least-squares
  // fit of I_kf on I_cur would be biased towards a = 0 (regression dilution), because edge
  // pixels make I_cur noisy under any misalignment.
  double n = 0, s_c = 0, s_k = 0, s_cc = 0, s_kk = 0;
  for (int i = 0; i < pts.size(); ++i) {
    const float c = ph_sample_[i];
    if (c == kInvalid) continue;
    const float kf = pts[i].ref;
    if (std::fabs(gain_ * c + brightness_ - kf) > kGainInlier) continue;
    n += 1;
    s_c += c;
    s_k += kf;
    s_cc += static_cast<double>(c) * c;
    s_kk += static_cast<double>(kf) * kf;
  }
  if (n < 50) return;
  const double mean_c = s_c / n, mean_k = s_k / n;
  const double var_c = s_cc / n - mean_c * mean_c, var_k = s_kk / n - mean_k * mean_k;
  if (var_c <= 1e-8 || var_k <= 1e-8) return;
  const double a = std::sqrt(var_k / var_c);
  if (a < 0.5 || a > 2.0) return;  // an implausible gain means a bad alignment, not light
  gain_ = static_cast<float>(a);
  brightness_ = static_cast<float>(mean_k - a * mean_c);
}

float Tracker::mad_sigma(int m) {
  // sigma = 1.4826 * median(|r - median(r)|) over scratch_[0, m), the paper's MAD estimate.
  float* first = &scratch_[0];
  std::nth_element(first, first + m / 2, first + m);
  const float median = first[m / 2];
  for (int i = 0; i < m; ++i) first[i] = std::fabs(first[i] - median);
  std::nth_element(first, first + m / 2, first + m);
  return kMadToSigma * first[m / 2];
}

void Tracker::update_scales(int level, int n_ph, int n_geo) {
  int m = 0;
  for (int i = 0; i < n_ph; ++i)
    if (ph_sample_[i] != kInvalid) scratch_[m++] = ph_residual_[i];
  if (m >= kMinScaleSamples) ph_sigma_ = std::max(kMinPhotometricSigma, mad_sigma(m));
  // Each term is scaled by its own residuals, so that one whose residuals stop agreeing (blur,
  // misregistration) loses weight to the other. The geometric ones are divided by the sensor
  // model, which weights the points against each other (constant in inverse depth, z^2 in
  // depth); their spread scales the term. Where the estimate is refined, the finest level,
  // down to the disparity's quantisation; at the coarser levels, which find the basin, not
  // below the sensor model, so that misaligned structure still pulls.
  m = 0;
  for (int i = 0; i < n_geo; ++i)
    if (geo_sigma_[i] != 0.f) scratch_[m++] = geo_residual_[i] / geo_sigma_[i];
  const float floor =
      level == 0 ? static_cast<float>(opt_.inverse_depth_sigma_floor / opt_.inverse_depth_sigma)
                 : 1.f;
  geo_scale_ = m >= kMinScaleSamples ? std::max(floor, mad_sigma(m)) : 1.f;
}

void Tracker::sample_geometric(const FixedVector<TrackPoint>& pts, const ImageF& idepth,
                               const PinholeIntrinsics& k, const SE3& T_c_k) {
  const Projector proj(T_c_k, k);
  const bool inverse = opt_.residuals.geometric == GeometricMode::kInverseDepth;
  const float sigma_rho = static_cast<float>(opt_.inverse_depth_sigma);
  geo_residual_.clear();
  geo_sigma_.clear();
  for (const TrackPoint& p : pts) {
    float u, v, z;
    float residual = 0.f, sigma = 0.f;  // sigma 0 marks invalid
    if (proj.project(p, &u, &v, &z) && idepth.contains(u, v, 1.f)) {
      const int x0 = static_cast<int>(u), y0 = static_cast<int>(v);
      const float* r0 = idepth.row(y0) + x0;
      const float* r1 = r0 + idepth.width();
      const float lo = std::min(std::min(r0[0], r0[1]), std::min(r1[0], r1[1]));
      const float hi = std::max(std::max(r0[0], r0[1]), std::max(r1[0], r1[1]));
      if (lo > 0.f && lo >= kDepthAgreement * hi) {
        const float rho = sample_bilinear(idepth, u, v);
        if (inverse) {
          residual = 1.f / z - rho;
          sigma = sigma_rho;
        } else {
          const float depth = 1.f / rho;
          residual = z - depth;
          sigma = sigma_rho * depth * depth;  // sigma_z = z^2 sigma_d / (f b)
        }
      }
    }
    (void)geo_residual_.push_back(residual);
    (void)geo_sigma_.push_back(sigma);
  }
}

Tracker::LevelCost Tracker::accumulate(const FixedVector<TrackPoint>& ph,
                                       const FixedVector<TrackPoint>& geo) {
  LevelCost out;
  const GemanMcClure gm(opt_.robust_c);
  NormalEquations ne_ph, ne_geo;
  double cost_ph = 0.0, cost_geo = 0.0;
  int valid_geo = 0;
  const double inv_sigma = 1.0 / ph_sigma_;
  for (int i = 0; i < ph.size(); ++i) {
    if (ph_sample_[i] == kInvalid) {
      cost_ph += gm.saturated_cost();
      continue;
    }
    const double x = ph_residual_[i] * inv_sigma;
    cost_ph += gm.cost(x);
    ne_ph.add(ph[i].J, static_cast<float>(inv_sigma), static_cast<float>(gm.weight(x)),
              static_cast<float>(x));
    ++out.valid;
  }
  for (int i = 0; i < geo.size(); ++i) {
    if (geo_sigma_[i] == 0.f) {
      cost_geo += gm.saturated_cost();
      continue;
    }
    const double inv_s = 1.0 / (geo_sigma_[i] * geo_scale_);
    const double x = geo_residual_[i] * inv_s;
    cost_geo += gm.cost(x);
    ne_geo.add(geo[i].J, static_cast<float>(inv_s), static_cast<float>(gm.weight(x)),
               static_cast<float>(x));
    ++out.valid;
    ++valid_geo;
  }
  ne_ph.write(&out.H, &out.g, 1.0);
  ne_geo.write(&out.H, &out.g, opt_.geometric_weight);
  out.cost = cost_ph + opt_.geometric_weight * cost_geo;
  const int invalid_ph = ph.size() - (out.valid - valid_geo);
  const int invalid_geo = geo.size() - valid_geo;
  out.valid_cost =
      out.cost - gm.saturated_cost() * (invalid_ph + opt_.geometric_weight * invalid_geo);
  out.total = ph.size() + geo.size();
  return out;
}

const FixedVector<TrackPoint>& Tracker::photometric_points(const Keyframe& kf, int level) const {
  return (terms_ & kPhotometricTerm) != 0 ? kf.photometric(level) : no_points_;
}

const FixedVector<TrackPoint>& Tracker::geometric_points(const Keyframe& kf,
                                                         const FramePyramid& frame,
                                                         int level) const {
  return (terms_ & kGeometricTerm) != 0 && frame.has_depth() ? kf.geometric[level] : no_points_;
}

Tracker::LevelCost Tracker::evaluate_level(const Keyframe& kf, const FramePyramid& frame, int level,
                                           const SE3& T_c_k, bool new_scale) {
  const FixedVector<TrackPoint>& ph = photometric_points(kf, level);
  const FixedVector<TrackPoint>& geo = geometric_points(kf, frame, level);
  const PinholeIntrinsics& k = frame.intrinsics(level);
  sample_photometric(ph, frame.gray(level), k, T_c_k);
  estimate_gain_brightness(ph);
  ph_residual_.clear();
  for (int i = 0; i < ph.size(); ++i) {
    (void)ph_residual_.push_back(
        ph_sample_[i] == kInvalid ? 0.f : gain_ * ph_sample_[i] + brightness_ - ph[i].ref);
  }
  sample_geometric(geo, frame.inverse_depth(level), k, T_c_k);
  if (new_scale) update_scales(level, ph.size(), geo.size());
  return accumulate(ph, geo);
}

Tracker::LevelCost Tracker::optimize_level(const Keyframe& kf, const FramePyramid& frame, int level,
                                           SE3* T_c_k, bool new_scale, int max_iterations,
                                           int* iterations) {
  LevelCost current = evaluate_level(kf, frame, level, *T_c_k, new_scale);
  // Gauss-Newton with Marquardt damping: a step that raises the cost is retried shorter
  // instead of ending the level, since the keyframe-side Jacobians are approximate far
  // from the keyframe.
  double damping = 0.0;
  bool buffers_current = true;  // the scratch buffers hold the evaluation at *T_c_k
  for (int it = 0; it < max_iterations; ++it) {
    if (current.valid < 6) break;
    Eigen::Matrix<double, 6, 6> H = current.H;
    H.diagonal() *= 1.0 + 1e-6 + damping;
    const Vector6d delta = H.ldlt().solve(-current.g);
    if (!delta.allFinite()) break;
    const SE3 T_new = *T_c_k * SE3::exp(-delta);
    const float gain = gain_, brightness = brightness_;
    LevelCost next = evaluate_level(kf, frame, level, T_new, false);
    ++*iterations;
    if (next.cost >= current.cost) {
      buffers_current = false;
      gain_ = gain;
      brightness_ = brightness;
      damping = damping == 0.0 ? kInitialDamping : damping * 10.0;
      if (damping > kMaxDamping) break;
      continue;
    }
    buffers_current = true;
    damping = damping * 0.1 < kInitialDamping ? 0.0 : damping * 0.1;
    const double decrease = (current.cost - next.cost) / current.cost;
    *T_c_k = T_new;
    current = next;
    if (decrease < opt_.min_relative_decrease) break;
  }
  if (!buffers_current) current = evaluate_level(kf, frame, level, *T_c_k, false);
  return current;
}

TrackResult Tracker::track(const Keyframe& kf, const FramePyramid& frame, const SE3& T_k_c_guess,
                           const ReferenceScales& reference, uint8_t terms) {
  TrackResult result;
  terms_ = terms;
  SE3 T_c_k = T_k_c_guess.inverse();
  gain_ = 1.f;
  brightness_ = 0.f;
  LevelCost finest;
  for (int level = kPyramidLevels - 1; level >= 0; --level) {
    finest = optimize_level(kf, frame, level, &T_c_k, true, opt_.max_iterations[level],
                            &result.iterations);
    result.level_sigma[level] = ph_sigma_;
  }
  result.T_k_c = T_c_k.inverse();
  result.terms =
      static_cast<uint8_t>((photometric_points(kf, 0).size() > 0 ? kPhotometricTerm : 0) |
                           (geometric_points(kf, frame, 0).size() > 0 ? kGeometricTerm : 0));
  result.photometric_sigma = ph_sigma_;
  result.gain = gain_;
  result.brightness = brightness_;
  result.residuals_used = finest.valid;
  result.information = finest.H;
  describe_fit(kf, frame, T_c_k, reference.photometric[0], &result);
  // Too few residuals left to constrain six degrees of freedom reliably.
  constexpr int kMinResiduals = 100;
  result.state = finest.valid >= kMinResiduals ? TrackingState::kOk : TrackingState::kLost;
  return result;
}

TrackResult Tracker::track_best(const Keyframe& kf, const FramePyramid& frame,
                                const SE3* T_k_c_guesses, int count,
                                const ReferenceScales& reference, uint8_t terms) {
  const int coarsest = kPyramidLevels - 1;
  terms_ = terms;
  SE3 best_T_c_k = T_k_c_guesses[0].inverse();
  double best_cost = -1.0;
  int iterations = 0;
  for (int i = 0; i < count; ++i) {
    SE3 T_c_k = T_k_c_guesses[i].inverse();
    gain_ = 1.f;
    brightness_ = 0.f;
    // Refined as tracking does, each term scaled by its own residuals so that a misaligned
    // guess still feels the pull of the data; a few iterations tell a guess in the basin from
    // one outside it.
    constexpr int kScreeningIterations = 5;
    (void)optimize_level(kf, frame, coarsest, &T_c_k, true, kScreeningIterations, &iterations);
    // Compared at the same fixed scales: a scale re-estimated from a bad guess's own residuals
    // would make its cost look small.
    if (reference.photometric[coarsest] > 0.f) ph_sigma_ = reference.photometric[coarsest];
    geo_scale_ = 1.f;
    const LevelCost c = evaluate_level(kf, frame, coarsest, T_c_k, false);
    // How well the points in view fit (as DSO compares its tries): a guess that turns the
    // camera away from the keyframe is not worse for it. A few lucky points do not count.
    constexpr int kMinInViewFraction = 4;  // a quarter
    if (c.valid * kMinInViewFraction < c.total) continue;
    const double cost = c.valid_cost / c.valid;
    if (best_cost < 0.0 || cost < best_cost) {
      best_cost = cost;
      best_T_c_k = T_c_k;
    }
  }
  TrackResult result = track(kf, frame, best_T_c_k.inverse(), reference, terms);
  result.iterations += iterations;
  return result;
}

namespace {
struct Spread {
  double n = 0, sum = 0, sum2 = 0;
  void add(double v) {
    n += 1;
    sum += v;
    sum2 += v * v;
  }
  double std() const {
    return n > 1 ? std::sqrt(std::max(0.0, sum2 / n - (sum / n) * (sum / n))) : 0.0;
  }
};
}  // namespace

void Tracker::describe_fit(const Keyframe& kf, const FramePyramid& frame, const SE3& T_c_k,
                           float reference_sigma, TrackResult* out) {
  // The scratch buffers hold the finest level's evaluation at T_c_k.
  const FixedVector<TrackPoint>& ph = photometric_points(kf, 0);
  const FixedVector<TrackPoint>& geo = geometric_points(kf, frame, 0);
  const double sigma_ref = reference_sigma > 0.f ? reference_sigma : ph_sigma_;
  const bool inverse = opt_.residuals.geometric == GeometricMode::kInverseDepth;
  Spread intensities, depths;
  int m = 0, inliers = 0;
  for (int i = 0; i < ph.size(); ++i) {
    if (ph_sample_[i] == kInvalid) continue;
    const float r = ph_residual_[i];
    if (std::fabs(r) < kInlierSigmas * sigma_ref) ++inliers;
    intensities.add(ph[i].ref);
    scratch_[m++] = r;
  }
  if (m >= kMinScaleSamples && intensities.std() > 0.0) {
    out->photometric_agreement = mad_sigma(m) / intensities.std();
    out->photometric_inliers = static_cast<double>(inliers) / m;
  }
  m = 0;
  inliers = 0;
  for (int i = 0; i < geo.size(); ++i) {
    if (geo_sigma_[i] == 0.f) continue;
    const float r = geo_residual_[i];
    if (std::fabs(r) < kInlierSigmas * geo_sigma_[i]) ++inliers;
    depths.add(inverse ? geo[i].ref : 1.0 / geo[i].ref);
    scratch_[m++] = r;
  }
  if (m >= kMinScaleSamples && depths.std() > 0.0) {
    out->geometric_agreement = mad_sigma(m) / depths.std();
    out->geometric_inliers = static_cast<double>(inliers) / m;
  }
  // The pose's covariance is the inverse of the information (residuals in standard deviations).
  const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(out->information);
  if (ldlt.info() == Eigen::Success && out->information.trace() > 0.0) {
    const Eigen::Matrix<double, 6, 6> cov = ldlt.solve(Eigen::Matrix<double, 6, 6>::Identity());
    const Eigen::SelfAdjointEigenSolver<Matrix3d> t(cov.topLeftCorner<3, 3>(),
                                                    Eigen::EigenvaluesOnly);
    const Eigen::SelfAdjointEigenSolver<Matrix3d> r(cov.bottomRightCorner<3, 3>(),
                                                    Eigen::EigenvaluesOnly);
    out->translation_std_m = std::sqrt(std::max(0.0, t.eigenvalues().maxCoeff()));
    out->rotation_std_rad = std::sqrt(std::max(0.0, r.eigenvalues().maxCoeff()));
  } else {
    out->translation_std_m = out->rotation_std_rad = std::numeric_limits<double>::infinity();
  }
  motion_stats(kf, frame, T_c_k, &out->visible, &out->parallax);
  out->overlap = out->visible * ((out->terms & kPhotometricTerm) != 0 ? out->photometric_inliers
                                                                      : out->geometric_inliers);
}

void Tracker::motion_stats(const Keyframe& kf, const FramePyramid& frame, const SE3& T_c_k,
                           double* visible_fraction, double* parallax) {
  const FixedVector<TrackPoint>& pts =
      kf.photometric(0).size() > 0 ? kf.photometric(0) : kf.geometric[0];
  const PinholeIntrinsics& k = frame.intrinsics(0);
  const Projector full(T_c_k, k);
  const ImageF& image = frame.gray(0);
  const Vector3d t = T_c_k.translation();
  constexpr int kStride = 4;  // fractions and medians: a quarter of the points is plenty
  int visible = 0, n = 0;
  for (int i = 0; i < pts.size(); i += kStride) {
    const TrackPoint& p = pts[i];
    // The angle the point's line of sight turns through from the translation alone, |t| / z
    // to first order: the median over the points, so that near points in a corner of the view
    // do not cut short a keyframe whose far points still need baseline to be mapped.
    scratch_[n++] = static_cast<float>(t.norm() / p.z);
    float u, v, z;
    // In view; an occlusion test against the frame's depth flickers at depth edges (fr1_xyz,
    // all frames: 0.84 cm without it, 0.82-0.91 with it, keyframes made and reused more often).
    if (full.project(p, &u, &v, &z) && image.contains(u, v, 1.f)) ++visible;
  }
  if (n == 0) {
    *visible_fraction = *parallax = 0.0;
    return;
  }
  *visible_fraction = static_cast<double>(visible) / n;
  std::nth_element(&scratch_[0], &scratch_[0] + n / 2, &scratch_[0] + n);
  *parallax = scratch_[n / 2];
}

double Tracker::visible_at(const Keyframe& kf, const FramePyramid& frame, const SE3& T_k_c) {
  double visible = 0.0, parallax = 0.0;
  motion_stats(kf, frame, T_k_c.inverse(), &visible, &parallax);
  return visible;
}

}  // namespace rgbdtam
