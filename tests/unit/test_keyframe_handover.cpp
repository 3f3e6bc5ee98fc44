// The keyframe that map reuse left (KeyframeHandover::left): the tracker tries it for a frame the
// keyframe taken up does not fit. It is offered only while the taken-up keyframe is the
// reference and the left one is still in its pool slot, in the estimate's frame.
#include <gtest/gtest.h>

#include "rgbdtam/runtime/tracking/frame_buffers.hpp"
#include "rgbdtam/runtime/tracking/keyframe_handover.hpp"
#include "synthetic_scene.hpp"
#include "tum_writer.hpp"

namespace rgbdtam {
namespace {

struct Handover {
  explicit Handover(int pool_size) : room(testing::SyntheticScene::half_resolution()) {
    p = testing::synthetic_params(room);
    p.keyframe_pool_size = pool_size;
    handover.init(p, &pool, &building, nullptr);
    frames.allocate(p.camera, p.sensor.depth_factor, p.sensor.depth_range);
  }
  // The room seen at t_s, as the current frame, kept as the last valid one.
  void see(double t_s) {
    testing::synthetic_pyramid(room.render(room.camera_at(t_s)), p, &frames.current());
    frames.keep_current();
  }
  // A keyframe of the room seen at t_s, its depth taken from T_c_d, built and adopted as the
  // reference; the builder is released.
  Keyframe* new_keyframe(double t_s, const SE3& T_c_d = SE3()) {
    Keyframe* kf = adopt_keyframe(t_s, T_c_d);
    handover.release_adopted();
    return kf;
  }
  // ... the builder not released: its frame is the keyframe's (adopted_frame).
  Keyframe* adopt_keyframe(double t_s, const SE3& T_c_d) {
    testing::synthetic_pyramid(room.render(room.camera_at(t_s)), p, &frames.current());
    frames.current().set_T_c_d(T_c_d);
    PoseEstimate out;
    EXPECT_TRUE(handover.ask(room.camera_at(t_s), handover.restart_link(), false,
                             frames.current_slot(), &out));
    handover.order_pending(frames, 0);
    Keyframe* kf = handover.adopt_built(0);
    EXPECT_NE(kf, nullptr);
    return kf;
  }
  testing::SyntheticScene room;
  Params p;
  KeyframePool pool;
  KeyframeBuildTask building;
  KeyframeHandover handover;
  FrameBuffers frames;
};

TEST(KeyframeHandover, TheKeyframeReuseLeftIsOfferedUntilTheReferenceChanges) {
  Handover h(8);
  Keyframe* first = h.new_keyframe(0.0);
  Keyframe* second = h.new_keyframe(0.5);
  EXPECT_EQ(h.handover.left(), nullptr) << "nothing taken up yet";

  h.handover.take_up(first);
  EXPECT_EQ(h.handover.left(), second);
  h.handover.track_against(first);  // frames tracked against the taken-up keyframe
  EXPECT_EQ(h.handover.left(), second);

  h.handover.track_against(second);  // the tracker went back to it
  EXPECT_EQ(h.handover.left(), nullptr);

  h.handover.take_up(first);
  Keyframe* third = h.new_keyframe(1.0);
  EXPECT_EQ(h.handover.reference(), third);
  EXPECT_EQ(h.handover.left(), nullptr) << "a new keyframe is the reference";

  h.handover.take_up(second);
  EXPECT_EQ(h.handover.left(), third);
  h.handover.restarted();
  EXPECT_EQ(h.handover.left(), nullptr) << "a restart leaves the estimate's frame";
}

TEST(KeyframeHandover, AKeyframeLeftWhoseSlotWasRecycledIsNotOffered) {
  // A full pool of three: the keyframe made of the last valid frame, while tracking fails,
  // takes the oldest slot that is not the reference's, the left keyframe's.
  Handover h(3);
  Keyframe* first = h.new_keyframe(0.0);
  Keyframe* second = h.new_keyframe(0.5);
  (void)h.new_keyframe(1.0);
  h.handover.take_up(first);
  h.handover.take_up(second);
  ASSERT_EQ(h.handover.left(), first);
  h.see(0.6);
  Keyframe* fallback =
      h.handover.from_last_valid_frame(h.frames, h.room.camera_at(0.6), 600'000'000);
  ASSERT_EQ(fallback, first) << "the left keyframe's slot is recycled";
  EXPECT_EQ(h.handover.left(), nullptr);
}

// Depth taken from elsewhere than its colour image (a Kinect streams the two unsynchronised):
// the keyframe's geometric points keep it where it was taken; the frame handed on to the mapper
// and the loop module has it moved to where the colour image was taken.
TEST(KeyframeHandover, TheKeyframeHandedOnHasItsDepthSeenFromItsColourImage) {
  Handover h(8);
  const SE3 T_c_d(so3_exp(Vector3d(0.0, 0.5 * M_PI / 180.0, 0.0)), Vector3d(0.01, 0.0, 0.0));
  testing::synthetic_pyramid(h.room.render(h.room.camera_at(0.0)), h.p, &h.frames.current());
  const ImageF& taken = h.frames.current().inverse_depth(0);
  ImageF moved;
  moved.allocate(taken.width(), taken.height());
  move_inverse_depth(taken, h.frames.current().intrinsics(0), T_c_d, &moved);
  ImageF as_taken;
  as_taken.allocate(taken.width(), taken.height());
  as_taken.copy_from(taken);

  const Keyframe* kf = h.adopt_keyframe(0.0, T_c_d);
  ASSERT_NE(kf, nullptr);
  EXPECT_EQ(kf->T_k_kd.translation(), T_c_d.translation());
  const FramePyramid& handed_on = h.handover.adopted_frame();
  EXPECT_TRUE(is_identity(handed_on.T_c_d()));
  int as_moved = 0, unchanged = 0;
  for (int i = 0; i < moved.size(); ++i) {
    as_moved += handed_on.inverse_depth(0).data()[i] == moved.data()[i] ? 1 : 0;
    unchanged += handed_on.inverse_depth(0).data()[i] == as_taken.data()[i] ? 1 : 0;
  }
  EXPECT_EQ(as_moved, moved.size());
  EXPECT_LT(unchanged, moved.size() / 2) << "the test shows nothing";
  h.handover.release_adopted();

  const Keyframe* together = h.new_keyframe(0.5);
  EXPECT_TRUE(is_identity(together->T_k_kd));
}

}  // namespace
}  // namespace rgbdtam
