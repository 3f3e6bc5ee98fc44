#include "stress_variants.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "rgbdtam/core/depth_registration.hpp"
#include "rgbdtam/hal/file.hpp"
#include "rgbdtam/hal/tum_replay_source.hpp"
#include "rgbdtam/hal/tum_trajectory.hpp"
#include "rgbdtam/runtime/params.hpp"
#include "synthetic_scene.hpp"
#include "tum_writer.hpp"

namespace rgbdtam::testing {
namespace {

bool fail(const std::string& what) {
  std::fprintf(stderr, "stress variant: %s\n", what.c_str());
  return false;
}

bool read_lines(const std::string& path, std::vector<std::string>* lines) {
  std::ifstream in(path);
  if (!in) return fail("cannot read " + path);
  std::string line;
  while (std::getline(in, line)) lines->push_back(line);
  return true;
}

bool write_lines(const std::string& path, const std::vector<std::string>& lines) {
  std::ofstream out(path);
  for (const std::string& l : lines) out << l << '\n';
  out.close();
  return out ? true : fail("cannot write " + path);
}

bool is_data_line(const std::string& l) { return !l.empty() && l[0] != '#'; }

// A new, empty output folder: never overwrite an earlier variant.
bool create_folder(const std::string& out) {
  if (::mkdir(out.c_str(), 0755) != 0) {
    return fail("cannot create " + out + ": " + std::strerror(errno) + " (it must not exist)");
  }
  return true;
}

// ... for a readable input, so that nothing is left behind for one that is not a sequence.
bool make_output(const std::string& in, const std::string& out) {
  for (const char* list : {"rgb.txt", "depth.txt", "groundtruth.txt"}) {
    const std::string path = in + "/" + list;
    if (::access(path.c_str(), R_OK) != 0) return fail("cannot read " + path);
  }
  return create_folder(out);
}

bool link_into(const std::string& in, const std::string& out, const char* name) {
  char real[PATH_MAX];
  const std::string src = in + "/" + name;
  if (::realpath(src.c_str(), real) == nullptr) return fail("missing " + src);
  const std::string dst = out + "/" + name;
  if (::symlink(real, dst.c_str()) != 0) return fail("cannot link " + dst);
  return true;
}

bool copy_file(const std::string& in, const std::string& out, const char* name, bool required) {
  std::vector<std::string> lines;
  const std::string src = in + "/" + name;
  if (::access(src.c_str(), R_OK) != 0) return required ? fail("missing " + src) : true;
  return read_lines(src, &lines) && write_lines(out + "/" + name, lines);
}

// Keeps the data lines of a list for which keep(index among data lines) holds.
template <typename Keep>
bool filter_list(const std::string& in, const std::string& out, const char* name, Keep keep,
                 const std::string& note) {
  std::vector<std::string> lines, kept = {"# " + note};
  if (!read_lines(in + "/" + name, &lines)) return false;
  int index = 0;
  for (const std::string& l : lines) {
    if (!is_data_line(l) || keep(index++)) kept.push_back(l);
  }
  return write_lines(out + "/" + name, kept);
}

}  // namespace

namespace {
// A variant that differs from its input in one list (rgb.txt or depth.txt), filtered by keep;
// images are linked, the other lists copied.
template <typename Keep>
bool filtered_variant(const std::string& in, const std::string& out, const char* list, Keep keep,
                      const std::string& note) {
  const char* other = std::string(list) == "rgb.txt" ? "depth.txt" : "rgb.txt";
  return make_output(in, out) && filter_list(in, out, list, keep, note) &&
         copy_file(in, out, other, true) && copy_file(in, out, "groundtruth.txt", true) &&
         copy_file(in, out, "calib.txt", false) && link_into(in, out, "rgb") &&
         link_into(in, out, "depth");
}
}  // namespace

bool decimate_sequence(const std::string& in, const std::string& out, int n) {
  if (n < 1) return fail("decimate: n must be at least 1");
  return filtered_variant(
      in, out, "rgb.txt", [n](int i) { return i % n == 0; },
      "every " + std::to_string(n) + "-th colour frame of " + in);
}

bool cut_frames(const std::string& in, const std::string& out, int first, int count) {
  if (first < 0 || count < 1) return fail("cut: needs a first frame >= 0 and a count >= 1");
  return filtered_variant(
      in, out, "rgb.txt", [first, count](int i) { return i < first || i >= first + count; },
      std::to_string(count) + " colour frames cut from frame " + std::to_string(first) + " of " +
          in);
}

namespace {
// Index of the data line whose stamp is nearest t, or -1.
int nearest_line(const std::vector<std::string>& lines, double t) {
  int best = -1;
  double best_dt = 0.0;
  for (size_t i = 0; i < lines.size(); ++i) {
    if (!is_data_line(lines[i])) continue;
    const double dt = std::fabs(std::atof(lines[i].c_str()) - t);
    if (best < 0 || dt < best_dt) {
      best = static_cast<int>(i);
      best_dt = dt;
    }
  }
  return best;
}

bool load_params(const std::string& config, Params* p) {
  char* text = nullptr;
  Status s = read_text_file(config.c_str(), 1 << 20, &text);
  if (s.is_ok()) s = parse_params(text, config.c_str(), p);
  delete[] text;
  return s.is_ok() ? true : fail(s.message());
}

// The file name of a `stamp file` list line.
std::string file_of(const std::string& line) { return line.substr(line.find_last_of(" \t") + 1); }
std::string stamp_of(const std::string& line) { return line.substr(0, line.find_first_of(" \t")); }
}  // namespace

bool kidnap_frame(const std::string& in, const std::string& out, int frame, int from) {
  std::vector<std::string> rgb, depth;
  if (!read_lines(in + "/rgb.txt", &rgb) || !read_lines(in + "/depth.txt", &depth)) return false;
  std::vector<int> data;
  for (size_t i = 0; i < rgb.size(); ++i) {
    if (is_data_line(rgb[i])) data.push_back(static_cast<int>(i));
  }
  const int n = static_cast<int>(data.size());
  if (frame < 0 || from < 0 || frame >= n || from >= n || frame == from) {
    return fail("kidnap: frames must be two different ones of the " + std::to_string(n));
  }
  std::string& target = rgb[static_cast<size_t>(data[static_cast<size_t>(frame)])];
  const std::string& source = rgb[static_cast<size_t>(data[static_cast<size_t>(from)])];
  const int d_target = nearest_line(depth, std::atof(target.c_str()));
  const int d_source = nearest_line(depth, std::atof(source.c_str()));
  if (d_target < 0 || d_source < 0) return fail("kidnap: no depth frames in " + in);
  depth[static_cast<size_t>(d_target)] = stamp_of(depth[static_cast<size_t>(d_target)]) + " " +
                                         file_of(depth[static_cast<size_t>(d_source)]);
  target = stamp_of(target) + " " + file_of(source);
  const std::string note =
      "# frame " + std::to_string(frame) + " shows frame " + std::to_string(from) + " of " + in;
  rgb.insert(rgb.begin(), note);
  depth.insert(depth.begin(), note);
  return make_output(in, out) && write_lines(out + "/rgb.txt", rgb) &&
         write_lines(out + "/depth.txt", depth) && copy_file(in, out, "groundtruth.txt", true) &&
         copy_file(in, out, "calib.txt", false) && link_into(in, out, "rgb") &&
         link_into(in, out, "depth");
}

bool drop_depth_frames(const std::string& in, const std::string& out, int every, int burst,
                       int period) {
  if (every < 2 && (burst < 1 || period <= burst)) return fail("drop-depth: nothing to drop");
  auto dropped = [=](int i) { return every > 1 ? i % every == every - 1 : i % period < burst; };
  const std::string note = every > 1 ? "every " + std::to_string(every) + "-th depth frame dropped"
                                     : std::to_string(burst) + " of every " +
                                           std::to_string(period) + " depth frames dropped";
  return filtered_variant(
      in, out, "depth.txt", [&](int i) { return !dropped(i); }, note);
}

namespace {
// The ground-truth pose at any instant its samples bracket closely (linear position, slerp).
class Trajectory {
 public:
  explicit Trajectory(std::vector<StampedPose> poses) : poses_(std::move(poses)) {
    std::vector<double> gaps;
    for (size_t i = 1; i < poses_.size(); ++i)
      gaps.push_back(poses_[i].stamp_s - poses_[i - 1].stamp_s);
    std::sort(gaps.begin(), gaps.end());
    max_gap_s_ = gaps.empty() ? 0.0 : 2.0 * gaps[gaps.size() / 2];
  }
  bool at(double t, SE3* T) const { return interpolate_pose(poses_, t, max_gap_s_, T); }

