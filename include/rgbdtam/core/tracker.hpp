#pragma once
// RGBDTAM tracking (Concha & Civera, IROS 2017, sec. IV): photometric error on Canny-edge
// points and a subsampled dense inverse-depth error, Geman-McClure weights on residuals scaled
// by their standard deviations, gain and brightness, inverse-compositional Gauss-Newton on
// SE(3) over a 4-level pyramid. All buffers are sized in allocate(); track() never allocates.

#include <cstdint>
#include <limits>
#include <memory>

#include "rgbdtam/core/canny.hpp"
#include "rgbdtam/core/fixed_vector.hpp"
#include "rgbdtam/core/pyramid.hpp"
#include "rgbdtam/core/residuals.hpp"
#include "rgbdtam/core/se3.hpp"
#include "rgbdtam/core/track_points.hpp"

namespace rgbdtam {

struct TrackerOptions {
  ResidualConfig residuals;
  int photometric_points_finest = 8991;  // x1/3 per coarser level (paper: up to 8K per keyframe)
  float gradient_top_fraction = 0.4f;    // photometric points keep the strongest 40 % gradients
  // Subsampled geometric points: one pixel in this many, per direction, finest first (paper:
  // every pixel at 80x60, one in 2, 3, 4 at the finer levels).
  int geometric_step[kPyramidLevels] = {4, 3, 2, 1};
  float canny_low = 20.f;  // Sobel-3 magnitude, 8-bit grey levels
  float canny_high = 60.f;
  // Finest first. Four at the two finest levels, as the authors' real-time mode: 0.88 cm
  // all-frames ATE on fr1_xyz at 6.8 ms median, against 0.84 cm at 8.1 ms with {6, 8}.
  int max_iterations[kPyramidLevels] = {4, 4, 10, 15};
  double min_relative_decrease = 1e-3;  // stop a level when the cost improves less than this
  double robust_c = 2.0;                // Geman-McClure scale, in standard deviations
  double geometric_weight = 1.0;        // lambda on the normalised geometric term
  double inverse_depth_sigma = 0.0023;  // sigma_rho = sigma_d / (f b), 1/m: the sensor model
  // The geometric term's scale follows its residuals' spread down to this (the disparity's
  // quantisation), 1/m.
  double inverse_depth_sigma_floor = 0.0002;
  // A new keyframe when less of the keyframe overlaps the frame (TrackResult::overlap) ...
  double keyframe_overlap = 0.85;
  // ... or when the camera has moved this fraction of the scene depth (the authors' code: 0.15).
  double keyframe_parallax = 0.15;
  bool gain_brightness = true;
  bool motion_model = true;
};

// A point of a keyframe's mapped depth, in the keyframe's camera frame, m.
struct MapPoint {
  float x, y, z;
};

// A shift of the keyframe's camera (keyframe frame, m) that sees what the keyframe sees: where a
// texture repeats along a surface (tiles, panels, brick), a frame fits as well one period away,
// so a pose against the keyframe is determined only up to its aliases (KeyframeAliasFinder).
struct KeyframeAliases {
  static constexpr int kMax = 8;
  Vector3d shift_k[kMax];
  int count = 0;
};

// A keyframe's residual points. Its photometric points are double-buffered: the mapper writes
// the fused map into the inactive set, and the tracker swaps the sets between frames once told
// the map is there. The telling, and which thread may touch what when, are the runtime's
// (KeyframePool); this type knows no threads.
struct Keyframe {
  uint32_t id = 0;
  int64_t timestamp_ns = 0;
  SE3 T_w_k;
  SE3 T_k_kd;  // its frame's depth camera (FramePyramid::T_c_d): the geometric points' frame
  Vector6d row_motion = Vector6d::Zero();  // its frame's rolling shutter (FramePyramid)
  TrackPoints photometric_sets[2][kPyramidLevels];
  TrackPoints geometric[kPyramidLevels];  // sensor depth only
  int active_photometric = 0;
  FixedVector<MapPoint> map_points;  // the mapper's fused edge map, with the inactive set
  KeyframeAliases aliases;

