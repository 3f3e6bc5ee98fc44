#include "tum_writer.hpp"

#include <png.h>
#include <sys/stat.h>

// clang-format off
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <jpeglib.h>  // needs <cstdio> first
// clang-format on

namespace rgbdtam::testing {
namespace {
bool write_png(const std::string& path, int w, int h, int bit_depth, int color_type,
               const void* data, int bytes_per_row) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return false;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(f);
    return false;
  }
  png_init_io(png, f);
  // Fast deflate, as the recorder's encoder: the tests write thousands of these images, and
  // the default level spent more time compressing them than rendering them.
  png_set_compression_level(png, 1);
  png_set_filter(png, 0, PNG_FILTER_SUB);
  png_set_IHDR(png, info, static_cast<png_uint_32>(w), static_cast<png_uint_32>(h), bit_depth,
               color_type, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  if (bit_depth == 16) png_set_swap(png);
  for (int y = 0; y < h; ++y) {
    png_write_row(png, static_cast<png_const_bytep>(data) + static_cast<size_t>(y) * bytes_per_row);
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return std::fclose(f) == 0;
}

void stamp(double t, char* buf, size_t n) { std::snprintf(buf, n, "%.6f", t); }

void write_pose(std::FILE* f, double t, const SE3& T) {
  const Vector3d& p = T.translation();
  const Eigen::Quaterniond& q = T.quaternion();
  std::fprintf(f, "%.6f %.7f %.7f %.7f %.7f %.7f %.7f %.7f\n", t, p.x(), p.y(), p.z(), q.x(), q.y(),
               q.z(), q.w());
}
}  // namespace

bool write_png_gray8(const std::string& path, int w, int h, const uint8_t* px) {
  return write_png(path, w, h, 8, PNG_COLOR_TYPE_GRAY, px, w);
}
bool write_png_rgb8(const std::string& path, int w, int h, const uint8_t* rgb) {
  return write_png(path, w, h, 8, PNG_COLOR_TYPE_RGB, rgb, 3 * w);
}
bool write_png_gray16(const std::string& path, int w, int h, const uint16_t* px) {
  return write_png(path, w, h, 16, PNG_COLOR_TYPE_GRAY, px, 2 * w);
}

bool write_text(const std::string& path, const std::string& text) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return false;
  std::fputs(text.c_str(), f);
  return std::fclose(f) == 0;
}

bool write_sequence(const std::string& dir, const SensorImageSize& size, int frames, double fps,
                    const std::function<const SyntheticFrame&(int, SE3*)>& frame,
                    double depth_late_s) {
  ::mkdir((dir + "/rgb").c_str(), 0755);
  ::mkdir((dir + "/depth").c_str(), 0755);
  std::FILE* rgb = std::fopen((dir + "/rgb.txt").c_str(), "w");
  std::FILE* depth = std::fopen((dir + "/depth.txt").c_str(), "w");
  std::FILE* gt = std::fopen((dir + "/groundtruth.txt").c_str(), "w");
  if (rgb == nullptr || depth == nullptr || gt == nullptr) return false;
  std::fputs("# color images\n# timestamp filename\n", rgb);
  std::fputs("# depth maps\n# timestamp filename\n", depth);
  std::fputs("# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n", gt);
  bool ok = true;
  const double t0 = 1000.0;  // like the benchmark, stamps far from zero
  for (int i = 0; i < frames && ok; ++i) {
    const double t = i / fps;
    SE3 T_w_c;
    const SyntheticFrame& f = frame(i, &T_w_c);
    char rs[32], ds[32];
    stamp(t0 + t, rs, sizeof(rs));
    stamp(t0 + t + depth_late_s + 1e-9 * kDepthStampOffsetNs, ds, sizeof(ds));
    ok = write_png_gray8(dir + "/rgb/" + rs + ".png", size.width_px, size.height_px,
                         f.gray.data()) &&
         write_png_gray16(dir + "/depth/" + ds + ".png", size.depth_width_px, size.depth_height_px,
                          f.depth.data());
    std::fprintf(rgb, "%s rgb/%s.png\n", rs, rs);
    std::fprintf(depth, "%s depth/%s.png\n", ds, ds);
    write_pose(gt, t0 + t, T_w_c);
  }
  ok = (std::fclose(rgb) == 0) && ok;
  ok = (std::fclose(depth) == 0) && ok;
  ok = (std::fclose(gt) == 0) && ok;
  return ok;
}