 private:
  std::vector<StampedPose> poses_;
  double max_gap_s_ = 0.0;
};

float sample_clamped(const ImageU8& img, double u, double v) {
  u = std::clamp(u, 0.0, img.width() - 1.001);
  v = std::clamp(v, 0.0, img.height() - 1.001);
  const int x = static_cast<int>(u), y = static_cast<int>(v);
  const double fx = u - x, fy = v - y;
  const uint8_t* r0 = img.row(y) + x;
  const uint8_t* r1 = img.row(y + 1) + x;
  return static_cast<float>((1 - fy) * ((1 - fx) * r0[0] + fx * r0[1]) +
                            fy * ((1 - fx) * r1[0] + fx * r1[1]));
}

// The frame blurred over the exposure; false when the ground truth does not cover it.
bool blur_frame(const ImageU8& gray, const ImageU16* depth, const Params& p,
                const Trajectory& truth, double t, double exposure_s, std::vector<uint8_t>* out) {
  SE3 T_w_t, first, last;
  if (!truth.at(t, &T_w_t) || !truth.at(t - exposure_s / 2, &first) ||
      !truth.at(t + exposure_s / 2, &last)) {
    return false;
  }
  const int w = gray.width(), h = gray.height();
  const PinholeIntrinsics& k = p.camera;
  std::vector<float> depth_m(static_cast<size_t>(w) * h, 0.f);
  std::vector<float> valid;
  for (int y = 0; y < h && depth != nullptr; ++y) {
    for (int x = 0; x < w; ++x) {
      const float d = static_cast<float>(depth->at(x, y) / p.sensor.depth_factor);
      depth_m[static_cast<size_t>(y) * w + x] = d;
      if (d > 0.f) valid.push_back(d);
    }
  }
  float median = 1.5f;  // a desk scene, when the frame has no depth at all
  if (!valid.empty()) {
    std::nth_element(valid.begin(), valid.begin() + valid.size() / 2, valid.end());
    median = valid[valid.size() / 2];
  }
  // Enough samples that consecutive ones move a pixel at most, probed at the median depth.
  const SE3 across = first.inverse() * last;
  double spread_px = 0.0;
  for (const auto& [u, v] : {std::pair<double, double>{0, 0},
                             {w - 1.0, 0},
                             {0, h - 1.0},
                             {w - 1.0, h - 1.0},
                             {w / 2.0, h / 2.0}}) {
    const Vector3d X = median * Vector3d((u - k.cx_px) / k.fx_px, (v - k.cy_px) / k.fy_px, 1.0);
    const Vector3d Y = across * X;
    spread_px = std::max(spread_px, std::hypot(k.fx_px * Y.x() / Y.z() + k.cx_px - u,
                                               k.fy_px * Y.y() / Y.z() + k.cy_px - v));
  }
  const int samples = std::clamp(static_cast<int>(std::ceil(spread_px)) + 1, 1, 64);
  std::vector<float> sum(static_cast<size_t>(w) * h, 0.f);
  for (int s = 0; s < samples; ++s) {
    SE3 T_w_s;
    (void)truth.at(t - exposure_s / 2 + exposure_s * (s + 0.5) / samples, &T_w_s);
    const SE3 T_t_s = T_w_t.inverse() * T_w_s;
    const Matrix3d R = T_t_s.rotation();
    const Vector3d tr = T_t_s.translation();
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const size_t i = static_cast<size_t>(y) * w + x;
        const double d = depth_m[i] > 0.f ? depth_m[i] : median;
        const Vector3d X = d * Vector3d((x - k.cx_px) / k.fx_px, (y - k.cy_px) / k.fy_px, 1.0);
        const Vector3d Y = R * X + tr;
        if (Y.z() <= 0.05) {
          sum[i] += gray.at(x, y);
          continue;
        }
        sum[i] += sample_clamped(gray, k.fx_px * Y.x() / Y.z() + k.cx_px,
                                 k.fy_px * Y.y() / Y.z() + k.cy_px);
      }
    }
  }
  out->resize(sum.size());
  for (size_t i = 0; i < sum.size(); ++i)
    (*out)[i] = static_cast<uint8_t>(std::clamp(std::lround(sum[i] / samples), 0L, 255L));
  return true;
}

}  // namespace

