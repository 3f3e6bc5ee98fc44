#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include <Eigen/Cholesky>

#include "rgbdtam/core/kth_smallest.hpp"
#include "rgbdtam/core/lanes.hpp"
#include "rgbdtam/core/rolling_shutter.hpp"
#include "rgbdtam/core/symmetric_eigen.hpp"
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
  bool project(float x, float y, float z, float* u, float* v) const {
    const float qx = r[0] * x + r[1] * y + r[2] * z + t[0];
    const float qy = r[3] * x + r[4] * y + r[5] * z + t[1];
    const float qz = r[6] * x + r[7] * y + r[8] * z + t[2];
    if (qz < kMinDepthM) return false;
    pinhole.project_inverse_depth(qx, qy, 1.f / qz, u, v);
    return true;
  }
};

// Where points x, y, z project: u (kInvalid where a point is behind the camera or outside
// [1, u_max] x [1, v_max]), 1/z, the offset of the pixel at the top left of (u, v) in an image
// `stride_px` wide and (u, v)'s fractions beyond it, the bilinear weights; for a point out of
// view, those of the nearest pixel in view. kRolling: each point seen from the camera of the
// row it projects to (that row found from the middle row's projection: one step).
template <bool kRolling>
void project_points(const Projector& P, const RowMotion& rows, const float* __restrict X,
                    const float* __restrict Y, const float* __restrict Z, int n, float u_max,
                    float v_max, float stride_px, float* __restrict u, float* __restrict inverse_z,
                    int32_t* __restrict offset, float* __restrict fraction_u,
                    float* __restrict fraction_v) {
  const float r0 = P.r[0], r1 = P.r[1], r2 = P.r[2], r3 = P.r[3], r4 = P.r[4], r5 = P.r[5];
  const float r6 = P.r[6], r7 = P.r[7], r8 = P.r[8], t0 = P.t[0], t1 = P.t[1], t2 = P.t[2];
  const float fx = P.pinhole.fx, fy = P.pinhole.fy, cx = P.pinhole.cx, cy = P.pinhole.cy;
  for (int i = 0; i < n; ++i) {
    float qx = r0 * X[i] + r1 * Y[i] + r2 * Z[i] + t0;
    float qy = r3 * X[i] + r4 * Y[i] + r5 * Z[i] + t1;
    float qz = r6 * X[i] + r7 * Y[i] + r8 * Z[i] + t2;
    if constexpr (kRolling) rows.move(-rows.from_middle(fy * qy / qz + cy), &qx, &qy, &qz);
    const float iz = 1.f / qz;
    const float ui = fx * qx * iz + cx;  // Pinhole::project_inverse_depth
    const float vi = fy * qy * iz + cy;
    const bool in_view =
        (qz >= kMinDepthM) & (ui >= 1.f) & (vi >= 1.f) & (ui <= u_max) & (vi <= v_max);
    u[i] = in_view ? ui : kInvalid;
    inverse_z[i] = iz;
    // Clamped into the image without branches (a NaN becomes 0), and in float, which SSE2
    // converts four at a time: exact below 2^24 pixels. Stored whether in view or not: GCC
    // does not vectorise a choice of a converted value on aarch64.
    const float uc = std::min(u_max, std::max(0.f, ui));
    const float vc = std::min(v_max, std::max(0.f, vi));
    const float column = static_cast<float>(static_cast<int>(uc));
    const float row = static_cast<float>(static_cast<int>(vc));
    offset[i] = static_cast<int32_t>(row * stride_px + column);
    fraction_u[i] = uc - column;
    fraction_v[i] = vc - row;
  }
}

// The 2x2 pixels whose top left is at each offset: a scalar loop (SSE2 and NEON have no
// gather), without branches; what the points out of view read is masked by their callers.
void gather_corners(const ImageF& img, const int32_t* __restrict offset, int n,
                    float* __restrict c00, float* __restrict c01, float* __restrict c10,
                    float* __restrict c11) {
  const float* pixels = img.data();
  const int below = img.width();
  for (int i = 0; i < n; ++i) {
    const float* p = pixels + offset[i];
    c00[i] = p[0];
    c01[i] = p[1];
    c10[i] = p[below];
    c11[i] = p[below + 1];
  }
}

