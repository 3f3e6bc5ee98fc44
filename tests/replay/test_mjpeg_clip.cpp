// A UVC camera sending MJPEG: the committed clip's frames as JPEGs from a fake V4L2 device
// (ClipCamera, driven by the reader so that every frame arrives on any machine), decoded by the
// V4L2 backend and tracked, as accurate as the same clip sent as YUYV. Also the decode time per
// frame.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

#include "clip_camera.hpp"
#include "rgbdtam/hal/file.hpp"
#include "rgbdtam/hal/jpeg_decoder.hpp"
#include "rgbdtam/hal/tum_trajectory.hpp"
#include "rgbdtam/hal/v4l2_source.hpp"
#include "rgbdtam/runtime/tracking_pipeline.hpp"
#include "test_paths.hpp"
#include "tum_writer.hpp"

namespace rgbdtam {
namespace {

constexpr int kW = 640, kH = 480;

struct Clip {
  std::vector<std::vector<uint8_t>> gray;
  std::vector<std::vector<uint16_t>> depth;
  std::vector<int64_t> stamps_ns;
  std::vector<std::vector<uint8_t>> jpeg;
};

const Clip& clip() {
  static Clip c;
  if (c.gray.empty()) {
    EXPECT_TRUE(testing::ClipCamera::load(testing::source_path("data/tum_fr1_xyz_clip"), &c.gray,
                                          &c.depth, &c.stamps_ns));
    for (const auto& g : c.gray) c.jpeg.push_back(testing::encode_jpeg(g.data(), kW, kH, 90));
  }
  return c;
}

Params clip_params() {
  Params p;
  char* text = nullptr;
  EXPECT_TRUE(
      read_text_file(testing::source_path("config/tum_fr1.conf").c_str(), 1 << 20, &text).is_ok());
  EXPECT_TRUE(parse_params(text, "tum_fr1.conf", &p).is_ok());
  delete[] text;
  p.map_enabled = false;
  return p;
}

// The clip's first 20 frames (0.7 s, 10 cm of motion) compare the two as well as all of it, in a
// third of the time under qemu.
constexpr int64_t kFramesCompared = 20;

// Tracks what the camera delivers until the first kFramesCompared have played; poses at the
// clip's stamps.
std::vector<StampedPose> track_camera(bool mjpeg, int* frames_delivered) {
  const Clip& c = clip();
  testing::ClipCamera camera(c.gray, c.depth, kW, kH, 10.0, {});
  if (mjpeg) camera.send_mjpeg(c.jpeg);
  camera.drive_by_reader();  // both runs see the same frames, however slow the machine
  V4l2Source source;
  const Status opened =
      source.open(&camera, "/dev/soak-depth", "/dev/soak-colour", same_size(kW, kH), 20'000'000,
                  1000, mjpeg ? V4l2Colour::kMjpeg : V4l2Colour::kYuyv);
  EXPECT_TRUE(opened.is_ok()) << opened.message();
  const Params params = clip_params();
  KeyframePool keyframes;
  KeyframeBuildTask building;
  TrackingPipeline pipeline;
  EXPECT_TRUE(pipeline.init(params, &keyframes, &building).is_ok());
  std::vector<StampedPose> poses;
  *frames_delivered = 0;
  for (;;) {
    SensorFrame f;
    Status warning;
    const Status s = source.next(&f, &warning);
    if (!s.is_ok()) {
      ADD_FAILURE() << s.message();
      break;
    }
    const int64_t index = camera.frame_of(f.timestamp_ns);
    if (index >= std::min<int64_t>(kFramesCompared, c.gray.size())) break;
    ++*frames_delivered;
    const PoseEstimate pose = pipeline.process(f);
    if ((pose.flags & kPoseValid) != 0) {
      poses.push_back({c.stamps_ns[static_cast<size_t>(index)] * 1e-9, pose.T_w_c});
    }
  }
  return poses;
}

TEST(MjpegClip, TheClipSentAsMjpegIsDecodedAndTrackedAsWellAsItsYuyv) {
  const std::string dir = testing::source_path("data/tum_fr1_xyz_clip");
  std::vector<StampedPose> gt;
  int bad = 0;
  ASSERT_TRUE(read_tum_trajectory((dir + "/groundtruth.txt").c_str(), &gt, &bad).is_ok());
  int yuyv_frames = 0, mjpeg_frames = 0;
  const std::vector<StampedPose> yuyv = track_camera(false, &yuyv_frames);
  const std::vector<StampedPose> mjpeg = track_camera(true, &mjpeg_frames);
  AteResult ate_yuyv, ate_mjpeg;
  ASSERT_TRUE(evaluate_ate(gt, yuyv, &ate_yuyv));
  ASSERT_TRUE(evaluate_ate(gt, mjpeg, &ate_mjpeg));
  const FalseValidResult fv = evaluate_false_valid(gt, mjpeg);
  size_t jpeg_bytes = 0;
  for (const auto& j : clip().jpeg) jpeg_bytes += j.size();
  std::printf(
      "clip as YUYV: %d frames, %zu tracked, ATE %.3f cm; as MJPEG (quality 90, %.1f kB a frame): "
      "%d frames, %zu tracked, ATE %.3f cm, %d false-valid of %d\n",
      yuyv_frames, yuyv.size(), ate_yuyv.rmse_m * 100, jpeg_bytes / 1024.0 / clip().jpeg.size(),
      mjpeg_frames, mjpeg.size(), ate_mjpeg.rmse_m * 100, fv.count, fv.checked);
  EXPECT_GE(mjpeg.size(), static_cast<size_t>(mjpeg_frames) - 1) << "every frame tracked";
  EXPECT_EQ(fv.count, 0);
  EXPECT_LT(ate_mjpeg.rmse_m, 0.015);
  EXPECT_LT(ate_mjpeg.rmse_m, ate_yuyv.rmse_m + 0.003) << "JPEG's loss costs little";
}

TEST(MjpegClip, DecodeTimePerFrame) {
  const Clip& c = clip();
  JpegDecoder decoder;
  ASSERT_TRUE(decoder.open(kW, kH).is_ok());
  std::vector<uint8_t> gray(kW * kH);
  std::vector<double> ms;
  for (int round = 0; round < 3; ++round) {
    for (const auto& j : c.jpeg) {
      const auto t0 = std::chrono::steady_clock::now();
      ASSERT_TRUE(decoder.decode(j.data(), j.size(), gray.data()).is_ok());
      ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    }
  }
  std::sort(ms.begin(), ms.end());
  std::printf(
      "MJPEG 640x480 to grey: median %.2f ms, max %.2f ms over %zu decodes; libjpeg's "
      "arena peak %zu kB of %zu kB\n",
      ms[ms.size() / 2], ms.back(), ms.size(), decoder.arena().peak_bytes() / 1024,
      decoder.arena().capacity_bytes() / 1024);
  EXPECT_EQ(decoder.decoded(), 3 * c.jpeg.size());
}

}  // namespace
}  // namespace rgbdtam
