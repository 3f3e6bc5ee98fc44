#pragma once
// Writes PNGs and whole TUM RGB-D folders, so tests can build sequences (and break them).

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "rgbdtam/core/pyramid.hpp"
#include "rgbdtam/runtime/params.hpp"
#include "synthetic_scene.hpp"

namespace rgbdtam::testing {

bool write_png_gray8(const std::string& path, int w, int h, const uint8_t* px);
bool write_png_rgb8(const std::string& path, int w, int h, const uint8_t* rgb);
bool write_png_gray16(const std::string& path, int w, int h, const uint16_t* px);
// A grey image as the colour JPEG a UVC camera sends in MJPEG mode (YCbCr, 4:2:2 chroma).
std::vector<uint8_t> encode_jpeg(const uint8_t* gray, int w, int h, int quality);

// Depth is rendered with its colour image and stamped this much after it: an offset of the
// stamps, not time between the images, as synthetic_params and synthetic_config say
// (depth.time_offset_ms), so that pairing is by nearest stamp and no depth is moved in time.
constexpr int64_t kDepthStampOffsetNs = 5'000'000;

// A TUM folder (rgb/, depth/, rgb.txt, depth.txt, groundtruth.txt, camera-to-world) of
// `frames` frames at `fps`: frame(i, &T_w_c) gives each, its depth at size's depth size, taken
// depth_late_s after its colour image and stamped so.
bool write_sequence(const std::string& dir, const SensorImageSize& size, int frames, double fps,
                    const std::function<const SyntheticFrame&(int, SE3*)>& frame,
                    double depth_late_s = 0.0);
// Renders `frames` frames of the scene's path at `fps` into a TUM folder (write_sequence), each
// depth image from where the camera was depth_late_s after its colour image. With a rolling
// shutter (readout_s > 0) the colour image's rows are exposed top to bottom over readout_s,
// its middle row at the image's stamp (where the ground truth is).
bool write_synthetic_sequence(const std::string& dir, const SyntheticScene& scene, int frames,
                              double fps, double depth_late_s = 0.0, double readout_s = 0.0);
// Parameters matching the scene's camera and its exact sensor, whose disparity noise is the
// matcher's own 0.1 px, not the effective 0.4 px that covers a real Kinect's registration and
// timing errors.
Params synthetic_params(const SyntheticScene& scene);
// A rendered frame as tracking sees it: undistorted with p's camera, its depth with p's sensor.
void synthetic_pyramid(const SyntheticFrame& f, const Params& p, FramePyramid* out);
// The config text matching the scene's camera.
std::string synthetic_config(const SyntheticScene& scene);
bool write_text(const std::string& path, const std::string& text);

}  // namespace rgbdtam::testing