// The geometric residuals from the four inverse depths around each projection: where it is in
// view and they agree (no depth edge), the bilinear inverse depth against the point's, in
// inverse depth or in depth; inverse_sigma 0 marks a point without residual.
void geometric_residuals(const float* __restrict c00, const float* __restrict c01,
                         const float* __restrict c10, const float* __restrict c11,
                         const float* __restrict u, const float* __restrict fraction_u,
                         const float* __restrict fraction_v, const float* __restrict inverse_z,
                         int n, bool inverse, float sigma_rho, float* __restrict residual,
                         float* __restrict inverse_sigma) {
  for (int i = 0; i < n; ++i) {
    const float a = c00[i], b = c01[i], c = c10[i], d = c11[i];
    const float lo = std::min(std::min(a, b), std::min(c, d));
    const float hi = std::max(std::max(a, b), std::max(c, d));
    const bool ok = (u[i] != kInvalid) & (lo > 0.f) & (lo >= kDepthAgreement * hi);
    const float rho = bilinear(a, b, c, d, fraction_u[i], fraction_v[i]);
    const float depth = 1.f / rho;
    const float r = inverse ? inverse_z[i] - rho : 1.f / inverse_z[i] - depth;
    // sigma_z = z^2 sigma_d / (f b) for the depth residual
    const float sigma = inverse ? sigma_rho : sigma_rho * depth * depth;
    residual[i] = ok ? r : 0.f;
    inverse_sigma[i] = ok ? 1.f / sigma : 0.f;
  }
}

// Sums kLanes interleaved partial sums, so that the compiler may vectorise a float reduction
// without reordering it; blocks of points are summed in float and the blocks in double.
constexpr int kSumBlock = 256;
static_assert(TrackPoints::kBlock % kLanes == 0 && kSumBlock % TrackPoints::kBlock == 0,
              "lanes tile the padded point arrays");

double sum_padded(const float* v, int n_padded) {
  double total = 0.0;
  for (int start = 0; start < n_padded; start += kSumBlock) {
    const int end = std::min(start + kSumBlock, n_padded);
    float lane[kLanes] = {};
    for (int i = start; i < end; i += kLanes) {
      for (int l = 0; l < kLanes; ++l) lane[l] += v[i + l];
    }
    for (const float s : lane) total += s;
  }
  return total;
}

double fold_lanes(Lanes v) { return (v[0] + v[1]) + (v[2] + v[3]); }

// Normal equations sum_i w_i J_i J_i^T and sum_i b_i J_i over the points' keyframe-side
// Jacobians (structure of arrays), in one pass: each point's eight values are loaded once into
// 27 running sums (21 of H, 6 of g), which a 32-register NEON core keeps in registers; a dot
// product per sum would load each row up to seven times, and the A72 has one load pipe. Lane by
// lane the sums are the dot products' (float within a block, double across blocks).
void add_normal_equations(const TrackPoints& pts, const float* w, const float* b, double scale,
                          Eigen::Matrix<double, 6, 6>* H, Vector6d* g) {
  const int n = pts.padded_size();
  const float* J[6];
  for (int r = 0; r < 6; ++r) J[r] = pts.J(r);
  for (int start = 0; start < n; start += kSumBlock) {
    const int end = std::min(start + kSumBlock, n);
    Lanes h[21] = {}, gl[6] = {};
    for (int i = start; i < end; i += kLanes) {
      Lanes j[6];
      for (int r = 0; r < 6; ++r) j[r] = load_lanes(J[r] + i);
      const Lanes wi = load_lanes(w + i), bi = load_lanes(b + i);
      int k = 0;
      for (int r = 0; r < 6; ++r) {
        const Lanes wj = wi * j[r];
        for (int c = r; c < 6; ++c) h[k++] += wj * j[c];
        gl[r] += bi * j[r];
      }
    }
    int k = 0;
    for (int r = 0; r < 6; ++r) {
      for (int c = r; c < 6; ++c) {
        const double v = scale * fold_lanes(h[k++]);
        (*H)(r, c) += v;
        if (c != r) (*H)(c, r) += v;
      }
      (*g)(r) += scale * fold_lanes(gl[r]);
    }
  }
}