  const TrackPoints& photometric(int level) const {
    return photometric_sets[active_photometric][level];
  }
  TrackPoints* inactive_photometric() { return photometric_sets[1 - active_photometric]; }
  void swap_photometric() { active_photometric = 1 - active_photometric; }
  // Everything but the points (and the mapper's map), which the callers move or copy themselves;
  // the points then go to the first photometric set.
  void take_header_of(const Keyframe& from) {
    id = from.id;
    timestamp_ns = from.timestamp_ns;
    T_w_k = from.T_w_k;
    T_k_kd = from.T_k_kd;
    row_motion = from.row_motion;
    aliases = from.aliases;
    active_photometric = 0;
  }
};

// Selects a keyframe's residual points; owns its scratch images.
class KeyframeBuilder {
 public:
  // What allocate_keyframe reserves for one keyframe, in bytes, before allocating it.
  static size_t keyframe_bytes(const PinholeIntrinsics& finest, const TrackerOptions& opt);
  // The most points a keyframe holds at any level, in one set.
  static int most_points(const PinholeIntrinsics& finest, const TrackerOptions& opt);
  void allocate(const PinholeIntrinsics& finest, const TrackerOptions& opt);
  void allocate_keyframe(Keyframe* kf) const;
  // photometric_depth, when given, replaces the frame's sensor depth for the photometric points
  // (the geometric points always use the sensor's).
  void build(const FramePyramid& frame, uint32_t id, int64_t timestamp_ns, const SE3& T_w_k,
             Keyframe* kf, const FramePyramid* photometric_depth = nullptr);
  // Photometric points only, into sets[0 .. kPyramidLevels), from the frame's (fused) depth;
  // edges: the frame's level-0 Canny edges, already found when it became a keyframe.
  void build_photometric(const FramePyramid& frame, const ImageU8& edges, TrackPoints* sets);
  // Level-0 Canny edges of the last prepared frame.
  const ImageU8& edges() const { return edges_[0]; }

 private:
  // Edges, gradients and thresholds of every level; level-0 edges are detected unless given.
  void prepare(const FramePyramid& frame, const ImageU8* edges = nullptr);
  void select_photometric(const FramePyramid& frame, const FramePyramid& depth, int level,
                          TrackPoints* out);
  void select_geometric(const FramePyramid& frame, int level, TrackPoints* out);
  bool is_semidense_pixel(int level, int x, int y) const;