bool blur_sequence(const std::string& in, const std::string& out, const std::string& config,
                   double exposure_ms) {
  if (!(exposure_ms > 0.0)) return fail("blur: the exposure must be positive");
  Params p;
  if (!load_params(config, &p)) return false;
  if (p.depth_camera.register_to_colour)
    return fail("blur: the depth must be registered to colour");
  std::vector<StampedPose> gt;
  int bad = 0;
  Status s = read_tum_trajectory((in + "/groundtruth.txt").c_str(), &gt, &bad);
  if (!s.is_ok()) return fail(s.message());
  const Trajectory truth(gt);
  TumReplaySource source;
  s = source.open(in.c_str(), sensor_image_size(p), p.sensor.max_rgb_depth_dt_ns,
                  p.sensor.depth_time_offset_ns);
  if (!s.is_ok()) return fail(s.message());
  if (!make_output(in, out) || ::mkdir((out + "/rgb").c_str(), 0755) != 0 ||
      !copy_file(in, out, "depth.txt", true) || !copy_file(in, out, "groundtruth.txt", true) ||
      !copy_file(in, out, "calib.txt", false) || !link_into(in, out, "depth")) {
    return false;
  }
  std::vector<std::string> rgb_lines = {"# colour frames of " + in + " blurred over " +
                                        std::to_string(exposure_ms) + " ms of their motion"};
  ImageU8 gray;
  ImageU16 depth;
  gray.allocate(p.camera.width_px, p.camera.height_px);
  depth.allocate(p.camera.width_px, p.camera.height_px);
  std::vector<uint8_t> blurred;
  int written = 0, sharp = 0;
  for (;;) {
    SensorFrame frame;
    Status warning;
    s = source.next_into(&gray, &depth, &frame, &warning);
    if (s.code() == StatusCode::kEndOfStream) break;
    if (!s.is_ok()) continue;  // unreadable in the original too: left out
    const TumListEntry& e = source.rgb_list().entries[source.position() - 1];
    const double t = static_cast<double>(e.timestamp_ns) * 1e-9;
    const bool moved = blur_frame(gray, frame.depth != nullptr ? &depth : nullptr, p, truth, t,
                                  exposure_ms * 1e-3, &blurred);
    if (!moved) ++sharp;  // no ground truth around it: kept as recorded
    const uint8_t* pixels = moved ? blurred.data() : gray.data();
    const std::string name = std::string("rgb/") + std::to_string(written) + ".png";
    if (!write_png_gray8(out + "/" + name, gray.width(), gray.height(), pixels)) {
      return fail("cannot write " + out + "/" + name);
    }
    char stamp[32];
    std::snprintf(stamp, sizeof(stamp), "%.6f", t);
    rgb_lines.push_back(std::string(stamp) + " " + name);
    ++written;
  }
  if (!write_lines(out + "/rgb.txt", rgb_lines)) return false;
  std::printf("%s: %d frames, %d blurred over %.1f ms, %d without ground truth kept sharp\n",
              out.c_str(), written, written - sharp, exposure_ms, sharp);
  return true;
}