// Geman-McClure: rho(x) = x^2 / (2 (1 + x^2/c^2)), weight = rho'(x)/x = 1 / (1 + x^2/c^2)^2.
struct GemanMcClure {
  float inv_c2;
  explicit GemanMcClure(double c) : inv_c2(static_cast<float>(1.0 / (c * c))) {}
  double saturated_cost() const { return 0.5 / inv_c2; }
};

// One term's rows: for residual r_i with standard deviation 1/inv_sigma_i (valid where
// inv_sigma_i > 0), x = r inv_sigma, the row weight w inv_sigma^2 and w x inv_sigma, and the
// point's cost; a point without residual costs the kernel's maximum. Returns the valid count.
int weigh_rows(const float* __restrict residual, const float* __restrict inv_sigma, int n_padded,
               const GemanMcClure& gm, float* __restrict row_weight, float* __restrict row_residual,
               float* __restrict cost) {
  const float saturated = static_cast<float>(gm.saturated_cost());
  const float inv_c2 = gm.inv_c2;
  int valid = 0;
  for (int i = 0; i < n_padded; ++i) {
    // Without residual, s = 0, so x and both rows are 0.
    const float s = inv_sigma[i];
    const float x = residual[i] * s;
    const float d = 1.f + x * x * inv_c2;
    const float ws = s / (d * d);
    row_weight[i] = ws * s;
    row_residual[i] = ws * x;
    const bool ok = s > 0.f;
    cost[i] = ok ? 0.5f * x * x / d : saturated;
    valid += ok ? 1 : 0;
  }
  return valid;
}
}  // namespace

size_t Tracker::scratch_bytes(const PinholeIntrinsics& finest, const TrackerOptions& opt) {
  // 20 float buffers and one of offsets, a slot per point (allocate()).
  constexpr size_t kBuffers = 21;
  const int n = TrackPoints::round_up(std::max(1, KeyframeBuilder::most_points(finest, opt)),
                                      TrackPoints::kBlock);
  return kBuffers * sizeof(float) * static_cast<size_t>(n);
}

void Tracker::allocate(const Keyframe& model, const TrackerOptions& opt) {
  opt_ = opt;
  int n = 1;
  for (int l = 0; l < kPyramidLevels; ++l) {
    n = std::max(n, model.photometric(l).capacity());
    n = std::max(n, model.geometric[l].capacity());
  }
  n = TrackPoints::round_up(n, TrackPoints::kBlock);
  for (auto* buffer :
       {&proj_u_,        &proj_fraction_u_, &proj_fraction_v_,    &proj_inverse_z_,
        &ph_sample_,     &ph_residual_,     &geo_residual_,       &geo_inverse_sigma_,
        &corners_[0],    &corners_[1],      &corners_[2],         &corners_[3],
        &row_weight_[0], &row_weight_[1],   &row_residual_[0],    &row_residual_[1],
        &point_cost_,    &scratch_,         &first_pose_cost_[0], &first_pose_cost_[1]}) {
    buffer->reset(new float[static_cast<size_t>(n)]());
  }
  proj_offset_.reset(new int32_t[static_cast<size_t>(n)]());
}