bool write_synthetic_sequence(const std::string& dir, const SyntheticScene& scene, int frames,
                              double fps, double depth_late_s, double readout_s) {
  const SensorImageSize size = same_size(scene.camera.width_px, scene.camera.height_px);
  if (depth_late_s == 0.0 && readout_s == 0.0) {
    const std::vector<SyntheticFrame>& rendered = scene.render_path(frames, fps);
    return write_sequence(dir, size, frames, fps, [&](int i, SE3* T_w_c) -> const SyntheticFrame& {
      *T_w_c = scene.camera_at(i / fps);
      return rendered[static_cast<size_t>(i)];
    });
  }
  const double last_row = scene.camera.height_px - 1;
  SyntheticFrame f;
  return write_sequence(
      dir, size, frames, fps,
      [&](int i, SE3* T_w_c) -> const SyntheticFrame& {
        const double t = i / fps;
        *T_w_c = scene.camera_at(t);
        f = scene.render_rows(
            [&](int y) { return scene.camera_at(t + (y / last_row - 0.5) * readout_s); });
        f.depth = scene.render(scene.camera_at(t + depth_late_s)).depth;
        return f;
      },
      depth_late_s);
}

Params synthetic_params(const SyntheticScene& scene) {
  Params p;
  p.camera = scene.camera;
  p.distortion = RadTanDistortion();
  p.sensor.depth_factor = scene.depth_factor;
  p.sensor.depth_range.max_m = 10.0;
  p.sensor.disparity_sigma_px = 0.1;
  p.sensor.depth_time_offset_ns = kDepthStampOffsetNs;
  return p;
}

void synthetic_pyramid(const SyntheticFrame& f, const Params& p, FramePyramid* out) {
  Undistorter undistorter;
  undistorter.init(p.camera, p.distortion);
  out->allocate(p.camera, p.sensor.depth_factor, p.sensor.depth_range);
  undistorter.undistort_gray(f.gray.data(), &out->gray(0));
  out->build_gray();
  out->build_inverse_depth(f.depth.data(), undistorter);
}

std::string synthetic_config(const SyntheticScene& s) {
  char buf[512];
  std::snprintf(buf, sizeof(buf),
                "camera.width = %d\ncamera.height = %d\ncamera.fx = %.6f\ncamera.fy = %.6f\n"
                "camera.cx = %.6f\ncamera.cy = %.6f\ndepth.factor = %.1f\ndepth.max = 10\n"
                "depth.time_offset_ms = %g\n",
                s.camera.width_px, s.camera.height_px, s.camera.fx_px, s.camera.fy_px,
                s.camera.cx_px, s.camera.cy_px, s.depth_factor, 1e-6 * kDepthStampOffsetNs);
  return buf;
}

std::vector<uint8_t> encode_jpeg(const uint8_t* gray, int w, int h, int quality) {
  jpeg_compress_struct c{};  // libjpeg keeps client_data as given: zero, not stack garbage
  jpeg_error_mgr error;
  c.err = jpeg_std_error(&error);
  jpeg_create_compress(&c);
  unsigned char* out = nullptr;
  unsigned long size = 0;
  jpeg_mem_dest(&c, &out, &size);
  c.image_width = static_cast<JDIMENSION>(w);
  c.image_height = static_cast<JDIMENSION>(h);
  c.input_components = 3;
  c.in_color_space = JCS_RGB;
  jpeg_set_defaults(&c);
  jpeg_set_quality(&c, quality, TRUE);
  c.comp_info[0].h_samp_factor = 2;  // 4:2:2, as UVC cameras send
  c.comp_info[0].v_samp_factor = 1;
  jpeg_start_compress(&c, TRUE);
  std::vector<uint8_t> row(static_cast<size_t>(w) * 3);
  while (c.next_scanline < c.image_height) {
    const uint8_t* in = gray + static_cast<size_t>(c.next_scanline) * w;
    for (int x = 0; x < w; ++x) row[3 * x] = row[3 * x + 1] = row[3 * x + 2] = in[x];
    JSAMPROW rows[1] = {row.data()};
    jpeg_write_scanlines(&c, rows, 1);
  }
  jpeg_finish_compress(&c);
  std::vector<uint8_t> jpeg(out, out + size);
  jpeg_destroy_compress(&c);
  std::free(out);
  return jpeg;
}

}  // namespace rgbdtam::testing