namespace {
// Every depth frame of in (at p's sizes) written anew into out, out_width x out_height, as
// move(depth, out_pixels) makes it; colour, stamps and ground truth as recorded.
template <typename Move>
bool rewrite_depth(const std::string& in, const std::string& out, const Params& p, int out_width,
                   int out_height, const std::string& header, Move move) {
  const SensorImageSize size = sensor_image_size(p);
  TumReplaySource source;
  Status s =
      source.open(in.c_str(), size, p.sensor.max_rgb_depth_dt_ns, p.sensor.depth_time_offset_ns);
  if (!s.is_ok()) return fail(s.message());
  if (!make_output(in, out) || ::mkdir((out + "/depth").c_str(), 0755) != 0 ||
      !copy_file(in, out, "rgb.txt", true) || !copy_file(in, out, "groundtruth.txt", true) ||
      !copy_file(in, out, "calib.txt", false) || !link_into(in, out, "rgb")) {
    return false;
  }
  std::vector<std::string> depth_lines = {"# " + header};
  ImageU16 depth;
  depth.allocate(size.depth_width_px, size.depth_height_px);
  std::vector<uint16_t> moved(static_cast<size_t>(out_width) * out_height);
  // Every listed image, not only those the config's pairing gives a colour frame: a copy
  // replayed under another pairing finds the depth it pairs with.
  const TumList& list = source.depth_list();
  for (int i = 0; i < list.size; ++i) {
    if (!source.depth_at(i, &depth).is_ok()) continue;  // unreadable: the replay skips it too
    move(depth.data(), moved.data());
    const std::string name = "depth/" + std::to_string(depth_lines.size() - 1) + ".png";
    if (!write_png_gray16(out + "/" + name, out_width, out_height, moved.data())) {
      return fail("cannot write " + out + "/" + name);
    }
    char stamp[32];
    std::snprintf(stamp, sizeof(stamp), "%.6f",
                  static_cast<double>(list.entries[i].timestamp_ns) * 1e-9);
    depth_lines.push_back(std::string(stamp) + " " + name);
  }
  if (!write_lines(out + "/depth.txt", depth_lines)) return false;
  std::printf("%s: %zu depth frames, %s\n", out.c_str(), depth_lines.size() - 1, header.c_str());
  return true;
}

// out/depth_camera.conf: the depth_camera.* keys that register out's depth to colour.
bool write_depth_camera_keys(const std::string& out, const Params& p,
                             const DepthCameraParams& depth_camera) {
  Params keys = p;
  keys.depth_camera = depth_camera;
  std::vector<char> listing(1 << 17);
  print_params(keys, listing.data(), static_cast<int>(listing.size()));
  std::vector<std::string> conf = {"# register " + out + "'s depth to colour"};
  for (const char* line = listing.data(); *line != '\0';) {
    const char* end = std::strchr(line, '\n');
    const std::string l(line, end != nullptr ? end : line + std::strlen(line));
    if (l.rfind("depth_camera.", 0) == 0) conf.push_back(l.substr(0, l.find("  #")));
    line = end != nullptr ? end + 1 : line + l.size();
  }
  return write_lines(out + "/depth_camera.conf", conf);
}

// The shape's depth camera beside the colour camera k: its principal point off the image's
// centre by another amount than k's.
DepthCameraParams depth_camera_beside(const PinholeIntrinsics& k, const DepthCameraShape& shape) {
  const int w = shape.width_px > 0 ? shape.width_px : k.width_px;
  const int h = shape.height_px > 0 ? shape.height_px : k.height_px;
  DepthCameraParams d;
  d.register_to_colour = true;
  d.intrinsics = {k.fx_px * shape.focal_scale,
                  k.fy_px * shape.focal_scale,
                  k.cx_px + 0.5 * (w - k.width_px) + 4.0,
                  k.cy_px + 0.5 * (h - k.height_px) - 3.0,
                  w,
                  h};
  d.T_c_d = SE3(so3_exp(Vector3d(0.004, -0.008, 0.005)), Vector3d(shape.baseline_m, 0.001, -0.002));
  return d;
}

bool valid_shape(const char* verb, const DepthCameraShape& shape) {
  const bool sized = (shape.width_px == 0 && shape.height_px == 0) ||
                     (shape.width_px >= 16 && shape.height_px >= 16 && shape.width_px <= 4096 &&
                      shape.height_px <= 4096);
  if (shape.focal_scale > 0.5 && shape.focal_scale < 2.0 && std::fabs(shape.baseline_m) < 0.2 &&
      sized) {
    return true;
  }
  return fail(std::string(verb) +
              ": the focal scale must be within 0.5-2, the baseline within 0.2 m and the depth "
              "size within 16x16-4096x4096");
}
}  // namespace

bool unregister_depth(const std::string& in, const std::string& out, const std::string& config,
                      const DepthCameraShape& shape) {
  Params p;
  if (!load_params(config, &p)) return false;
  if (!valid_shape("unregister", shape)) return false;
  if (p.depth_camera.register_to_colour) {
    return fail("unregister: the depth of " + in + " must be registered to colour already");
  }
  DepthCameraParams depth_camera = depth_camera_beside(p.camera, shape);
  depth_camera.distortion.k1 = -0.04;
  depth_camera.distortion.k2 = 0.01;
  DepthRegistration to_depth_camera;
  to_depth_camera.init(CameraModel{p.camera, p.distortion},
                       CameraModel{depth_camera.intrinsics, depth_camera.distortion},
                       depth_camera.T_c_d.inverse(), p.sensor.depth_factor);
  if (!rewrite_depth(
          in, out, p, depth_camera.intrinsics.width_px, depth_camera.intrinsics.height_px,
          "depth of " + in + " in a depth camera of its own",
          [&](const uint16_t* depth, uint16_t* moved) { to_depth_camera.apply(depth, moved); })) {
    return false;
  }
  if (!write_depth_camera_keys(out, p, depth_camera)) return false;
  std::printf("register it back with %s\n", (out + "/depth_camera.conf").c_str());
  return true;
}

bool dither_depth(const std::string& in, const std::string& out, const std::string& config,
                  unsigned seed) {
  Params p;
  if (!load_params(config, &p)) return false;
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> step(-1, 1);
  const SensorImageSize size = sensor_image_size(p);
  const size_t n = size.depth_pixels();
  return rewrite_depth(in, out, p, size.depth_width_px, size.depth_height_px,
                       "depth of " + in + " dithered by one raw unit, seed " + std::to_string(seed),
                       [&](const uint16_t* depth, uint16_t* dithered) {
                         for (size_t i = 0; i < n; ++i) {
                           const int v = depth[i];  // holes and the top value stay as they are
                           dithered[i] = static_cast<uint16_t>(
                               v == 0 || v == 65535 ? v : std::max(1, v + step(rng)));
                         }
                       });
}

bool sensor_noise_depth(const std::string& in, const std::string& out, const std::string& config,
                        unsigned seed, int block_px) {
  Params p;
  if (!load_params(config, &p)) return false;
  if (block_px < 1) return fail("the noise's block is at least one pixel");
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise_px(0.0, p.sensor.disparity_sigma_px);
  const SensorImageSize size = sensor_image_size(p);
  const int w = size.depth_width_px, h = size.depth_height_px;
  const int blocks_x = (w + block_px - 1) / block_px;
  std::vector<double> block_noise_px(static_cast<size_t>(blocks_x) *
                                     ((h + block_px - 1) / block_px));
  const double fb = p.sensor.depth_focal_px * p.sensor.baseline_m;
  const double quantum_px = p.sensor.disparity_quantum_px;
  return rewrite_depth(
      in, out, p, w, h,
      "depth of " + in + " with structured-light noise in " + std::to_string(block_px) +
          "-pixel blocks, seed " + std::to_string(seed),
      [&](const uint16_t* depth, uint16_t* noisy) {
        for (double& n : block_noise_px) n = noise_px(rng);
        for (int y = 0; y < h; ++y) {
          for (int x = 0; x < w; ++x) {
            const size_t i = static_cast<size_t>(y) * w + x;
            const int v = depth[i];  // holes and the top value stay as they are
            if (v == 0 || v == 65535) {
              noisy[i] = static_cast<uint16_t>(v);
              continue;
            }
            double disparity_px =
                fb * p.sensor.depth_factor / v +
                block_noise_px[static_cast<size_t>(y / block_px) * blocks_x + x / block_px];
            if (quantum_px > 0) disparity_px = std::round(disparity_px / quantum_px) * quantum_px;
            const double raw = disparity_px > 0 ? fb * p.sensor.depth_factor / disparity_px : 0;
            noisy[i] = static_cast<uint16_t>(raw >= 1 && raw < 65535 ? std::lround(raw) : 0);
          }
        }
      });
}