void Tracker::project(const TrackPoints& pts, const PinholeIntrinsics& k, int width_px,
                      int height_px, const SE3& T_c_k, const Vector6d& row_motion) {
  const Projector P(T_c_k, k);
  const RowMotion rows(row_motion, height_px);
  // In view with the 1-px margin that bilinear sampling needs (Image::contains).
  const float u_max = static_cast<float>(width_px - 1) - 1.f;
  const float v_max = static_cast<float>(height_px - 1) - 1.f;
  auto project_all = row_motion.isZero() ? project_points<false> : project_points<true>;
  project_all(P, rows, pts.x(), pts.y(), pts.z(), pts.padded_size(), u_max, v_max,
              static_cast<float>(width_px), proj_u_.get(), proj_inverse_z_.get(),
              proj_offset_.get(), proj_fraction_u_.get(), proj_fraction_v_.get());
  const int n = pts.padded_size();
  // The padding is never in view (its offsets, clamped, are in the image like any other).
  for (int i = pts.size(); i < n; ++i) proj_u_[i] = kInvalid;
}

void Tracker::gather(const ImageF& img, int n) {
  gather_corners(img, proj_offset_.get(), n, corners_[0].get(), corners_[1].get(),
                 corners_[2].get(), corners_[3].get());
}

void Tracker::sample_photometric(const TrackPoints& pts, const ImageF& img) {
  const int n = pts.padded_size();
  gather(img, n);
  const float* u = proj_u_.get();
  const float* fraction_u = proj_fraction_u_.get();
  const float* fraction_v = proj_fraction_v_.get();
  const float* c00 = corners_[0].get();
  const float* c01 = corners_[1].get();
  const float* c10 = corners_[2].get();
  const float* c11 = corners_[3].get();
  float* __restrict sample = ph_sample_.get();
  for (int i = 0; i < n; ++i) {
    const float s = bilinear(c00[i], c01[i], c10[i], c11[i], fraction_u[i], fraction_v[i]);
    sample[i] = u[i] == kInvalid ? kInvalid : s;
  }
}

