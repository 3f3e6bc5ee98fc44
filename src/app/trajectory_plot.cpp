#include "trajectory_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>

#include "rgbdtam/core/symmetric_eigen.hpp"
#include "rgbdtam/hal/file.hpp"

namespace rgbdtam {
namespace {

constexpr double kWidth = 1120, kHeight = 560;
constexpr double kPanelTop = 60, kPanelHeight = 420;
constexpr double kTopViewLeft = 50, kTopViewWidth = 460;
constexpr double kErrorLeft = 600, kErrorWidth = 480;
constexpr const char* kTruthColour = "#555555";
constexpr const char* kEstimateColour = "#1f6fd1";
constexpr const char* kLostColour = "#f39c12";
constexpr const char* kFalseValidColour = "#d62728";
constexpr const char* kMisleadingColour = "#9467bd";

std::string format(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
std::string format(const char* fmt, ...) {
  char buf[512];
  va_list args;
  va_start(args, fmt);
  std::vsnprintf(buf, sizeof(buf), fmt, args);
  va_end(args);
  return buf;
}

std::string escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// A linear map from [lo, hi] onto [to_lo, to_hi].
struct Axis {
  double lo, hi, to_lo, to_hi;
  double operator()(double v) const { return to_lo + (v - lo) / (hi - lo) * (to_hi - to_lo); }
};

// Tick spacing of 1, 2 or 5 times a power of ten, about five ticks over the range.
double tick_step(double range) {
  const double raw = range / 5;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0}) {
    if (m * magnitude >= raw) return m * magnitude;
  }
  return 10 * magnitude;
}

// Ticks from 0 over [0, range]; none for a range that is not a positive finite number (a
// hostile trajectory's), and never more than a handful, however the steps round.
std::vector<double> ticks(double range) {
  std::vector<double> out;
  if (!std::isfinite(range) || range <= 0) return out;
  const double step = tick_step(range);
  for (int i = 0; i <= 10 && i * step <= range + 1e-9; ++i) out.push_back(i * step);
  return out;
}

// Polylines of points, broken wherever `broken(i)` says point i starts a new piece.
template <typename Point, typename Broken>
std::string polylines(const std::vector<Point>& points, Broken broken, const char* colour,
                      double width) {
  std::string out, piece;
  int count = 0;
  auto flush = [&] {
    if (count >= 2) {
      out += format("<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"%.1f\" points=\"", colour,
                    width) +
             piece + "\"/>\n";
    }
    piece.clear();
    count = 0;
  };
  for (size_t i = 0; i < points.size(); ++i) {
    if (i > 0 && broken(i)) flush();
    if (!points[i].allFinite()) {  // off any scale: the line breaks there
      flush();
      continue;
    }
    piece += format("%.1f,%.1f ", points[i].x(), points[i].y());
    ++count;
  }
  flush();
  return out;
}

bool inside_any(const std::vector<LostStretch>& lost, double t0, double t1) {
  for (const LostStretch& s : lost) {
    if (s.begin_s > t0 && s.begin_s < t1) return true;
  }
  return false;
}

double median_interval(const std::vector<StampedPose>& est) {
  std::vector<double> dt;
  for (size_t i = 1; i < est.size(); ++i) dt.push_back(est[i].stamp_s - est[i - 1].stamp_s);
  if (dt.empty()) return 0;
  std::nth_element(dt.begin(), dt.begin() + dt.size() / 2, dt.end());
  return dt[dt.size() / 2];
}

}  // namespace