namespace {
bool write_png(const std::string& path, int w, int h, const uint8_t* px) {
  return write_png_gray8(path, w, h, px);
}
bool write_png(const std::string& path, int w, int h, const uint16_t* px) {
  return write_png_gray16(path, w, h, px);
}

// Replaces every image of one list (rgb.txt or depth.txt) with what draw(pixels) writes.
template <typename Pixel, typename Draw>
bool noise_list(const std::string& in, const std::string& out, const char* list, const char* folder,
                int w, int h, Draw draw) {
  std::vector<std::string> lines, written = {"# pure noise in place of the images of " + in};
  if (!read_lines(in + "/" + list, &lines) || ::mkdir((out + "/" + folder).c_str(), 0755) != 0) {
    return fail("cannot make the noise images of " + out + "/" + list);
  }
  std::vector<Pixel> pixels(static_cast<size_t>(w) * h);
  for (const std::string& l : lines) {
    if (!is_data_line(l)) continue;
    draw(&pixels);
    const std::string name = folder + ("/" + std::to_string(written.size() - 1) + ".png");
    if (!write_png(out + "/" + name, w, h, pixels.data()))
      return fail("cannot write " + out + "/" + name);
    written.push_back(stamp_of(l) + " " + name);
  }
  return write_lines(out + "/" + list, written);
}
}  // namespace

bool noise_sequence(const std::string& in, const std::string& out, const std::string& config,
                    const std::string& kind, unsigned seed) {
  Params p;
  if (!load_params(config, &p)) return false;
  const struct {
    const char* kind;
    double raw;
  } kStuck[] = {
      {"depth-1m", p.sensor.depth_factor}, {"depth-zero", 0.0}, {"depth-saturated", 65535.0}};
  double stuck_raw = -1.0;
  for (const auto& k : kStuck) {
    if (kind == k.kind) stuck_raw = k.raw;
  }
  const bool depth = kind == "depth" || kind == "both" || stuck_raw >= 0.0;
  const bool colour = kind == "colour" || kind == "both";
  if (!depth && !colour) {
    return fail("noise: the kind is depth, colour, both, depth-1m, depth-zero or depth-saturated");
  }
  if (!make_output(in, out) || !copy_file(in, out, "groundtruth.txt", true) ||
      !copy_file(in, out, "calib.txt", false)) {
    return false;
  }
  const int w = p.camera.width_px, h = p.camera.height_px;
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> intensity(0, 255);
  std::uniform_real_distribution<double> depth_m(p.sensor.depth_range.min_m,
                                                 p.sensor.depth_range.max_m);
  const bool colour_ok = colour ? noise_list<uint8_t>(in, out, "rgb.txt", "rgb", w, h,
                                                      [&](std::vector<uint8_t>* px) {
                                                        for (uint8_t& v : *px)
                                                          v = static_cast<uint8_t>(intensity(rng));
                                                      })
                                : copy_file(in, out, "rgb.txt", true) && link_into(in, out, "rgb");
  const bool depth_ok =
      depth ? noise_list<uint16_t>(
                  in, out, "depth.txt", "depth", w, h,
                  [&](std::vector<uint16_t>* px) {
                    for (uint16_t& v : *px) {
                      v = static_cast<uint16_t>(std::lround(
                          stuck_raw >= 0.0 ? stuck_raw : depth_m(rng) * p.sensor.depth_factor));
                    }
                  })
            : copy_file(in, out, "depth.txt", true) && link_into(in, out, "depth");
  return colour_ok && depth_ok;
}