void Tracker::estimate_gain_brightness(const TrackPoints& pts) {
  if (!opt_.gain_brightness) return;
  // Moment matching, a = std(I_kf) / std(I_cur), b = mean(I_kf) - a mean(I_cur): a least-squares
  // fit of I_kf on I_cur would be biased towards a = 0 (regression dilution), because edge
  // pixels make I_cur noisy under any misalignment.
  double n = 0, s_c = 0, s_k = 0, s_cc = 0, s_kk = 0;
  const float* ref = pts.ref();
  for (int i = 0; i < pts.size(); ++i) {
    const float c = ph_sample_[i];
    if (c == kInvalid) continue;
    const float kf = ref[i];
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
  float* first = scratch_.get();
  const float median = kth_smallest(first, m, m / 2);
  for (int i = 0; i < m; ++i) first[i] = std::fabs(first[i] - median);
  return kMadToSigma * kth_smallest(first, m, m / 2);
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
    if (geo_inverse_sigma_[i] != 0.f) scratch_[m++] = geo_residual_[i] * geo_inverse_sigma_[i];
  const float floor =
      level == 0 ? static_cast<float>(opt_.inverse_depth_sigma_floor / opt_.inverse_depth_sigma)
                 : 1.f;
  geo_scale_ = m >= kMinScaleSamples ? std::max(floor, mad_sigma(m)) : 1.f;
}

void Tracker::sample_geometric(const TrackPoints& pts, const ImageF& idepth) {
  const int n = pts.padded_size();
  gather(idepth, n);
  geometric_residuals(
      corners_[0].get(), corners_[1].get(), corners_[2].get(), corners_[3].get(), proj_u_.get(),
      proj_fraction_u_.get(), proj_fraction_v_.get(), proj_inverse_z_.get(), n,
      opt_.residuals.geometric == GeometricMode::kInverseDepth,
      static_cast<float>(opt_.inverse_depth_sigma), geo_residual_.get(), geo_inverse_sigma_.get());
}

int Tracker::weigh(const TrackPoints& pts, bool geometric) {
  // The photometric residuals share one scale; the geometric ones are each divided by their
  // sensor model, and all of them by the term's spread.
  float* inv_sigma = scratch_.get();
  const int n = pts.padded_size();
  if (geometric) {
    const float inv_scale = 1.f / geo_scale_;
    for (int i = 0; i < n; ++i) inv_sigma[i] = geo_inverse_sigma_[i] * inv_scale;
  } else {
    const float inv_ph_sigma = 1.f / ph_sigma_;
    for (int i = 0; i < n; ++i) inv_sigma[i] = ph_sample_[i] == kInvalid ? 0.f : inv_ph_sigma;
  }
  const float* residual = geometric ? geo_residual_.get() : ph_residual_.get();
  return weigh_rows(residual, inv_sigma, n, GemanMcClure(opt_.robust_c),
                    row_weight_[geometric].get(), row_residual_[geometric].get(),
                    point_cost_.get());
}

Tracker::LevelCost Tracker::measure(const TrackPoints& ph, const TrackPoints& geo) {
  LevelCost out;
  const double saturated = GemanMcClure(opt_.robust_c).saturated_cost();
  const int valid_ph = weigh(ph, false);
  const double cost_ph = sum_padded(point_cost_.get(), ph.padded_size());
  const int valid_geo = weigh(geo, true);
  const double cost_geo = sum_padded(point_cost_.get(), geo.padded_size());
  // The padding counts as points without residual; their saturated cost is taken back out.
  const int invalid_ph = ph.size() - valid_ph;
  const int invalid_geo = geo.size() - valid_geo;
  const double padding =
      (ph.padded_size() - ph.size()) + opt_.geometric_weight * (geo.padded_size() - geo.size());
  out.valid = valid_ph + valid_geo;
  out.cost = cost_ph + opt_.geometric_weight * cost_geo - saturated * padding;
  out.valid_cost = out.cost - saturated * (invalid_ph + opt_.geometric_weight * invalid_geo);
  out.total = ph.size() + geo.size();
  return out;
}

void Tracker::add_normal_equations_of(const TrackPoints& ph, const TrackPoints& geo, LevelCost* c) {
  // The rows measure() weighed for this evaluation: the scratch buffers hold it.
  c->H.setZero();
  c->H_geometric.setZero();
  c->g.setZero();
  add_normal_equations(ph, row_weight_[0].get(), row_residual_[0].get(), 1.0, &c->H, &c->g);
  add_normal_equations(geo, row_weight_[1].get(), row_residual_[1].get(), opt_.geometric_weight,
                       &c->H_geometric, &c->g);
  c->H += c->H_geometric;
  c->has_normal_equations = true;
}

const TrackPoints& Tracker::photometric_points(const Keyframe& kf, int level) const {
  return (terms_ & kPhotometricTerm) != 0 ? kf.photometric(level) : no_points_;
}

const TrackPoints& Tracker::geometric_points(const Keyframe& kf, const FramePyramid& frame,
                                             int level) const {
  return (terms_ & kGeometricTerm) != 0 && frame.has_depth() ? kf.geometric[level] : no_points_;
}

Tracker::LevelCost Tracker::evaluate_level(const Keyframe& kf, const FramePyramid& frame, int level,
                                           const SE3& T_c_k, bool new_scale) {
  const TrackPoints& ph = photometric_points(kf, level);
  const TrackPoints& geo = geometric_points(kf, frame, level);
  const PinholeIntrinsics& k = frame.intrinsics(level);
  const ImageF& img = frame.gray(level);
  project(ph, k, img.width(), img.height(), T_c_k, rows_.colour);
  sample_photometric(ph, img);
  estimate_gain_brightness(ph);
  const float* ref = ph.ref();
  for (int i = 0; i < ph.padded_size(); ++i) {
    const float s = ph_sample_[i];
    ph_residual_[i] = s == kInvalid ? 0.f : gain_ * s + brightness_ - ref[i];
  }
  // From the keyframe's depth camera to the frame's: each depth image as taken. The keyframe-side
  // Jacobians stay those of T_c_k, off by the adjoint of a few milliseconds' motion.
  project(geo, k, img.width(), img.height(), frame.T_c_d().inverse() * T_c_k * kf.T_k_kd,
          rows_.depth);
  sample_geometric(geo, frame.inverse_depth(level));
  if (new_scale) update_scales(level, ph.size(), geo.size());
  return measure(ph, geo);
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
  const TrackPoints& ph = photometric_points(kf, level);
  const TrackPoints& geo = geometric_points(kf, frame, level);
  for (int it = 0; it < max_iterations; ++it) {
    if (current.valid < 6) break;
    // Formed only for a pose a step is taken from: a rejected or final evaluation needs none.
    if (!current.has_normal_equations) add_normal_equations_of(ph, geo, &current);
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
  LevelCost finest = optimize_levels(kf, frame, 0, &T_c_k, &result);
  if (!finest.has_normal_equations) {
    add_normal_equations_of(photometric_points(kf, 0), geometric_points(kf, frame, 0), &finest);
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
  describe_depth_degeneracy(geometric_points(kf, frame, 0), finest.H_geometric, &result);
  // Too few residuals left to constrain six degrees of freedom reliably.
  constexpr int kMinResiduals = 100;
  result.state = finest.valid >= kMinResiduals ? TrackingState::kOk : TrackingState::kLost;
  return result;
}

Tracker::LevelCost Tracker::optimize_levels(const Keyframe& kf, const FramePyramid& frame,
                                            int finest_level, SE3* T_c_k, TrackResult* result) {
  gain_ = 1.f;
  brightness_ = 0.f;
  LevelCost cost;
  for (int level = kPyramidLevels - 1; level >= finest_level; --level) {
    rows_ = frame.row_motions_at(kf.T_w_k * T_c_k->inverse());
    cost = optimize_level(kf, frame, level, T_c_k, true, opt_.max_iterations[level],
                          &result->iterations);
    result->level_sigma[level] = ph_sigma_;
  }
  return cost;
}

SE3 Tracker::align(const Keyframe& kf, const FramePyramid& frame, const SE3& T_k_c_guess,
                   uint8_t terms, int finest_level) {
  terms_ = terms;
  SE3 T_c_k = T_k_c_guess.inverse();
  TrackResult unused;
  (void)optimize_levels(kf, frame, finest_level, &T_c_k, &unused);
  return T_c_k.inverse();
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
    rows_ = frame.row_motions_at(kf.T_w_k * T_k_c_guesses[i]);
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

void Tracker::profile(const Keyframe& kf, const FramePyramid& frame, const SE3& T_k_c,
                      const Vector6d& d, const double* offsets, int n, int level,
                      const ReferenceScales& reference, uint8_t terms, double* mean_cost,
                      double* valid_fraction) {
  terms_ = terms;
  rows_ = frame.fixed_row_motions();  // every pose compared on the same rows
  for (int i = 0; i < n; ++i) {
    if (reference.photometric[level] > 0.f) ph_sigma_ = reference.photometric[level];
    geo_scale_ = 1.f;
    gain_ = 1.f;
    brightness_ = 0.f;
    const SE3 T = T_k_c * SE3::exp(d * offsets[i]);
    const LevelCost c = evaluate_level(kf, frame, level, T.inverse(), false);
    mean_cost[i] = c.mean_valid_cost();
    if (valid_fraction != nullptr)
      valid_fraction[i] = c.total > 0 ? double(c.valid) / c.total : 0.0;
  }
}

void Tracker::fit_on_common_points(const Keyframe& kf, const FramePyramid& frame, const SE3& T_k_a,
                                   const SE3& T_k_b, int level, const ReferenceScales& reference,
                                   uint8_t terms, double* cost_a, double* cost_b) {
  terms_ = terms;
  rows_ = frame.fixed_row_motions();  // both poses compared on the same rows
  const TrackPoints* sets[2] = {&photometric_points(kf, level),
                                &geometric_points(kf, frame, level)};
  const double weights[2] = {1.0, opt_.geometric_weight};
  double sum[2] = {0.0, 0.0}, weight = 0.0;
  for (int pose = 0; pose < 2; ++pose) {
    if (reference.photometric[level] > 0.f) ph_sigma_ = reference.photometric[level];
    geo_scale_ = 1.f;
    gain_ = 1.f;
    brightness_ = 0.f;
    (void)evaluate_level(kf, frame, level, (pose == 0 ? T_k_a : T_k_b).inverse(), false);
    for (int term = 0; term < 2; ++term) {
      const TrackPoints& pts = *sets[term];
      (void)weigh(pts, term == 1);
      float* first = first_pose_cost_[term].get();
      for (int i = 0; i < pts.size(); ++i) {
        const bool has_residual =
            term == 0 ? ph_sample_[i] != kInvalid : geo_inverse_sigma_[i] != 0.f;
        if (pose == 0) {
          first[i] = has_residual ? point_cost_[i] : std::numeric_limits<float>::quiet_NaN();
        } else if (has_residual && !std::isnan(first[i])) {
          sum[0] += weights[term] * first[i];
          sum[1] += weights[term] * point_cost_[i];
          weight += weights[term];
        }
      }
    }
  }
  const double none = std::numeric_limits<double>::infinity();
  *cost_a = weight > 0.0 ? sum[0] / weight : none;
  *cost_b = weight > 0.0 ? sum[1] / weight : none;
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
  const TrackPoints& ph = photometric_points(kf, 0);
  const TrackPoints& geo = geometric_points(kf, frame, 0);
  const double sigma_ref = reference_sigma > 0.f ? reference_sigma : ph_sigma_;
  const bool inverse = opt_.residuals.geometric == GeometricMode::kInverseDepth;
  Spread intensities, depths;
  int m = 0, inliers = 0;
  for (int i = 0; i < ph.size(); ++i) {
    if (ph_sample_[i] == kInvalid) continue;
    const float r = ph_residual_[i];
    if (std::fabs(r) < kInlierSigmas * sigma_ref) ++inliers;
    intensities.add(ph.ref()[i]);
    scratch_[m++] = r;
  }
  if (m >= kMinScaleSamples && intensities.std() > 0.0) {
    out->photometric_agreement = mad_sigma(m) / intensities.std();
    out->photometric_inliers = static_cast<double>(inliers) / m;
  }
  m = 0;
  inliers = 0;
  for (int i = 0; i < geo.size(); ++i) {
    if (geo_inverse_sigma_[i] == 0.f) continue;
    const float r = geo_residual_[i];
    if (std::fabs(r) * geo_inverse_sigma_[i] < kInlierSigmas) ++inliers;
    depths.add(inverse ? geo.ref()[i] : 1.0 / geo.ref()[i]);
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
    const Matrix3d cov_t = cov.topLeftCorner<3, 3>(), cov_r = cov.bottomRightCorner<3, 3>();
    out->translation_std_m = std::sqrt(std::max(0.0, symmetric_eigen(cov_t).values(2)));
    out->rotation_std_rad = std::sqrt(std::max(0.0, symmetric_eigen(cov_r).values(2)));
  } else {
    out->translation_std_m = out->rotation_std_rad = std::numeric_limits<double>::infinity();
  }
  motion_stats(kf, frame, T_c_k, &out->visible, &out->parallax);
  out->overlap = out->visible * ((out->terms & kPhotometricTerm) != 0 ? out->photometric_inliers
                                                                      : out->geometric_inliers);
}

void Tracker::describe_depth_degeneracy(const TrackPoints& geo,
                                        const Eigen::Matrix<double, 6, 6>& H_geo,
                                        TrackResult* out) {
  // Real scenes give the depth term a condition number of 100-300 in these units (fr1_xyz,
  // fr3_teddy); plain planes, 6e4 and more (a corridor: its axis; a wall: three directions).
  constexpr double kDegenerate = 1e-4;
  constexpr int kStride = 8;  // the median depth of a sample
  out->depth_degenerate = false;
  out->weak_direction_std_m = 0.0;
  out->weak_direction.setZero();
  out->depth_translation_axes.setIdentity();
  if ((out->terms & kGeometricTerm) != 0 && H_geo.topLeftCorner<3, 3>().trace() > 0.0) {
    // Translation alone: sensor noise gives every direction some information from a plane's
    // gradients, which turns the six-dimensional weakest direction, but not these.
    const Matrix3d H_t = H_geo.topLeftCorner<3, 3>();
    out->depth_translation_axes = symmetric_eigen(H_t).vectors;
  }
  int n = 0;
  for (int i = 0; i < geo.size(); i += kStride) scratch_[n++] = geo.z()[i];
  if ((out->terms & kGeometricTerm) == 0 || n == 0 || !(H_geo.trace() > 0.0)) return;
  std::nth_element(scratch_.get(), scratch_.get() + n / 2, scratch_.get() + n);
  const double depth = scratch_[n / 2];
  // Translation in scene depths, so that a shift and a turn that move the scene alike count
  // alike.
  Vector6d s;
  s << depth, depth, depth, 1.0, 1.0, 1.0;
  const SymmetricEigen<6> geometric =
      symmetric_eigen(Matrix6d(s.asDiagonal() * H_geo * s.asDiagonal()));
  const Vector6d& e = geometric.values;
  const Vector6d u = geometric.vectors.col(0);
  out->weak_direction = s.asDiagonal() * u / depth;
  if (!(e(0) < kDegenerate * e(5))) return;
  out->depth_degenerate = true;
  const double information = u.dot(s.asDiagonal() * out->information * s.asDiagonal() * u);
  out->weak_direction_std_m =
      information > 0.0 ? depth / std::sqrt(information) : std::numeric_limits<double>::infinity();
}

void Tracker::motion_stats(const Keyframe& kf, const FramePyramid& frame, const SE3& T_c_k,
                           double* visible_fraction, double* parallax) {
  const TrackPoints& pts = kf.photometric(0).size() > 0 ? kf.photometric(0) : kf.geometric[0];
  const PinholeIntrinsics& k = frame.intrinsics(0);
  const Projector full(T_c_k, k);
  const ImageF& image = frame.gray(0);
  const Vector3d t = T_c_k.translation();
  constexpr int kStride = 4;  // fractions and medians: a quarter of the points is plenty
  int visible = 0, n = 0;
  for (int i = 0; i < pts.size(); i += kStride) {
    const float x = pts.x()[i], y = pts.y()[i], z = pts.z()[i];
    // The angle the point's line of sight turns through from the translation alone, |t| / z
    // to first order: the median over the points, so that near points in a corner of the view
    // do not cut short a keyframe whose far points still need baseline to be mapped.
    scratch_[n++] = static_cast<float>(t.norm() / z);
    float u, v;
    // In view; an occlusion test against the frame's depth flickers at depth edges (fr1_xyz,
    // all frames: 0.84 cm without it, 0.82-0.91 with it, keyframes made and reused more often).
    if (full.project(x, y, z, &u, &v) && image.contains(u, v, 1.f)) ++visible;
  }
  if (n == 0) {
    *visible_fraction = *parallax = 0.0;
    return;
  }
  *visible_fraction = static_cast<double>(visible) / n;
  std::nth_element(scratch_.get(), scratch_.get() + n / 2, scratch_.get() + n);
  *parallax = scratch_[n / 2];
}

double Tracker::visible_at(const Keyframe& kf, const FramePyramid& frame, const SE3& T_k_c) {
  double visible = 0.0, parallax = 0.0;
  motion_stats(kf, frame, T_k_c.inverse(), &visible, &parallax);
  return visible;
}

}  // namespace rgbdtam
