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
  // A keyframe of the room seen at t_s, ordered in the world of `ordered` and adopted in that of
  // `adopted`, as the reference (null: it was stale).
  Keyframe* new_keyframe(double t_s, const MapFrame& ordered = MapFrame(),
                         const MapFrame& adopted = MapFrame()) {
    testing::synthetic_pyramid(room.render(room.camera_at(t_s)), p, &frames.current());
    PoseEstimate out;
    EXPECT_TRUE(handover.ask(room.camera_at(t_s), handover.restart_link(), false,
                             frames.current_slot(), &out));
    handover.order_pending(frames, ordered);
    Keyframe* kf = handover.adopt_built(adopted);
    if (kf != nullptr) handover.release_adopted();
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

// A loop correction while a keyframe is built moves the world its pose was measured in: the
// keyframe is adopted, moved with it, so that the frames tracked meanwhile are not lost with it.
// A restart or relocalisation meanwhile (a new epoch) leaves its pose nowhere: it is dropped.
TEST(KeyframeHandover, AKeyframeBuiltAcrossACorrectionMovesWithTheMap) {
  Handover h(8);
  (void)h.new_keyframe(0.0);
  MapFrame ordered;
  ordered.corrections = 2;
  ordered.T_now_epoch = SE3(so3_exp(Vector3d(0, 0.01, 0)), Vector3d(0.01, 0, 0));
  const SE3 step(so3_exp(Vector3d(0.002, 0, 0)), Vector3d(0, 0.004, -0.003));
  MapFrame corrected = ordered;
  corrected.corrections = 3;
  corrected.T_now_epoch = step * ordered.T_now_epoch;
  Keyframe* moved = h.new_keyframe(0.5, ordered, corrected);
  ASSERT_NE(moved, nullptr);
  const SE3 expected = step * h.room.camera_at(0.5);
  EXPECT_LT((moved->T_w_k.translation() - expected.translation()).norm(), 1e-9);
  EXPECT_LT(so3_log((moved->T_w_k.inverse() * expected).quaternion()).norm(), 1e-9);
  EXPECT_EQ(h.handover.counters().keyframes_stale, 0u);

  MapFrame restarted = corrected;
  ++restarted.epoch;
  restarted.corrections = 0;
  restarted.T_now_epoch = SE3();
  EXPECT_EQ(h.new_keyframe(1.0, corrected, restarted), nullptr);
  EXPECT_EQ(h.handover.counters().keyframes_stale, 1u);
  EXPECT_EQ(h.handover.reference(), moved);
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

}  // namespace
}  // namespace rgbdtam