bool two_camera_sequence(const std::string& out, int frames, const DepthCameraShape& shape) {
  if (frames < 2 || frames > kTwoCameraFrames) {
    return fail("two-camera: 2 to " + std::to_string(kTwoCameraFrames) +
                " frames (later the camera is too near the box to track)");
  }
  if (!valid_shape("two-camera", shape)) return false;
  constexpr double kFps = 30.0;
  SyntheticScene scene;
  scene.diagonal_path = true;  // parallax: the box hides other wall from each camera
  const Params p = synthetic_params(scene);
  const DepthCameraParams depth_camera = depth_camera_beside(scene.camera, shape);
  SyntheticScene depth_scene = scene;
  depth_scene.camera = depth_camera.intrinsics;
  const std::string exact = out + "/exact", own = out + "/depth_camera";
  if (!create_folder(out) || !create_folder(exact) || !create_folder(own) ||
      !write_synthetic_sequence(exact, scene, frames, kFps) ||
      !write_text(exact + "/camera.conf", synthetic_config(scene))) {
    return fail("cannot write the synthetic sequence into " + exact);
  }
  // The same colour frames with depth as the depth camera sees it, and that depth registered
  // to colour compared with the exact depth: every pixel both cameras see (its exact point
  // projects into the depth camera onto that point's own depth), and those within 2 px of an
  // occlusion edge (a neighbour's depth 5 % off) apart.
  const SE3 T_d_c = depth_camera.T_c_d.inverse();
  const PinholeIntrinsics& kd = depth_camera.intrinsics;
  DepthRegistration registration;
  registration.init(CameraModel{depth_camera.intrinsics, depth_camera.distortion},
                    CameraModel{scene.camera, RadTanDistortion()}, depth_camera.T_c_d,
                    scene.depth_factor);
  const std::vector<SyntheticFrame>& rendered = scene.render_path(frames, kFps);
  const int w = scene.camera.width_px, h = scene.camera.height_px;
  std::vector<uint16_t> registered(static_cast<size_t>(w) * h);
  std::vector<float> errors_mm, edge_errors_mm;
  long exact_pixels = 0, filled = 0, wrong = 0, edge_pixels = 0, edge_filled = 0;
  SyntheticFrame shown;
  const bool written = write_sequence(
      own, {w, h, kd.width_px, kd.height_px}, frames, kFps,
      [&](int i, SE3* T_w_c) -> const SyntheticFrame& {
        *T_w_c = scene.camera_at(i / kFps);
        const SyntheticFrame& colour = rendered[static_cast<size_t>(i)];
        shown.gray = colour.gray;
        shown.depth = depth_scene.render(*T_w_c * depth_camera.T_c_d).depth;
        registration.apply(shown.depth.data(), registered.data());
        const std::vector<uint16_t>& truth = colour.depth;
        for (int y = 2; y < h - 2; ++y) {
          for (int x = 2; x < w - 2; ++x) {
            const size_t at = static_cast<size_t>(y) * w + x;
            if (truth[at] == 0) continue;
            const double z = truth[at] / scene.depth_factor;
            const Vector3d in_depth_camera =
                T_d_c * Vector3d((x - scene.camera.cx_px) / scene.camera.fx_px * z,
                                 (y - scene.camera.cy_px) / scene.camera.fy_px * z, z);
            const int u = static_cast<int>(std::lround(
                          kd.fx_px * in_depth_camera.x() / in_depth_camera.z() + kd.cx_px)),
                      v = static_cast<int>(std::lround(
                          kd.fy_px * in_depth_camera.y() / in_depth_camera.z() + kd.cy_px));
            if (u < 0 || v < 0 || u >= kd.width_px || v >= kd.height_px) continue;
            const double seen =
                shown.depth[static_cast<size_t>(v) * kd.width_px + u] / scene.depth_factor;
            if (std::fabs(seen - in_depth_camera.z()) > 0.02 * in_depth_camera.z()) continue;
            bool edge = false;
            for (int dy = -2; dy <= 2; ++dy) {
              for (int dx = -2; dx <= 2; ++dx) {
                const double n = truth[at + static_cast<size_t>(dy * w + dx)];
                edge = edge || std::fabs(n - truth[at]) > 0.05 * truth[at];
              }
            }
            ++(edge ? edge_pixels : exact_pixels);
            if (registered[at] == 0) continue;
            ++(edge ? edge_filled : filled);
            const float e_mm = static_cast<float>(std::fabs(double(registered[at]) - truth[at]) /
                                                  scene.depth_factor * 1000.0);
            (edge ? edge_errors_mm : errors_mm).push_back(e_mm);
            if (e_mm > 50.0 * truth[at] / scene.depth_factor) ++wrong;
          }
        }
        return shown;
      });
  if (!written || !write_text(own + "/camera.conf", synthetic_config(scene)) ||
      !write_depth_camera_keys(own, p, depth_camera)) {
    return fail("cannot write " + own);
  }
  auto percentile = [](std::vector<float>* v, double q) {
    if (v->empty()) return 0.0f;
    const size_t k = static_cast<size_t>(q * static_cast<double>(v->size() - 1));
    std::nth_element(v->begin(), v->begin() + static_cast<long>(k), v->end());
    return (*v)[k];
  };
  std::printf(
      "%s: %d frames, colour with exact depth (exact/) and with its own depth camera's "
      "(depth_camera/, keys in depth_camera/depth_camera.conf)\n"
      "registered against exact: %.2f %% of the pixels both see filled, error median %.2f mm, "
      "95th percentile %.2f mm; within 2 px of an occlusion edge %.2f %% filled, median %.2f "
      "mm, 95th percentile %.2f mm; %.3f %% of all on another surface (over 5 %% off)\n",
      out.c_str(), frames, 100.0 * filled / std::max(1L, exact_pixels), percentile(&errors_mm, 0.5),
      percentile(&errors_mm, 0.95), 100.0 * edge_filled / std::max(1L, edge_pixels),
      percentile(&edge_errors_mm, 0.5), percentile(&edge_errors_mm, 0.95),
      100.0 * wrong / std::max(1L, filled + edge_filled));
  return true;
}

SyntheticScene pan_scene(double peak_deg_s) {
  SyntheticScene scene;
  scene.pan_peak_deg_s = peak_deg_s;
  scene.max_depth_m = 4.0;  // a structured-light sensor's range; the back wall stays in it
  return scene;
}

bool pan_sequence(const std::string& out, double peak_deg_s, int frames, double fps,
                  double depth_late_ms, double readout_ms) {
  if (!(peak_deg_s > 0.0) || frames < 2 || !(fps > 0.0)) {
    return fail("pan: the rate, the frame count and the frame rate must be positive");
  }
  // Within the pairing's 20 ms, as a Kinect's two streams are after it.
  if (!(std::fabs(depth_late_ms) <= 15.0)) return fail("pan: --depth-late-ms within +-15 ms");
  if (!(readout_ms >= 0.0 && readout_ms * fps <= 1e3)) {
    return fail("pan: --readout-ms from 0 to the frame interval");
  }
  const SyntheticScene scene = pan_scene(peak_deg_s);
  if (!create_folder(out) ||
      !write_synthetic_sequence(out, scene, frames, fps, 1e-3 * depth_late_ms, 1e-3 * readout_ms) ||
      !write_text(out + "/camera.conf", synthetic_config(scene))) {
    return fail("cannot write the synthetic sequence into " + out);
  }
  std::printf(
      "%s: %d frames at %.0f Hz, pan peaking at %.0f deg/s, depth %.1f ms after colour, "
      "colour read out over %.1f ms (config: camera.conf)\n",
      out.c_str(), frames, fps, peak_deg_s, depth_late_ms, readout_ms);
  return true;
}