std::vector<LostStretch> lost_stretches(const PlotInput& in) {
  std::vector<LostStretch> out;
  const std::vector<StampedPose>& gt = *in.gt;
  const std::vector<StampedPose>& est = *in.est;
  if (gt.empty()) return out;
  if (in.frame_stamps != nullptr) {
    std::vector<double> gt_stamps, est_stamps;
    for (const StampedPose& p : gt) gt_stamps.push_back(p.stamp_s);
    for (const StampedPose& p : est) est_stamps.push_back(p.stamp_s);
    const auto with_gt = associate(*in.frame_stamps, gt_stamps);
    const auto with_est = associate(*in.frame_stamps, est_stamps);
    std::vector<char> estimated(in.frame_stamps->size(), 0);
    for (const auto& m : with_est) estimated[static_cast<size_t>(m.first)] = 1;
    bool open = false;
    for (const auto& m : with_gt) {
      const double t = (*in.frame_stamps)[static_cast<size_t>(m.first)];
      if (!estimated[static_cast<size_t>(m.first)]) {
        if (!open) out.push_back({t, t});
        out.back().end_s = t;
        open = true;
      } else {
        open = false;
      }
    }
    return out;
  }
  const double gap = 3 * median_interval(est);
  for (size_t i = 1; i < est.size(); ++i) {
    if (est[i].stamp_s - est[i - 1].stamp_s > gap)
      out.push_back({est[i - 1].stamp_s, est[i].stamp_s});
  }
  return out;
}