  TrackerOptions opt_;
  CannyDetector canny_;
  ImageU8 edges_[kPyramidLevels];  // level l: some Canny edge inside the pixel's 2^l block
  ImageF gx_[kPyramidLevels], gy_[kPyramidLevels];
  float gradient_threshold_[kPyramidLevels] = {};
};

enum class TrackingState : uint8_t { kOk = 0, kLost = 1 };

// The residual terms a track uses (those that have data: points, sensor depth).
enum TermMask : uint8_t {
  kPhotometricTerm = 1,
  kGeometricTerm = 2,
  kAllTerms = kPhotometricTerm | kGeometricTerm,
};

// Photometric scales of healthy frames, per pyramid level (finest first); 0 = not known yet.
struct ReferenceScales {
  float photometric[kPyramidLevels] = {};
};

// The tracker's answer and what its health is judged by, all at the finest level and final pose.
struct TrackResult {
  SE3 T_k_c;                                   // keyframe from current camera
  TrackingState state = TrackingState::kLost;  // kOk: enough residuals to constrain six DOF
  uint8_t terms = 0;                           // TermMask of the terms the estimate used
  double photometric_sigma = 0;                // robust scale of the finest level, intensity units
  float level_sigma[kPyramidLevels] = {};      // ... and of every level, finest first
  double gain = 1.0, brightness = 0.0;
  int iterations = 0;
  int residuals_used = 0;  // valid photometric + geometric
  // The keyframe's points that project into the image ...
  double visible = 0.0;
  // ... and of those, the fraction that still look as they did (the main term's inliers): the
  // part of the keyframe the frame still sees as it was, the paper's overlap. The authors' code
  // counts residuals below 0.2 in intensity; here the yardstick is the typical scale, which
  // does not grow with the misfit as the adaptive one does.
  double overlap = 0.0;
  // The camera's translation over the depth of the keyframe's points, |t| / z (median): the
  // angle their lines of sight turn through, the authors' "translational ratio".
  double parallax = 0.0;
  // Each used term's residual spread over the spread of what it compares (keyframe
  // intensities, inverse depths): 0 for a perfect fit, about sqrt(2) against an unrelated image.
  // Scale-free, so it needs no history. 0 when the term is unused or has no residuals.
  double photometric_agreement = 0.0, geometric_agreement = 0.0;
  // Fraction of each used term's valid residuals within 3 reference sigmas (1 without).
  double photometric_inliers = 1.0, geometric_inliers = 1.0;
  // One standard deviation of the pose along its worst direction, from the information.
  double translation_std_m = 0.0, rotation_std_rad = 0.0;
  // The sensor's depth leaves a direction of motion nearly free (planes sliding along planes:
  // its information there, translation counted in scene depths, under 1e-4 of its strongest),
  // so the pose along it rests on the image alone; and the standard deviation along that
  // direction, as a displacement at the scene's depth. From the information (uncalibrated).
  bool depth_degenerate = false;
  double weak_direction_std_m = 0.0;
  // The twist (v, omega) that moves the scene 1 m at its depth along the direction the depth
  // determines worst (whether or not degenerate); zero without the depth term.
  Vector6d weak_direction = Vector6d::Zero();
  // The directions of translation (camera frame, unit columns) the depth term determines least
  // to most: the surfaces' own directions first, along which a texture painted on them
  // repeats. The camera's axes without the depth term.
  Matrix3d depth_translation_axes = Matrix3d::Identity();
  // Finest-level J^T W J of the used terms, perturbation delta in T_c_k exp(-delta), (v, omega).
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
};

class Tracker {
 public:
  // What allocate() takes for a keyframe of this camera and these options, in bytes.
  static size_t scratch_bytes(const PinholeIntrinsics& finest, const TrackerOptions& opt);
  void allocate(const Keyframe& capacity_model, const TrackerOptions& opt);
  // reference: the yardstick for inliers; the solver itself scales each term by its own
  // residuals. terms: a subset of the configured residuals (a term without data is left
  // out anyway).
  TrackResult track(const Keyframe& kf, const FramePyramid& frame, const SE3& T_k_c_guess,
                    const ReferenceScales& reference, uint8_t terms = kAllTerms);
  // Tracking's coarse-to-fine refinement from a guess, stopped after `finest_level`: where the
  // coarse levels take it.
  SE3 align(const Keyframe& kf, const FramePyramid& frame, const SE3& T_k_c_guess, uint8_t terms,
            int finest_level);
  // A wider basin: each guess is refined at the coarsest level, and the one whose points in
  // view fit best at the reference scales is tracked through the pyramid.
  TrackResult track_best(const Keyframe& kf, const FramePyramid& frame, const SE3* T_k_c_guesses,
                         int count, const ReferenceScales& reference, uint8_t terms = kAllTerms);
  // A cut through the cost: at T_k_c exp(s_i d) for each offset s_i, the mean cost of the
  // keyframe's points at `level` that have a residual there, and (if wanted) the fraction of
  // them that do, at the reference scales, without optimising.
  void profile(const Keyframe& kf, const FramePyramid& frame, const SE3& T_k_c, const Vector6d& d,
               const double* offsets, int n, int level, const ReferenceScales& reference,
               uint8_t terms, double* mean_cost, double* valid_fraction = nullptr);
  // The visible fraction of the keyframe's points at a pose, without optimising: cheap enough
  // to rank several keyframes.
  double visible_at(const Keyframe& kf, const FramePyramid& frame, const SE3& T_k_c);
  // Two poses compared on the same evidence: the mean robust cost, at each, of the keyframe's
  // points at `level` that have a residual at both, at the reference scales, without optimising
  // (infinite when none has). A mean over each pose's own points in view favours the pose that
  // sees less of the keyframe, its best-fitting part.
  void fit_on_common_points(const Keyframe& kf, const FramePyramid& frame, const SE3& T_k_a,
                            const SE3& T_k_b, int level, const ReferenceScales& reference,
                            uint8_t terms, double* cost_a, double* cost_b);

