// rgbdtam-loop-bench views: what direct view alignment says about pairs of frames whose true
// relative pose is known, so that the acceptance test of a revisit is chosen by measurement.
// One CSV row per alignment: the pair, its ground-truth relative pose, the guess's error, the
// result's error, and every quantity an acceptance test could use.
#include "view_study.hpp"

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "frontend_frames.hpp"
#include "rgbdtam/core/view_alignment.hpp"
#include "rgbdtam/hal/tum_trajectory.hpp"

namespace rgbdtam {
namespace {

struct Sample {
  double t_s;
  SE3 T_w_c;
  View view;
};

bool truth_near(const std::vector<StampedPose>& gt, double t, SE3* T) {
  const StampedPose* best = nullptr;
  for (const StampedPose& p : gt) {
    if (best == nullptr || std::fabs(p.stamp_s - t) < std::fabs(best->stamp_s - t)) best = &p;
  }
  if (best == nullptr || std::fabs(best->stamp_s - t) > 0.02) return false;
  *T = best->T_w_c;
  return true;
}

bool load_samples(const std::string& sequence, const Params& params, int every,
                  std::vector<Sample>* out) {
  FrontendFrames frames;
  Status s = frames.open(sequence.c_str(), params);
  std::vector<StampedPose> gt;
  int bad = 0;
  if (s.is_ok()) s = read_tum_trajectory((sequence + "/groundtruth.txt").c_str(), &gt, &bad);
  if (!s.is_ok()) {
    std::fprintf(stderr, "rgbdtam-loop-bench: %s\n", s.message());
    return false;
  }
  for (int i = 0; i < frames.count(); i += every) {
    Sample sample;
    sample.t_s = frames.timestamp_ns(i) * 1e-9;
    if (!truth_near(gt, sample.t_s, &sample.T_w_c) || !frames.load(i)) continue;
    sample.view.allocate(params.camera);
    capture_view(frames.frame(), &sample.view);
    out->push_back(std::move(sample));
  }
  return true;
}

double angle_deg(const SE3& T) { return so3_log(T.quaternion()).norm() * 180.0 / M_PI; }

void print_row(const char* kind, const Sample& a, const Sample& b, const SE3* truth,
               const SE3& guess, const ViewAlignment& r) {
  double err_t = -1, err_r = -1, gt_t = -1, gt_r = -1, guess_t = -1, guess_r = -1;
  if (truth != nullptr) {
    gt_t = truth->translation().norm();
    gt_r = angle_deg(*truth);
    const SE3 e = truth->inverse() * r.T_a_b;
    err_t = e.translation().norm();
    err_r = angle_deg(e);
    const SE3 g = truth->inverse() * guess;
    guess_t = g.translation().norm();
    guess_r = angle_deg(g);
  }
  auto fit = [](const TrackResult& f) {
    std::printf(",%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%d,%.6f,%.5f", f.photometric_agreement,
                f.geometric_agreement, f.photometric_inliers, f.geometric_inliers, f.visible,
                f.overlap, f.residuals_used, f.translation_std_m, f.rotation_std_rad);
  };
  std::printf("%s,%.3f,%.3f,%.4f,%.3f,%.4f,%.3f,%.4f,%.3f,%u,%u,%.4f,%.3f", kind, a.t_s, b.t_s,
              gt_t, gt_r, guess_t, guess_r, err_t, err_r, r.forward_failed, r.backward_failed,
              r.disagreement_m, r.disagreement_rad * 180 / M_PI);
  fit(r.forward);
  fit(r.backward);
  std::printf("\n");
}

}  // namespace

int view_study(const std::string& sequence, const Params& params, const std::string& other,
               const Params& other_params, int every) {
  std::vector<Sample> samples, strangers;
  if (!load_samples(sequence, params, every, &samples)) return 1;
  if (!other.empty() && !load_samples(other, other_params, every, &strangers)) return 1;
  ViewAligner aligner;
  aligner.allocate(params.camera, params.sensor.depth_factor, params.sensor.depth_range,
                   params.tracker);
  HealthLimits limits = params.health;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  // The drift a map's guess carries: up to 8 cm and 4 degrees.
  auto drifted = [&](const SE3& T) {
    const Vector3d dt(unit(rng), unit(rng), unit(rng));
    const Vector3d dr(unit(rng), unit(rng), unit(rng));
    return T * SE3(so3_exp(dr.normalized() * (std::fabs(unit(rng)) * 4 * M_PI / 180)),
                   dt.normalized() * (std::fabs(unit(rng)) * 0.08));
  };
  std::printf(
      "kind,t_a,t_b,gt_m,gt_deg,guess_err_m,guess_err_deg,err_m,err_deg,fwd_failed,bwd_failed,"
      "disagree_m,disagree_deg,"
      "f_ph_agree,f_geo_agree,f_ph_in,f_geo_in,f_visible,f_overlap,f_residuals,f_tstd,f_rstd,"
      "b_ph_agree,b_geo_agree,b_ph_in,b_geo_in,b_visible,b_overlap,b_residuals,b_tstd,b_rstd\n");
  for (size_t i = 0; i < samples.size(); ++i) {
    aligner.set(0, samples[i].view);
    for (size_t j = i + 1; j < samples.size(); ++j) {
      if (samples[j].t_s - samples[i].t_s < 2.0) continue;
      const SE3 truth = samples[i].T_w_c.inverse() * samples[j].T_w_c;
      aligner.set(1, samples[j].view);
      // The map's guess, drifted; and none at all (the place's own pose).
      const SE3 guess = drifted(truth);
      print_row("map", samples[i], samples[j], &truth, guess, aligner.align(&guess, 1, limits));
      const SE3 none;
      print_row("none", samples[i], samples[j], &truth, none, aligner.align(&none, 1, limits));
    }
    for (const Sample& s : strangers) {
      aligner.set(1, s.view);
      const SE3 none;
      print_row("stranger", samples[i], s, nullptr, none, aligner.align(&none, 1, limits));
    }
  }
  return 0;
}

}  // namespace rgbdtam