std::string trajectory_svg(const PlotInput& in) {
  const std::vector<StampedPose>& gt = *in.gt;
  const std::vector<StampedPose>& est = *in.est;
  const EvaluationReport& report = *in.report;
  const std::vector<LostStretch> lost = lost_stretches(in);
  const SE3& T_gt_est = report.ate.T_gt_est;

  // The ground truth's principal axes: the plane it moves in most.
  Vector3d mean = Vector3d::Zero();
  for (const StampedPose& p : gt) mean += p.T_w_c.translation();
  mean /= std::max<size_t>(gt.size(), 1);
  Matrix3d covariance = Matrix3d::Zero();
  for (const StampedPose& p : gt) {
    const Vector3d d = p.T_w_c.translation() - mean;
    covariance += d * d.transpose();
  }
  const SymmetricEigen<3> eigen = symmetric_eigen(covariance);
  const Vector3d first = eigen.vectors.col(2), second = eigen.vectors.col(1);
  auto project = [&](const Vector3d& p) {
    return Eigen::Vector2d((p - mean).dot(first), (p - mean).dot(second));
  };
  std::vector<Eigen::Vector2d> gt_plane, est_plane;
  for (const StampedPose& p : gt) gt_plane.push_back(project(p.T_w_c.translation()));
  for (const StampedPose& p : est) est_plane.push_back(project(T_gt_est * p.T_w_c.translation()));
  Eigen::Vector2d lo(1e300, 1e300), hi(-1e300, -1e300);
  for (const auto* points : {&gt_plane, &est_plane}) {
    for (const Eigen::Vector2d& p : *points) {
      if (!p.allFinite()) continue;
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  // One scale for both axes, centred, 5 % margin.
  double span = std::max({hi.x() - lo.x(), hi.y() - lo.y(), 1e-3}) * 1.1;
  if (!std::isfinite(span)) span = 1e-3;  // nothing finite to draw, or beyond a double's range
  const Eigen::Vector2d centre = (lo + hi) / 2;
  const double side = std::min(kTopViewWidth, kPanelHeight);
  const Axis u{centre.x() - span / 2, centre.x() + span / 2, kTopViewLeft, kTopViewLeft + side};
  const Axis v{centre.y() - span / 2, centre.y() + span / 2, kPanelTop + side, kPanelTop};
  auto to_view = [&](const std::vector<Eigen::Vector2d>& points) {
    std::vector<Eigen::Vector2d> out;
    for (const Eigen::Vector2d& p : points) out.emplace_back(u(p.x()), v(p.y()));
    return out;
  };

  std::string svg = format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" viewBox=\"0 0 "
      "%.0f %.0f\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%%\" "
      "height=\"100%%\" fill=\"white\"/>\n",
      kWidth, kHeight, kWidth, kHeight);
  svg += "<text x=\"20\" y=\"24\" font-size=\"16\">" + escape(in.title) + "</text>\n";
  svg += format(
      "<text x=\"20\" y=\"44\">ATE RMSE %.2f cm over %d poses (all estimates, aligned without "
      "scale)",
      report.ate.rmse_m * 100, report.ate.compared);
  if (report.has_coverage) svg += format("; coverage %.1f %%", 100 * report.coverage.fraction());
  svg += format("; false-valid %d of %d", report.false_valid.count, report.false_valid.checked);
  if (report.nees.pairs > 0) svg += format("; misleading %d", report.nees.misleading);
  svg += format("; lost stretches %zu</text>\n", lost.size());

  // Top view.
  svg += format(
      "<g id=\"top-view\"><rect x=\"%.0f\" y=\"%.0f\" width=\"%.0f\" height=\"%.0f\" "
      "fill=\"none\" stroke=\"#cccccc\"/>\n",
      kTopViewLeft, kPanelTop, side, side);
  const double scale_m = tick_step(span);
  svg += format(
      "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"black\" stroke-width=\"2\"/>"
      "<text x=\"%.1f\" y=\"%.1f\">%.3g m</text>\n",
      kTopViewLeft + 10, kPanelTop + side - 10, kTopViewLeft + 10 + side * scale_m / span,
      kPanelTop + side - 10, kTopViewLeft + 10, kPanelTop + side - 16, scale_m);
  svg +=
      format("<text x=\"%.0f\" y=\"%.0f\">top view: the ground truth's two principal axes</text>\n",
             kTopViewLeft, kPanelTop + side + 18);
  const auto gt_view = to_view(gt_plane), est_view = to_view(est_plane);
  svg += polylines(
      gt_view, [](size_t) { return false; }, kTruthColour, 1.5);
  // The camera's path while tracking was lost, over the ground truth.
  for (const LostStretch& s : lost) {
    std::vector<Eigen::Vector2d> stretch;
    for (size_t i = 0; i < gt.size(); ++i) {
      if (gt[i].stamp_s >= s.begin_s - 0.02 && gt[i].stamp_s <= s.end_s + 0.02)
        stretch.push_back(gt_view[i]);
    }
    svg += polylines(
        stretch, [](size_t) { return false; }, kLostColour, 5);
  }
  svg += polylines(
      est_view,
      [&](size_t i) { return inside_any(lost, est[i - 1].stamp_s, est[i].stamp_s + 1e-9); },
      kEstimateColour, 1.5);

  // Error over time.
  const double t0 = gt.front().stamp_s, t1 = std::max(gt.back().stamp_s, t0 + 1e-3);
  std::vector<double> gt_stamps, est_stamps;
  for (const StampedPose& p : gt) gt_stamps.push_back(p.stamp_s);
  for (const StampedPose& p : est) est_stamps.push_back(p.stamp_s);
  const auto matches = associate(gt_stamps, est_stamps);
  std::vector<double> error_cm(est.size(), -1);
  double max_error_cm = 0.1;
  for (const auto& m : matches) {
    const double e = (T_gt_est * est[static_cast<size_t>(m.second)].T_w_c.translation() -
                      gt[static_cast<size_t>(m.first)].T_w_c.translation())
                         .norm() *
                     100;
    if (!std::isfinite(e)) continue;  // not drawn, as the estimate's point is not
    error_cm[static_cast<size_t>(m.second)] = e;
    max_error_cm = std::max(max_error_cm, e);
  }
  const Axis x{0, t1 - t0, kErrorLeft, kErrorLeft + kErrorWidth};
  const Axis y{0, max_error_cm * 1.1, kPanelTop + kPanelHeight, kPanelTop};
  svg += "</g>\n<g id=\"error-over-time\">\n";
  for (const LostStretch& s : lost) {
    svg += format(
        "<rect class=\"lost\" x=\"%.1f\" y=\"%.0f\" width=\"%.1f\" height=\"%.0f\" fill=\"%s\" "
        "fill-opacity=\"0.35\"/>\n",
        x(s.begin_s - t0), kPanelTop, std::max(1.0, x(s.end_s - t0) - x(s.begin_s - t0)),
        kPanelHeight, kLostColour);
  }
  svg += format(
      "<rect x=\"%.0f\" y=\"%.0f\" width=\"%.0f\" height=\"%.0f\" fill=\"none\" "
      "stroke=\"#cccccc\"/>\n",
      kErrorLeft, kPanelTop, kErrorWidth, kPanelHeight);
  for (const double t : ticks(t1 - t0)) {
    svg += format("<text x=\"%.1f\" y=\"%.0f\" text-anchor=\"middle\">%g</text>\n", x(t),
                  kPanelTop + kPanelHeight + 16, t);
  }
  for (const double e : ticks(max_error_cm * 1.1)) {
    svg += format(
        "<line x1=\"%.0f\" y1=\"%.1f\" x2=\"%.0f\" y2=\"%.1f\" stroke=\"#eeeeee\"/><text "
        "x=\"%.0f\" y=\"%.1f\" text-anchor=\"end\">%g</text>\n",
        kErrorLeft, y(e), kErrorLeft + kErrorWidth, y(e), kErrorLeft - 6, y(e) + 4, e);
  }
  svg += format("<text x=\"%.0f\" y=\"%.0f\">position error (cm) over time (s)</text>\n",
                kErrorLeft, kPanelTop + kPanelHeight + 36);
  std::vector<Eigen::Vector2d> error_points;
  std::vector<double> error_stamps;
  for (size_t i = 0; i < est.size(); ++i) {
    if (error_cm[i] < 0) continue;
    error_points.emplace_back(x(est[i].stamp_s - t0), y(error_cm[i]));
    error_stamps.push_back(est[i].stamp_s);
  }
  svg += polylines(
      error_points,
      [&](size_t i) { return inside_any(lost, error_stamps[i - 1], error_stamps[i] + 1e-9); },
      kEstimateColour, 1.2);

  // False-valid poses (circles) and misleading ones (squares): in both views.
  auto mark = [&](const std::vector<double>& stamps, const char* css, const char* shape,
                  const char* colour) {
    for (double stamp : stamps) {
      const auto at = std::lower_bound(est_stamps.begin(), est_stamps.end(), stamp);
      if (at == est_stamps.end()) continue;
      const size_t i = static_cast<size_t>(at - est_stamps.begin());
      if (!est_view[i].allFinite()) continue;
      const double e = error_cm[i] < 0 ? 0 : error_cm[i];
      for (const Eigen::Vector2d& p : {est_view[i], Eigen::Vector2d(x(stamp - t0), y(e))}) {
        svg += format(shape, css, p.x(), p.y(), colour);
      }
    }
  };
  mark(report.false_valid.stamps_s, "false-valid",
       "<circle class=\"%s\" cx=\"%.1f\" cy=\"%.1f\" r=\"4\" fill=\"none\" stroke=\"%s\" "
       "stroke-width=\"2\"/>\n",
       kFalseValidColour);
  mark(report.nees.misleading_stamps_s, "misleading",
       "<rect class=\"%s\" x=\"%.1f\" y=\"%.1f\" width=\"7\" height=\"7\" fill=\"none\" "
       "stroke=\"%s\" stroke-width=\"2\" transform=\"translate(-3.5,-3.5)\"/>\n",
       kMisleadingColour);
  svg += "</g>\n";

  // Legend.
  const double legend_y = kHeight - 22;
  double legend_x = 50;
  for (const auto& [colour, label] :
       {std::make_pair(kTruthColour, "ground truth"), std::make_pair(kEstimateColour, "estimate"),
        std::make_pair(kLostColour, "lost (no pose)"),
        std::make_pair(kFalseValidColour, "false-valid pose"),
        std::make_pair(kMisleadingColour, "misleading pose")}) {
    svg += format(
        "<rect x=\"%.0f\" y=\"%.0f\" width=\"18\" height=\"6\" fill=\"%s\"/><text x=\"%.0f\" "
        "y=\"%.0f\">%s</text>\n",
        legend_x, legend_y - 6, colour, legend_x + 24, legend_y, label);
    legend_x += 170;
  }
  svg += "</svg>\n";
  return svg;
}

Status write_trajectory_svg(const char* path, const PlotInput& in) {
  const std::string svg = trajectory_svg(in);
  static char buffer[1 << 16];
  OutputFile out;
  RGBDTAM_RETURN_IF_ERROR(out.open(path, buffer, sizeof(buffer)));
  RGBDTAM_RETURN_IF_ERROR(
      out.check(std::fwrite(svg.data(), 1, svg.size(), out.stream()) == svg.size()));
  return out.commit();
}

}  // namespace rgbdtam