 private:
  struct LevelCost {
    double cost = 0.0;        // a point without a residual costs the kernel's maximum
    double valid_cost = 0.0;  // the points with residuals only
    int valid = 0;
    int total = 0;
    Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 6> H_geometric = Eigen::Matrix<double, 6, 6>::Zero();  // its part
    Vector6d g = Vector6d::Zero();
    bool has_normal_equations = false;  // H and g are formed
    double mean_valid_cost() const {
      return valid > 0 ? valid_cost / valid : std::numeric_limits<double>::infinity();
    }
  };
  LevelCost evaluate_level(const Keyframe& kf, const FramePyramid& frame, int level,
                           const SE3& T_c_k, bool new_scale);
  const TrackPoints& photometric_points(const Keyframe& kf, int level) const;
  const TrackPoints& geometric_points(const Keyframe& kf, const FramePyramid& frame,
                                      int level) const;
  // Gauss-Newton from the coarsest level down to `finest_level` from T_c_k, with the gain and
  // brightness reset; the finest level's cost.
  LevelCost optimize_levels(const Keyframe& kf, const FramePyramid& frame, int finest_level,
                            SE3* T_c_k, TrackResult* result);
  // Gauss-Newton on one level from T_c_k; the scratch buffers end at the returned pose.
  LevelCost optimize_level(const Keyframe& kf, const FramePyramid& frame, int level, SE3* T_c_k,
                           bool new_scale, int max_iterations, int* iterations);
  void describe_fit(const Keyframe& kf, const FramePyramid& frame, const SE3& T_c_k,
                    float reference_sigma, TrackResult* out);
  void describe_depth_degeneracy(const TrackPoints& geo, const Eigen::Matrix<double, 6, 6>& H_geo,
                                 TrackResult* out);
  void motion_stats(const Keyframe& kf, const FramePyramid& frame, const SE3& T_c_k,
                    double* visible, double* parallax);
  // Projects every point at the level: u, v and 1/z into proj_*; u = kOutside where the point
  // is behind the camera or out of the image's bilinear range. row_motion: the frame's rolling
  // shutter (FramePyramid::set_row_motion), zero for none.
  void project(const TrackPoints& pts, const PinholeIntrinsics& k, int width_px, int height_px,
               const SE3& T_c_k, const Vector6d& row_motion);
  void sample_photometric(const TrackPoints& pts, const ImageF& img);
  void sample_geometric(const TrackPoints& pts, const ImageF& inv_depth);
  void gather(const ImageF& img, int n);  // corners_ at proj_offset_
  void estimate_gain_brightness(const TrackPoints& pts);
  float mad_sigma(int count);
  void update_scales(int level, int n_photometric, int n_geometric);
  // The term's rows (row_weight_[term], row_residual_[term]; photometric 0, geometric 1) and
  // costs (point_cost_) from its residuals; returns how many points have one.
  int weigh(const TrackPoints& pts, bool geometric);
  LevelCost measure(const TrackPoints& ph, const TrackPoints& geo);
  void add_normal_equations_of(const TrackPoints& ph, const TrackPoints& geo, LevelCost* c);

  TrackerOptions opt_;
  const TrackPoints no_points_{};  // stands in for the geometric set without depth
  // Per-point scratch, indexed like the keyframe's point sets, padded like them.
  std::unique_ptr<float[]> proj_u_;  // kInvalid marks a point out of view
  std::unique_ptr<float[]> proj_inverse_z_;
  // The top-left pixel of each projection in the level, and the bilinear weights beyond it.
  std::unique_ptr<int32_t[]> proj_offset_;
  std::unique_ptr<float[]> proj_fraction_u_, proj_fraction_v_;
  std::unique_ptr<float[]> ph_sample_, ph_residual_, geo_residual_;
  std::unique_ptr<float[]> geo_inverse_sigma_;  // 0 where a point has no residual
  std::unique_ptr<float[]> corners_[4];         // the pixels around each projection
  // The normal equations' rows of each term at the last measured evaluation, and the costs.
  std::unique_ptr<float[]> row_weight_[2], row_residual_[2], point_cost_;
  std::unique_ptr<float[]> scratch_;  // medians
  // fit_on_common_points: each term's point costs at the first pose, NaN without a residual.
  std::unique_ptr<float[]> first_pose_cost_[2];
  float gain_ = 1.f, brightness_ = 0.f, ph_sigma_ = 0.05f;
  float geo_scale_ = 1.f;      // geometric spread in sensor-model standard deviations
  uint8_t terms_ = kAllTerms;  // of the current track
  // The frame's rows' motions the evaluations use: while optimising, those the pose each level
  // starts from implies (FramePyramid::row_motions_at), fixed within the level; the fixed ones
  // when poses are compared.
  RowMotions rows_;
};

}  // namespace rgbdtam