bool wall_sequence(const std::string& out, double distance_m, double yaw_deg, int frames) {
  if (!(distance_m > 0.3) || !(std::fabs(yaw_deg) < 60.0) || frames < 1) {
    return fail("wall: the distance must be over 0.3 m, the yaw within +-60 deg, frames >= 1");
  }
  SyntheticScene scene;  // its camera and depth units
  const PinholeIntrinsics& k = scene.camera;
  // Camera frame: the body is the boards' forward mounting (x forward = camera z, y right =
  // camera x), so the wall's normal, at yaw_deg clockwise from forward, is (sin, 0, cos).
  const double yaw = yaw_deg * M_PI / 180.0;
  const Vector3d normal(std::sin(yaw), 0.0, std::cos(yaw)),
      along(std::cos(yaw), 0.0, -std::sin(yaw));
  SyntheticFrame f;
  f.gray.resize(static_cast<size_t>(k.width_px) * k.height_px);
  f.depth.resize(f.gray.size());
  for (int v = 0; v < k.height_px; ++v) {
    for (int u = 0; u < k.width_px; ++u) {
      const Vector3d ray((u - k.cx_px) / k.fx_px, (v - k.cy_px) / k.fy_px, 1.0);
      const double z = distance_m / normal.dot(ray);  // the ray's depth where it meets the wall
      const Vector3d p = z * ray;
      // 10 cm squares, so that tracking has edges to hold on to.
      const bool light = (static_cast<int>(std::floor(p.dot(along) / 0.1)) +
                          static_cast<int>(std::floor(p.y() / 0.1))) %
                             2 !=
                         0;
      const size_t i = static_cast<size_t>(v) * k.width_px + u;
      f.gray[i] = light ? 200 : 60;
      f.depth[i] = z > 0 && z < scene.max_depth_m
                       ? static_cast<uint16_t>(std::lround(z * scene.depth_factor))
                       : 0;
    }
  }
  const bool ok = create_folder(out) &&
                  write_sequence(out, same_size(k.width_px, k.height_px), frames, 30.0,
                                 [&](int, SE3* T_w_c) -> const SyntheticFrame& {
                                   *T_w_c = SE3();
                                   return f;
                                 }) &&
                  write_text(out + "/camera.conf", synthetic_config(scene));
  if (!ok) return fail("cannot write the wall sequence into " + out);
  std::printf(
      "%s: %d frames of a wall %.2f m from the camera, its normal at %.1f deg "
      "(config: camera.conf)\n",
      out.c_str(), frames, distance_m, yaw_deg);
  return true;
}

bool concatenate(const std::string& first, const std::string& second, const std::string& out,
                 double gap_s) {
  const char* names[3] = {"rgb.txt", "depth.txt", "groundtruth.txt"};
  std::vector<std::string> lists[2][3];
  for (int k = 0; k < 2; ++k) {
    for (int i = 0; i < 3; ++i) {
      if (!read_lines((k == 0 ? first : second) + "/" + names[i], &lists[k][i])) return false;
    }
  }
  auto colour_span = [&](int k, double* begin, double* end) {
    *begin = 1e300;
    *end = -1e300;
    for (const std::string& l : lists[k][0]) {
      if (!is_data_line(l)) continue;
      *begin = std::min(*begin, std::atof(l.c_str()));
      *end = std::max(*end, std::atof(l.c_str()));
    }
    return *end >= *begin;
  };
  double b0, e0, b1, e1;
  if (!colour_span(0, &b0, &e0) || !colour_span(1, &b1, &e1)) {
    return fail("concat: no colour frames in an input");
  }
  // The second's stamps move to begin gap_s after the first's last frame. Both keep their ground
  // truth (the same motion-capture frame for variants of one sequence), split halfway through
  // the gap.
  const double shift = e0 + gap_s - b1;
  const double split = e0 + 0.5 * gap_s;
  auto link_as = [&](const std::string& in, const char* name) {
    char real[PATH_MAX];
    if (::realpath(in.c_str(), real) == nullptr) return fail("missing " + in);
    return ::symlink(real, (out + "/" + name).c_str()) == 0 || fail("cannot link " + out);
  };
  if (!create_folder(out) || !link_as(first, "a") || !link_as(second, "b")) return false;
  for (int i = 0; i < 3; ++i) {
    const bool images = i < 2;
    std::vector<std::string> result = {"# " + std::string(names[i]) + " of " + first + ", then " +
                                       second + " from " + std::to_string(gap_s) + " s later"};
    for (int k = 0; k < 2; ++k) {
      for (const std::string& l : lists[k][i]) {
        if (!is_data_line(l)) continue;
        const double t = std::atof(l.c_str()) + (k == 1 ? shift : 0.0);
        if (!images && (k == 0 ? t > split : t <= split)) continue;
        char stamp[32];
        std::snprintf(stamp, sizeof(stamp), "%.6f", t);
        const std::string rest = l.substr(l.find_first_of(" \t"));
        const size_t file = rest.find_first_not_of(" \t");
        result.push_back(images
                             ? std::string(stamp) + " " + (k == 0 ? "a/" : "b/") + rest.substr(file)
                             : stamp + rest);
      }
    }
    if (!write_lines(out + "/" + names[i], result)) return false;
  }
  return copy_file(first, out, "calib.txt", false);
}

bool degenerate_sequence(const std::string& out, const std::string& layout, int frames) {
  SyntheticScene scene;
  if (layout == "corridor") {
    scene.layout = SyntheticScene::Layout::kCorridor;
  } else if (layout == "room") {
    scene.layout = SyntheticScene::Layout::kPlainRoom;
  } else {
    return fail("degenerate: the scene is corridor or room, not '" + layout + "'");
  }
  if (frames < 2) return fail("degenerate: needs at least 2 frames");
  scene.max_depth_m = 4.0;  // a structured-light sensor's range
  constexpr double kFps = 30.0;
  if (!create_folder(out) || !write_synthetic_sequence(out, scene, frames, kFps) ||
      !write_text(out + "/camera.conf", synthetic_config(scene))) {
    return fail("cannot write the synthetic sequence into " + out);
  }
  std::printf("%s: %d frames at 30 Hz of the %s (config: camera.conf)\n", out.c_str(), frames,
              layout.c_str());
  return true;
}

