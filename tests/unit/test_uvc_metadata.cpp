// uvcvideo's metadata buffers read (hal/uvc_metadata): the standard payload header's PTS and a
// RealSense D4xx's frame counter, in the layouts the kernel documents, and buffers cut short.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <vector>

#include "rgbdtam/hal/uvc_metadata.hpp"

namespace rgbdtam {
namespace {

void put32(std::vector<uint8_t>* b, uint32_t v) {
  for (int i = 0; i < 4; ++i) b->push_back(static_cast<uint8_t>(v >> (8 * i)));
}

// One block: arrival ns and USB frame number, then a payload header of these flags.
std::vector<uint8_t> block(uint8_t flags, uint32_t pts, const std::vector<uint8_t>& vendor = {}) {
  std::vector<uint8_t> b(10, 0xEE);  // arrival and SOF: not read
  const bool has_pts = (flags & 0x04) != 0, has_scr = (flags & 0x08) != 0;
  b.push_back(static_cast<uint8_t>(2 + (has_pts ? 4 : 0) + (has_scr ? 6 : 0) + vendor.size()));
  b.push_back(flags);
  if (has_pts) put32(&b, pts);
  if (has_scr) b.insert(b.end(), {1, 2, 3, 4, 5, 6});
  b.insert(b.end(), vendor.begin(), vendor.end());
  return b;
}

std::vector<uint8_t> capture_timing(uint32_t flags, uint32_t counter) {
  std::vector<uint8_t> v;
  put32(&v, 0x80000001u);
  put32(&v, 40);
  put32(&v, 1);
  put32(&v, flags);
  put32(&v, counter);
  for (int i = 0; i < 5; ++i) put32(&v, 777);  // optical, readout, exposure, interval, latency
  return v;
}

std::vector<uint8_t> depth_control() {
  std::vector<uint8_t> v;
  put32(&v, 0x80000000u);
  put32(&v, 16);
  put32(&v, 1);
  put32(&v, 0xFF);
  return v;
}

TEST(UvcMetadata, TheStandardHeadersPtsIsTheCameraStamp) {
  const std::vector<uint8_t> b = block(0x0C | 0x02, 987654321u);
  UvcFrameMetadata m;
  ASSERT_TRUE(parse_uvc_metadata(b.data(), b.size(), &m));
  EXPECT_TRUE(m.has_pts);
  EXPECT_EQ(m.pts, 987654321u);
  EXPECT_FALSE(m.has_frame_counter);
}

TEST(UvcMetadata, AD4xxsFrameCounterIsFoundAmongItsBlocks) {
  std::vector<uint8_t> vendor = depth_control();
  const std::vector<uint8_t> timing = capture_timing(0x3F, 4242);
  vendor.insert(vendor.end(), timing.begin(), timing.end());
  const std::vector<uint8_t> b = block(0x0C, 1000, vendor);
  UvcFrameMetadata m;
  ASSERT_TRUE(parse_uvc_metadata(b.data(), b.size(), &m));
  EXPECT_EQ(m.pts, 1000u);
  ASSERT_TRUE(m.has_frame_counter);
  EXPECT_EQ(m.frame_counter, 4242u);
}

TEST(UvcMetadata, ACounterMarkedNotValidIsNotTaken) {
  const std::vector<uint8_t> b = block(0x0C, 1000, capture_timing(0x3E, 4242));
  UvcFrameMetadata m;
  ASSERT_TRUE(parse_uvc_metadata(b.data(), b.size(), &m));
  EXPECT_FALSE(m.has_frame_counter);
}

TEST(UvcMetadata, TheFirstBlockWithAPtsGivesItLaterBlocksOnlyTheirScr) {
  std::vector<uint8_t> b = block(0x08, 0);  // SCR only: no stamp
  const std::vector<uint8_t> second = block(0x0C, 55), third = block(0x0C, 66);
  b.insert(b.end(), second.begin(), second.end());
  b.insert(b.end(), third.begin(), third.end());
  UvcFrameMetadata m;
  ASSERT_TRUE(parse_uvc_metadata(b.data(), b.size(), &m));
  EXPECT_EQ(m.pts, 55u);
}

TEST(UvcMetadata, BuffersCutShortOrMalformedGiveWhatIsWholeOrNothing) {
  UvcFrameMetadata m;
  EXPECT_FALSE(parse_uvc_metadata(nullptr, 0, &m));
  const std::vector<uint8_t> whole = block(0x0C, 77, capture_timing(0x1, 9));
  for (size_t cut = 0; cut < whole.size(); ++cut) {
    EXPECT_FALSE(parse_uvc_metadata(whole.data(), cut, &m)) << "cut at " << cut;
  }
  std::vector<uint8_t> b = block(0x0C, 77);
  b[10] = 1;  // a header shorter than its own two bytes
  EXPECT_FALSE(parse_uvc_metadata(b.data(), b.size(), &m));
  // A vendor block claiming more than the header holds is not read; the PTS before it is.
  std::vector<uint8_t> vendor = capture_timing(0x1, 9);
  vendor[4] = 200;
  b = block(0x0C, 78, vendor);
  ASSERT_TRUE(parse_uvc_metadata(b.data(), b.size(), &m));
  EXPECT_EQ(m.pts, 78u);
  EXPECT_FALSE(m.has_frame_counter);
}

}  // namespace
}  // namespace rgbdtam
