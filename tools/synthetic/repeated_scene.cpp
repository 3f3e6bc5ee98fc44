#include "repeated_scene.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <thread>

#include "tum_writer.hpp"

namespace rgbdtam::testing {
namespace {
// World: x along the wall, y down, z towards the wall (the first camera's axes).
constexpr double kInf = std::numeric_limits<double>::infinity();

double frac(double x) { return x - std::floor(x); }

// An axis-aligned box and the grey of its faces at a world point.
struct Box {
  Vector3d lo, hi;
  double grey = 0.5;
  double stripe_m = 0.0;  // horizontal stripes of this height (a shirt), 0: plain
};

struct GreyHit {
  double t = kInf;  // along a ray whose direction has unit camera z: the camera depth
  double grey = 0.0;
  // The wall and the floor are shaded once they are known to be the nearest.
  enum class Surface { kBox, kWall, kFloor } surface = Surface::kBox;
};

// The ray o + t d enters the box at t (slab method); false when it misses or starts inside.
bool enters(const Box& b, const Vector3d& o, const Vector3d& d, double* t) {
  double t0 = 0.0, t1 = kInf;
  for (int a = 0; a < 3; ++a) {
    if (std::fabs(d[a]) < 1e-12) {
      if (o[a] < b.lo[a] || o[a] > b.hi[a]) return false;
      continue;
    }
    double ta = (b.lo[a] - o[a]) / d[a], tb = (b.hi[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  if (t0 > t1 || t0 <= 1e-6) return false;
  *t = t0;
  return true;
}

// Grout or seam lines of width w_m every period_m, at coordinate u.
bool on_line(double u, double period_m, double w_m) { return frac(u / period_m) * period_m < w_m; }

double lateral_position(const RepeatedScene& s, double t) {
  // Speed swings between min_step and max_step per frame every 4 s: x is its integral.
  const double w = 2.0 * M_PI / 4.0;
  const double a = s.min_step_m * s.fps, b = (s.max_step_m - s.min_step_m) * s.fps;
  return a * t + 0.5 * b * (t - std::sin(w * t) / w);
}

// Whether any ray through the image (a pixel's margin around it) can enter the box: false only
// when all its corners are in front of the camera and their image lies beside the image.
bool may_be_seen(const Box& b, const SE3& T_w_c, const PinholeIntrinsics& k) {
  const SE3 T_c_w = T_w_c.inverse();
  double u_lo = kInf, u_hi = -kInf, v_lo = kInf, v_hi = -kInf;
  for (int corner = 0; corner < 8; ++corner) {
    const Vector3d w((corner & 1) ? b.hi.x() : b.lo.x(), (corner & 2) ? b.hi.y() : b.lo.y(),
                     (corner & 4) ? b.hi.z() : b.lo.z());
    const Vector3d c = T_c_w * w;
    if (c.z() <= 1e-6) return true;
    const double u = k.fx_px * c.x() / c.z() + k.cx_px, v = k.fy_px * c.y() / c.z() + k.cy_px;
    u_lo = std::min(u_lo, u);
    u_hi = std::max(u_hi, u);
    v_lo = std::min(v_lo, v);
    v_hi = std::max(v_hi, v);
  }
  return u_hi >= -1.0 && u_lo <= k.width_px && v_hi >= -1.0 && v_lo <= k.height_px;
}

class Renderer {
 public:
  // Only the structures within reach that the camera can see are kept (the rays' tests of the
  // others took a third of the rendering).
  Renderer(const RepeatedScene& s, const SE3& T_w_c, double t_s) : s_(s) {
    D_ = s.wall_distance_m;
    H_ = 0.7 * D_;  // the camera's height over the floor: the floor fills the image's lower part
    // A few boxes against the wall, far apart and unlike each other: the only things that
    // tell one stretch of wall from the next.
    std::mt19937 rng(s.seed);
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    double x = -0.5;
    for (int i = 0; i < 12; ++i) {
      x += 1.6 + 1.4 * u01(rng);
      const double size = (0.25 + 0.35 * u01(rng)) * std::min(1.0, D_);
      Box b;
      b.lo = Vector3d(x, H_ - size * (0.6 + 0.6 * u01(rng)), D_ - size);
      b.hi = Vector3d(x + size * (0.8 + 0.6 * u01(rng)), H_, D_);
      b.grey = 0.3 + 0.45 * u01(rng);
      const bool within_reach = std::fabs(x - T_w_c.translation().x()) < 2.0 + 3.0 * D_;
      if (within_reach && may_be_seen(b, T_w_c, s.camera)) structures_.push_back(b);
    }
    x_camera_at_enter_ = lateral_position(s, 0.33 * kPersonSequenceS);
    person_ = person_at(t_s);
    person_seen_ = s.person && may_be_seen(person_, T_w_c, s.camera);
  }

  // The nearest surface along the ray, and with `shade` its grey under the room's light.
  GreyHit cast(const Vector3d& o, const Vector3d& d, bool shade) const {
    GreyHit h;
    if (d.z() > 1e-9) consider(&h, (D_ - o.z()) / d.z(), GreyHit::Surface::kWall);
    if (d.y() > 1e-9) {
      const double t = (H_ - o.y()) / d.y();
      const Vector3d p = o + t * d;
      if (p.z() < D_) consider(&h, t, GreyHit::Surface::kFloor);
    }
    for (const Box& b : structures_) consider_box(&h, b, o, d, b.grey);
    if (s_.wall == RepeatedScene::Pattern::kShelving) shelving(&h, o, d);
    if (person_seen_) consider_box(&h, person_, o, d, 0.0);
    if (shade && h.t < kInf) {
      const Vector3d p = o + h.t * d;
      if (h.surface == GreyHit::Surface::kWall) h.grey = wall_grey(p);
      if (h.surface == GreyHit::Surface::kFloor) h.grey = floor_grey(p);
      // A room light: brighter near the middle of a long stretch, over metres, not periods.
      h.grey *=
          0.94 + 0.06 * std::cos(2.0 * M_PI * p.x() / 7.3) * std::cos(2.0 * M_PI * p.y() / 5.1);
    }
    return h;
  }

 private:
  void consider(GreyHit* h, double t, double grey) const {
    if (t > 1e-6 && t < h->t) {
      h->t = t;
      h->grey = grey;
      h->surface = GreyHit::Surface::kBox;
    }
  }
  void consider(GreyHit* h, double t, GreyHit::Surface surface) const {
    if (t > 1e-6 && t < h->t) {
      h->t = t;
      h->surface = surface;
    }
  }
  void consider_box(GreyHit* h, const Box& b, const Vector3d& o, const Vector3d& d,
                    double grey) const {
    double t;
    if (!enters(b, o, d, &t) || t >= h->t) return;
    if (b.stripe_m > 0.0) {
      const Vector3d p = o + t * d;
      const double from_top = p.y() - b.lo.y();
      grey = from_top > 0.45 * (b.hi.y() - b.lo.y())           ? 0.15
             : on_line(from_top, b.stripe_m, 0.5 * b.stripe_m) ? 0.2
                                                               : 0.8;
    }
    consider(h, t, grey);
  }

  double wall_grey(const Vector3d& p) const {
    const double u = p.x(), v = p.y(), P = s_.period_m;
    switch (s_.wall) {
      case RepeatedScene::Pattern::kPanels: {
        // Tall panels, identical, with a faint shading of their own; the seams are the edges.
        constexpr double kSeamM = 0.012;
        if (on_line(u, P, kSeamM) || on_line(v, 2.0 * P, kSeamM)) return 0.28;
        return 0.62 + 0.04 * (frac(u / P) - 0.5) - 0.03 * (frac(v / (2.0 * P)) - 0.5);
      }
      case RepeatedScene::Pattern::kTiles: {
        const double grout = std::min(0.08 * P, 0.008);
        if (on_line(u, P, grout) || on_line(v, P, grout)) return 0.82;
        return 0.48 + 0.03 * (frac(u / P) - frac(v / P));
      }
      case RepeatedScene::Pattern::kBrick: {
        // Bricks a third as high as long, every other row shifted by half a brick.
        const double h = P / 3.0, mortar = std::min(0.04 * P, 0.01);
        const double row = std::floor(v / h);
        const double shifted = u + (std::fmod(std::fabs(row), 2.0) > 0.5 ? 0.5 * P : 0.0);
        if (on_line(v, h, mortar) || on_line(shifted, P, mortar)) return 0.75;
        return 0.38;
      }
      case RepeatedScene::Pattern::kShelving: {
        // Book spines between the shelves, the same row of them in every bay.
        const double in_bay = frac(u / P) * P;
        const double spine = 0.035;
        const int book = static_cast<int>(in_bay / spine);
        return 0.25 + 0.5 * frac(std::sin(book * 12.9898) * 43758.5453);
      }
    }
    return 0.5;
  }

  double floor_grey(const Vector3d& p) const {
    const double P = s_.floor_period_m;
    if (on_line(p.x(), P, 0.006) || on_line(p.z(), P, 0.006)) return 0.7;
    return 0.42;
  }

  // Uprights every period and a board every 0.35 m, 0.3 m deep from the wall.
  void shelving(GreyHit* h, const Vector3d& o, const Vector3d& d) const {
    constexpr double kDepthM = 0.3, kBoardEveryM = 0.35, kThickM = 0.02, kUprightM = 0.03;
    const double z0 = D_ - kDepthM;
    if (d.z() <= 1e-9) return;
    const double ta = std::max(0.0, (z0 - o.z()) / d.z()), tb = (D_ - o.z()) / d.z();
    const double xa = o.x() + ta * d.x(), xb = o.x() + tb * d.x();
    const double P = s_.period_m;
    for (double k = std::floor(std::min(xa, xb) / P) - 1; k <= std::ceil(std::max(xa, xb) / P);
         ++k) {
      Box b;
      b.lo = Vector3d(k * P, H_ - 2.2, z0);
      b.hi = Vector3d(k * P + kUprightM, H_, D_);
      consider_box(h, b, o, d, 0.3);
    }
    // Only the boards the ray's stretch between the uprights' front and the wall passes: the
    // others could not be entered (a nanometre's margin for rounding), and testing all six
    // took most of the shelving's rendering.
    const double ya = o.y() + ta * d.y(), yb = o.y() + tb * d.y();
    const double y_lo = std::min(ya, yb) - 1e-9, y_hi = std::max(ya, yb) + 1e-9;
    for (int k = 1; k <= 6; ++k) {
      if (H_ - k * kBoardEveryM > y_hi || H_ - k * kBoardEveryM + kThickM < y_lo) continue;
      Box b;
      b.lo = Vector3d(-kInf, H_ - k * kBoardEveryM, z0);
      b.hi = Vector3d(kInf, H_ - k * kBoardEveryM + kThickM, D_);
      consider_box(h, b, o, d, 0.55);
    }
  }

  // Crossing the view from right to left at walking pace, half-way to the wall, in the middle
  // third of the sequence.
  Box person_at(double t_s) const {
    const double z = 0.55 * D_, half_view = 0.7 * z;
    const double t_enter = 0.33 * kPersonSequenceS;
    const double x = x_camera_at_enter_ + half_view + 0.25 - 1.2 * (t_s - t_enter);
    Box b;
    b.lo = Vector3d(x - 0.22, H_ - 1.75, z - 0.15);
    b.hi = Vector3d(x + 0.22, H_, z + 0.15);
    b.stripe_m = 0.08;
    return b;
  }

  static constexpr double kPersonSequenceS = 5.0;
  const RepeatedScene& s_;
  double D_ = 0.5, H_ = 0.35;
  std::vector<Box> structures_;
  double x_camera_at_enter_ = 0.0;
  Box person_;  // where the person is in this frame, and whether the camera can see them
  bool person_seen_ = false;
};

// Structured-light depth: disparity noise of 0.1 px quantised to 1/8 px (580 px x 7.5 cm),
// blobs of missing depth, a shadow beside each jump in depth, and no depth nearer than 0.2 m.
void add_sensor_noise(const RepeatedScene& s, int frame, std::vector<double>* depth_m) {
  constexpr double kFocalBaseline = 580.0 * 0.075, kSigmaPx = 0.1, kQuantumPx = 0.125;
  const int w = s.camera.width_px, h = s.camera.height_px;
  std::mt19937 rng(s.seed * 7919u + static_cast<unsigned>(frame));
  std::normal_distribution<double> noise(0.0, kSigmaPx);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  // Blobs: a coarse random grid, bilinearly smooth, thresholded to about 3 % of the image.
  constexpr int kCell = 24;
  const int gw = w / kCell + 2, gh = h / kCell + 2;
  std::vector<double> grid(static_cast<size_t>(gw) * gh);
  for (double& g : grid) g = u01(rng);
  std::vector<double> out(*depth_m);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      const double z = (*depth_m)[i];
      if (!(z > 0.2)) {
        out[i] = 0.0;
        continue;
      }
      const double gx = static_cast<double>(x) / kCell, gy = static_cast<double>(y) / kCell;
      const int cx = static_cast<int>(gx), cy = static_cast<int>(gy);
      const double fx = gx - cx, fy = gy - cy;
      auto g = [&](int a, int b) { return grid[static_cast<size_t>(b) * gw + a]; };
      const double blob = (1 - fy) * ((1 - fx) * g(cx, cy) + fx * g(cx + 1, cy)) +
                          fy * ((1 - fx) * g(cx, cy + 1) + fx * g(cx + 1, cy + 1));
      const double left = x >= 4 ? (*depth_m)[i - 4] : z;
      if (blob > 0.93 || left > 1.05 * z) {
        out[i] = 0.0;  // a blob, or the projector's shadow beyond a nearer edge
        continue;
      }
      const double disparity = kFocalBaseline / z + noise(rng);
      out[i] = kFocalBaseline / (std::round(disparity / kQuantumPx) * kQuantumPx);
    }
  }
  *depth_m = out;
}

RepeatedScene make(const char* name, RepeatedScene::Pattern wall, double period_m,
                   double distance_m, double min_step_m, double max_step_m, double fps) {
  RepeatedScene s;
  s.name = name;
  s.wall = wall;
  s.period_m = period_m;
  s.wall_distance_m = distance_m;
  s.min_step_m = min_step_m;
  s.max_step_m = max_step_m;
  s.fps = fps;
  s.floor_period_m = std::clamp(period_m, 0.1, 0.6);
  return s;
}
}  // namespace

SE3 RepeatedScene::camera_at(int frame) const {
  const double t = frame / fps;
  // The view swings in yaw and pitch at up to max_turn_deg a frame, looking down at the wall's
  // foot; the height and the distance to the wall wander by a few centimetres.
  const double swing = 2.0 * M_PI / 3.0;
  const double yaw_amplitude =
      std::min(12.0 * M_PI / 180.0, max_turn_deg * M_PI / 180.0 * fps / swing);
  const double H = 0.7 * wall_distance_m;
  const double look_down = std::atan(H / wall_distance_m) - std::atan(96.0 / camera.fy_px);
  const double yaw = yaw_amplitude * std::sin(swing * t);
  const double pitch = look_down + 0.3 * yaw_amplitude * std::sin(1.7 * swing * t);
  const double roll = 0.2 * yaw_amplitude * std::sin(0.9 * swing * t);
  const Matrix3d R =
      (Eigen::AngleAxisd(yaw, Vector3d::UnitY()) * Eigen::AngleAxisd(-pitch, Vector3d::UnitX()) *
       Eigen::AngleAxisd(roll, Vector3d::UnitZ()))
          .toRotationMatrix();
  const Vector3d p(lateral_position(*this, t), 0.03 * wall_distance_m * std::sin(2.1 * t),
                   0.1 * wall_distance_m * std::sin(0.7 * t));
  return SE3(Eigen::Quaterniond(R), p);
}

SyntheticFrame RepeatedScene::render(int frame) const {
  const double t = frame / fps;
  const SE3 T_w_c = camera_at(frame);
  const Renderer r(*this, T_w_c, t);
  const Matrix3d R = T_w_c.rotation();
  const Vector3d o = T_w_c.translation();
  const int w = camera.width_px, h = camera.height_px;
  SyntheticFrame f;
  f.gray.resize(static_cast<size_t>(w) * h);
  f.depth.resize(f.gray.size());
  std::vector<double> depth_m(f.gray.size());
  const double gain =
      exposure_step_frame >= 0 && frame >= exposure_step_frame ? exposure_gain : 1.0;
  auto rows = [&](int y0, int step) {
    for (int y = y0; y < h; y += step) {
      for (int x = 0; x < w; ++x) {
        // 2x2 samples a pixel: seams a centimetre wide stay smooth at every distance.
        double grey = 0.0;
        for (int sy = 0; sy < 2; ++sy) {
          for (int sx = 0; sx < 2; ++sx) {
            const double px = x - 0.25 + 0.5 * sx, py = y - 0.25 + 0.5 * sy;
            const Vector3d ray((px - camera.cx_px) / camera.fx_px,
                               (py - camera.cy_px) / camera.fy_px, 1.0);
            grey += 0.25 * r.cast(o, R * ray, true).grey;
          }
        }
        const Vector3d centre((x - camera.cx_px) / camera.fx_px, (y - camera.cy_px) / camera.fy_px,
                              1.0);
        const size_t i = static_cast<size_t>(y) * w + x;
        depth_m[i] = r.cast(o, R * centre, false).t;  // unit camera z: t is the depth
        f.gray[i] = static_cast<uint8_t>(std::clamp(std::lround(gain * grey * 255.0), 0L, 255L));
      }
    }
  };
  // Rows interleaved over the machine's cores; each pixel is written by one thread.
  const int threads = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  std::vector<std::thread> pool;
  for (int k = 1; k < threads; ++k) pool.emplace_back(rows, k, threads);
  rows(0, threads);
  for (std::thread& th : pool) th.join();
  if (sensor_noise) add_sensor_noise(*this, frame, &depth_m);
  for (size_t i = 0; i < depth_m.size(); ++i) {
    const double z = depth_m[i];
    f.depth[i] = z > 0.0 && z < 10.0 ? static_cast<uint16_t>(std::lround(z * depth_factor)) : 0;
  }
  return f;
}

std::vector<RepeatedScene> RepeatedScene::family() {
  using P = Pattern;
  std::vector<RepeatedScene> f;
  // Panels as the hidden scene: 0.6 m at arm's length, fast.
  f.push_back(make("panels60_d05_30hz", P::kPanels, 0.6, 0.5, 0.03, 0.08, 30));
  f.push_back(make("panels60_d05_10hz", P::kPanels, 0.6, 0.5, 0.05, 0.15, 10));
  f.push_back(make("panels60_d05_10hz_noisy", P::kPanels, 0.6, 0.5, 0.05, 0.15, 10));
  f.back().sensor_noise = true;
  f.push_back(make("panels100_d2_30hz_person", P::kPanels, 1.0, 2.0, 0.02, 0.08, 30));
  f.back().person = true;
  f.push_back(make("panels30_d1_30hz_exposure", P::kPanels, 0.3, 1.0, 0.02, 0.08, 30));
  f.back().exposure_step_frame = 45;
  f.push_back(make("tiles5_d03_30hz", P::kTiles, 0.05, 0.3, 0.02, 0.05, 30));
  f.push_back(make("tiles15_d06_10hz_noisy", P::kTiles, 0.15, 0.6, 0.04, 0.12, 10));
  f.back().sensor_noise = true;
  f.push_back(make("brick25_d1_10hz", P::kBrick, 0.25, 1.0, 0.05, 0.15, 10));
  f.push_back(make("brick25_d1_30hz_noisy", P::kBrick, 0.25, 1.0, 0.02, 0.08, 30));
  f.back().sensor_noise = true;
  f.push_back(make("shelving80_d15_10hz", P::kShelving, 0.8, 1.5, 0.05, 0.15, 10));
  f.push_back(make("shelving50_d1_30hz_person", P::kShelving, 0.5, 1.0, 0.02, 0.07, 30));
  f.back().person = true;
  return f;
}

bool RepeatedScene::named(const std::string& name, RepeatedScene* out) {
  for (const RepeatedScene& s : family()) {
    if (s.name == name) {
      *out = s;
      return true;
    }
  }
  return false;
}

bool repeated_sequence(const std::string& out, const RepeatedScene& scene, int frames) {
  if (::mkdir(out.c_str(), 0755) != 0) {
    std::fprintf(stderr, "repeated: cannot create %s (it must not exist)\n", out.c_str());
    return false;
  }
  SyntheticFrame current;
  const bool ok =
      write_sequence(out, same_size(scene.camera.width_px, scene.camera.height_px), frames,
                     scene.fps, [&](int i, SE3* T_w_c) -> const SyntheticFrame& {
                       *T_w_c = scene.camera_at(i);
                       current = scene.render(i);
                       return current;
                     });
  SyntheticScene camera_only;
  camera_only.camera = scene.camera;
  camera_only.depth_factor = scene.depth_factor;
  if (!ok || !write_text(out + "/camera.conf", synthetic_config(camera_only))) {
    std::fprintf(stderr, "repeated: cannot write the sequence into %s\n", out.c_str());
    return false;
  }
  std::printf("%s: %d frames at %.0f Hz of %s (config: camera.conf)\n", out.c_str(), frames,
              scene.fps, scene.name.c_str());
  return true;
}

}  // namespace rgbdtam::testing