bool there_and_back(const std::string& in, const std::string& out, const std::string& config) {
  Params p;
  if (!load_params(config, &p)) return false;
  const double offset_s = static_cast<double>(p.sensor.depth_time_offset_ns) * 1e-9;
  std::vector<std::string> lists[3];
  const char* names[3] = {"rgb.txt", "depth.txt", "groundtruth.txt"};
  for (int i = 0; i < 3; ++i) {
    if (!read_lines(in + "/" + names[i], &lists[i])) return false;
  }
  double last = -1.0;
  for (const std::string& l : lists[0]) {
    if (is_data_line(l)) last = std::max(last, std::atof(l.c_str()));
  }
  if (last < 0.0) return fail("there-and-back: no colour frames in " + in);
  if (!make_output(in, out)) return false;
  for (int i = 0; i < 3; ++i) {
    std::vector<std::string> data;
    for (const std::string& l : lists[i]) {
      if (is_data_line(l)) data.push_back(l);
    }
    std::vector<std::string> result = {"# " + std::string(names[i]) + " of " + in +
                                       ", then backwards with mirrored stamps"};
    result.insert(result.end(), data.begin(), data.end());
    // Mirror about the last colour stamp (depth: shifted by twice the pairing offset).
    const double centre = 2.0 * last + (i == 1 ? 2.0 * offset_s : 0.0);
    for (auto it = data.rbegin(); it != data.rend(); ++it) {
      const double t = std::atof(it->c_str());
      const double mirrored = centre - t;
      if (mirrored <= (i == 1 ? last + 2.0 * offset_s : last)) continue;
      char stamp[32];
      std::snprintf(stamp, sizeof(stamp), "%.6f", mirrored);
      result.push_back(stamp + it->substr(it->find_first_of(" \t")));
    }
    if (!write_lines(out + "/" + names[i], result)) return false;
  }
  return copy_file(in, out, "calib.txt", false) && link_into(in, out, "rgb") &&
         link_into(in, out, "depth");
}

}  // namespace rgbdtam::testing

namespace rgbdtam::testing {

bool wander_sequence(const std::string& in, const std::string& out, const std::string& config,
                     int frames, unsigned seed) {
  if (frames < 2) return fail("wander: needs at least 2 frames");
  Params p;
  if (!load_params(config, &p)) return false;
  std::vector<std::string> rgb, depth;
  std::vector<StampedPose> gt;
  int bad = 0;
  if (!read_lines(in + "/rgb.txt", &rgb) || !read_lines(in + "/depth.txt", &depth)) return false;
  if (!read_tum_trajectory((in + "/groundtruth.txt").c_str(), &gt, &bad).is_ok()) {
    return fail("wander: cannot read " + in + "/groundtruth.txt");
  }
  const Trajectory truth(gt);
  // The playable frames: a colour frame, the depth replay pairs with it, and its true pose.
  const double offset_s = static_cast<double>(p.sensor.depth_time_offset_ns) * 1e-9;
  constexpr double kMaxPairingS = 0.02;  // as rgbdtam replay pairs them
  struct Playable {
    double t_s;
    std::string rgb_file, depth_file;
    SE3 T_w_c;
  };
  std::vector<Playable> playable;
  for (const std::string& l : rgb) {
    if (!is_data_line(l)) continue;
    const double t = std::atof(l.c_str());
    const int d = nearest_line(depth, t + offset_s);
    SE3 T;
    if (d < 0 ||
        std::fabs(std::atof(depth[static_cast<size_t>(d)].c_str()) - t - offset_s) >=
            kMaxPairingS ||
        !truth.at(t, &T)) {
      continue;
    }
    playable.push_back({t, file_of(l), file_of(depth[static_cast<size_t>(d)]), T});
  }
  const int n = static_cast<int>(playable.size());
  if (n < 2) return fail("wander: fewer than 2 frames of " + in + " have depth and ground truth");
  // Segments of a tenth to a half of the sequence, forwards or backwards, at 1x or 2x; every
  // fifth begins after an outage of 0.5-2 s, somewhere else in it.
  std::mt19937 rng(seed);
  auto uniform = [&](double a, double b) { return std::uniform_real_distribution<>(a, b)(rng); };
  constexpr double kFps = 30.0;
  std::vector<std::string> rgb_out = {"# a wander of " + std::to_string(frames) + " frames over " +
                                      in + " (seed " + std::to_string(seed) + ")"};
  std::vector<std::string> depth_out = rgb_out, gt_out = rgb_out;
  double t = playable[0].t_s;
  int at = 0, direction = 1, step = 1, left = 0, segments = 0, outages = 0;
  char line[256];
  for (int played = 0; played < frames; ++played) {
    if (left == 0) {
      ++segments;
      left = std::max(2, static_cast<int>(uniform(0.1, 0.5) * n));
      step = uniform(0, 1) < 0.7 ? 1 : 2;
      direction = uniform(0, 1) < 0.5 ? 1 : -1;
      if (segments % 5 == 0) {
        ++outages;
        t += uniform(0.5, 2.0);
        at = static_cast<int>(uniform(0, n));
      }
    }
    if (at + direction * step < 0 || at + direction * step >= n) direction = -direction;
    const Playable& f = playable[static_cast<size_t>(at)];
    std::snprintf(line, sizeof(line), "%.6f %s", t, f.rgb_file.c_str());
    rgb_out.push_back(line);
    std::snprintf(line, sizeof(line), "%.6f %s", t + offset_s, f.depth_file.c_str());
    depth_out.push_back(line);
    const Vector3d& x = f.T_w_c.translation();
    const Eigen::Quaterniond& q = f.T_w_c.quaternion();
    std::snprintf(line, sizeof(line), "%.6f %.7f %.7f %.7f %.7f %.7f %.7f %.7f", t, x.x(), x.y(),
                  x.z(), q.x(), q.y(), q.z(), q.w());
    gt_out.push_back(line);
    at = std::clamp(at + direction * step, 0, n - 1);
    t += 1.0 / kFps;
    --left;
  }
  if (!make_output(in, out) || !write_lines(out + "/rgb.txt", rgb_out) ||
      !write_lines(out + "/depth.txt", depth_out) ||
      !write_lines(out + "/groundtruth.txt", gt_out) || !copy_file(in, out, "calib.txt", false) ||
      !link_into(in, out, "rgb") || !link_into(in, out, "depth")) {
    return false;
  }
  std::printf("%s: %d frames of %s in %d segments, %d outages with a jump\n", out.c_str(), frames,
              in.c_str(), segments, outages);
  return true;
}

}  // namespace rgbdtam::testing
