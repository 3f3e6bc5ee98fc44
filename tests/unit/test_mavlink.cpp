// MAVLink v2 framing: CRC_EXTRA recomputed from the XML definitions, the X.25 check value,
// round trips with v2 zero truncation, and a decoder that survives garbage, truncation and
// corrupted bytes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "rgbdtam/runtime/mavlink.hpp"
#include "test_paths.hpp"

namespace rgbdtam::mavlink {
namespace {

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

struct XmlField {
  std::string type, name;
  int array = 0;  // 0: scalar
  int type_bytes = 0;
};

struct XmlMessage {
  uint8_t crc_extra = 0;
  int payload_bytes = 0;
};

// CRC_EXTRA as the MAVLink generator defines it: the X.25 CRC over "NAME ", then, for each
// base (non-extension) field in wire order, "type " and "name " and the array length, folded
// to one byte.
// The text of attribute `attr` in the tag starting at `from`, or "" (a small reader for the
// generator's XML, enough for message and field tags).
std::string attribute(const std::string& xml, size_t from, const std::string& attr) {
  const size_t end = xml.find('>', from);
  const size_t at = xml.find(" " + attr + "=\"", from);
  if (at == std::string::npos || at > end) return "";
  const size_t start = at + attr.size() + 3;
  return xml.substr(start, xml.find('"', start) - start);
}

XmlMessage from_xml(const std::string& xml, const std::string& name) {
  size_t message = xml.find("<message ");
  while (message != std::string::npos && attribute(xml, message, "name") != name) {
    message = xml.find("<message ", message + 1);
  }
  EXPECT_NE(message, std::string::npos) << name;
  if (message == std::string::npos) return {};
  const size_t body_end = xml.find("</message>", message);
  const size_t extensions = xml.find("<extensions/>", message);
  std::vector<XmlField> base, all;
  for (size_t tag = xml.find("<field ", message); tag < body_end;
       tag = xml.find("<field ", tag + 1)) {
    XmlField f;
    f.type = attribute(xml, tag, "type");
    f.name = attribute(xml, tag, "name");
    const size_t bracket = f.type.find('[');
    if (bracket != std::string::npos) {
      f.array = std::stoi(f.type.substr(bracket + 1));
      f.type = f.type.substr(0, bracket);
    }
    if (f.type == "uint8_t_mavlink_version") f.type = "uint8_t";
    f.type_bytes = f.type.find("64") != std::string::npos || f.type == "double"  ? 8
                   : f.type.find("32") != std::string::npos || f.type == "float" ? 4
                   : f.type.find("16") != std::string::npos                      ? 2
                                                                                 : 1;
    all.push_back(f);
    if (tag < extensions) base.push_back(f);
  }
  std::stable_sort(base.begin(), base.end(), [](const XmlField& a, const XmlField& b) {
    return a.type_bytes > b.type_bytes;
  });
  auto add = [](const std::string& s, uint16_t crc) {
    return crc_accumulate(reinterpret_cast<const uint8_t*>(s.data()), s.size(), crc);
  };
  uint16_t crc = add(name + " ", kCrcInit);
  for (const XmlField& f : base) {
    crc = add(f.type + " ", crc);
    crc = add(f.name + " ", crc);
    if (f.array > 0) crc = crc_accumulate(static_cast<uint8_t>(f.array), crc);
  }
  XmlMessage out;
  out.crc_extra = static_cast<uint8_t>((crc & 0xFF) ^ (crc >> 8));
  for (const XmlField& f : all) out.payload_bytes += f.type_bytes * std::max(1, f.array);
  return out;
}

void expect_spec_matches(const std::string& xml, const MessageSpec& spec) {
  const XmlMessage m = from_xml(xml, spec.name);
  EXPECT_EQ(m.crc_extra, spec.crc_extra) << spec.name;
  EXPECT_EQ(m.payload_bytes, spec.payload_bytes) << spec.name;
}

TEST(Mavlink, X25CheckValue) {
  const char* check = "123456789";
  EXPECT_EQ(crc_accumulate(reinterpret_cast<const uint8_t*>(check), 9, kCrcInit), 0x6F91);
}

TEST(Mavlink, CrcExtraAndLengthsMatchTheXmlDefinitions) {
  const std::string xml = read_file(testing::source_path("tests/data/mavlink/messages.xml"));
  ASSERT_FALSE(xml.empty());
  for (const MessageSpec* s :
       {&kHeartbeat, &kStatusText, &kOdometry, &kTimesync, &kObstacleDistance, &kAttitude,
        &kAttitudeQuaternion, &kSetGpsGlobalOrigin, &kNamedValueFloat}) {
    expect_spec_matches(xml, *s);
  }
}

TEST(Mavlink, CrcExtraMatchesTheUpstreamFilesWhereThisMachineHasThem) {
  const std::string dir = testing::source_path("../shared/spec/mavlink/");
  const std::string minimal = read_file(dir + "minimal.xml"),
                    common = read_file(dir + "common.xml");
  if (minimal.empty() || common.empty()) GTEST_SKIP() << "no " << dir;
  expect_spec_matches(minimal, kHeartbeat);
  expect_spec_matches(common, kStatusText);
  expect_spec_matches(common, kOdometry);
  expect_spec_matches(common, kTimesync);
  expect_spec_matches(common, kObstacleDistance);
  expect_spec_matches(common, kAttitude);
  expect_spec_matches(common, kAttitudeQuaternion);
  expect_spec_matches(common, kSetGpsGlobalOrigin);
  expect_spec_matches(common, kNamedValueFloat);
}

TEST(Mavlink, ObstacleDistanceRoundTripsInWireOrder) {
  ObstacleDistance sent;
  sent.time_usec = 1305031098382263ull;
  for (int i = 0; i < 72; ++i) sent.distances[i] = static_cast<uint16_t>(100 + i);
  sent.distances[71] = UINT16_MAX;
  sent.min_distance = 30;
  sent.max_distance = 500;
  sent.increment = 1;
  sent.increment_f = 0.8716f;
  sent.angle_offset = -30.94f;
  uint8_t payload[kMaxPayloadBytes];
  ASSERT_EQ(pack(sent, payload), kObstacleDistance.payload_bytes);
  // common.xml's wire order: time_usec, distances, min, max, sensor_type, increment, then the
  // extensions increment_f, angle_offset, frame.
  uint16_t first, min_cm;
  std::memcpy(&first, payload + 8, 2);
  std::memcpy(&min_cm, payload + 152, 2);
  EXPECT_EQ(first, 100);
  EXPECT_EQ(min_cm, 30);
  EXPECT_EQ(payload[156], kMavDistanceSensorInfrared);
  EXPECT_EQ(payload[166], kMavFrameBodyFrd);
  ObstacleDistance got;
  unpack(payload, kObstacleDistance.payload_bytes, &got);
  EXPECT_EQ(got.time_usec, sent.time_usec);
  EXPECT_EQ(got.distances[71], UINT16_MAX);
  EXPECT_EQ(got.max_distance, 500);
  EXPECT_FLOAT_EQ(got.increment_f, sent.increment_f);
  EXPECT_FLOAT_EQ(got.angle_offset, sent.angle_offset);
}

TEST(Mavlink, TheAutopilotsAttitudeAndTheOriginWeSendAreInWireOrder) {
  AttitudeQuaternion a;
  a.time_boot_ms = 123456;
  a.q[0] = 0.5f;
  a.q[1] = -0.5f;
  a.q[2] = 0.5f;
  a.q[3] = -0.5f;
  a.yawspeed = 1.5f;
  uint8_t payload[kMaxPayloadBytes];
  ASSERT_EQ(pack(a, payload), kAttitudeQuaternion.payload_bytes);
  float q4 = 0, yawspeed = 0;  // common.xml: time_boot_ms, q1..q4, rates, then repr_offset_q
  std::memcpy(&q4, payload + 16, 4);
  std::memcpy(&yawspeed, payload + 28, 4);
  EXPECT_EQ(q4, -0.5f);
  EXPECT_EQ(yawspeed, 1.5f);
  AttitudeQuaternion got_a;
  unpack(payload, 32, &got_a);  // sent without the extension, as older autopilots do
  EXPECT_EQ(got_a.time_boot_ms, 123456u);
  EXPECT_EQ(got_a.q[1], -0.5f);
  EXPECT_EQ(got_a.repr_offset_q[0], 0.f);

  SetGpsGlobalOrigin o;
  o.latitude = 473977420;  // degE7
  o.longitude = 85455940;
  o.altitude = 488000;  // mm
  o.target_system = 1;
  o.time_usec = 42;
  ASSERT_EQ(pack(o, payload), kSetGpsGlobalOrigin.payload_bytes);
  int32_t latitude = 0;  // latitude, longitude, altitude, target_system, then time_usec
  std::memcpy(&latitude, payload, 4);
  EXPECT_EQ(latitude, 473977420);
  EXPECT_EQ(payload[12], 1);
  SetGpsGlobalOrigin got_o;
  unpack(payload, kSetGpsGlobalOrigin.payload_bytes, &got_o);
  EXPECT_EQ(got_o.altitude, 488000);
  EXPECT_EQ(got_o.time_usec, 42u);
}

Odometry sample_odometry(uint64_t t_us) {
  Odometry o;
  o.time_usec = t_us;
  o.x = 1.25f;
  o.y = -0.5f;
  o.z = 0.125f;
  o.q[0] = 0.5f;
  o.q[1] = 0.5f;
  o.q[2] = -0.5f;
  o.q[3] = 0.5f;
  o.vx = 0.1f;
  o.yawspeed = -0.25f;
  for (int i = 0; i < 21; ++i) {
    o.pose_covariance[i] = 1e-4f * static_cast<float>(i + 1);
    o.velocity_covariance[i] = NAN;
  }
  o.reset_counter = 7;
  o.quality = 0;  // trailing zero: truncated on the wire
  return o;
}

TEST(Mavlink, OdometryRoundTripsWithTrailingZerosTruncated) {
  Encoder enc(1, 197);
  uint8_t wire[kMaxFrameBytes];
  const Odometry sent = sample_odometry(123456789012345ull);
  const int n = enc.encode(sent, wire);
  EXPECT_EQ(n, kHeaderBytes + kOdometry.payload_bytes - 1 + kChecksumBytes);  // quality dropped
  Decoder dec;
  Frame f;
  bool got = false;
  EXPECT_EQ(dec.feed(wire, static_cast<size_t>(n), &f, &got), static_cast<size_t>(n));
  ASSERT_TRUE(got);
  EXPECT_EQ(f.message_id, kOdometry.id);
  EXPECT_EQ(f.system_id, 1);
  EXPECT_EQ(f.component_id, 197);
  Odometry back;
  back.quality = 55;
  unpack(f.payload, f.length, &back);
  EXPECT_EQ(back.time_usec, sent.time_usec);
  EXPECT_EQ(back.x, sent.x);
  EXPECT_EQ(back.q[2], sent.q[2]);
  EXPECT_EQ(back.yawspeed, sent.yawspeed);
  EXPECT_EQ(back.pose_covariance[20], sent.pose_covariance[20]);
  EXPECT_TRUE(std::isnan(back.velocity_covariance[3]));
  EXPECT_EQ(back.reset_counter, 7);
  EXPECT_EQ(back.estimator_type, kMavEstimatorTypeVision);
  EXPECT_EQ(back.quality, 0);
}

TEST(Mavlink, HeartbeatAndStatusTextRoundTrip) {
  Encoder enc(1, 197);
  std::vector<uint8_t> stream;
  uint8_t wire[kMaxFrameBytes];
  Heartbeat hb;
  hb.system_status = kMavStateCritical;
  StatusText st;
  st.severity = kMavSeverityWarning;
  std::memcpy(st.text, "tracking lost", 14);
  for (int n : {enc.encode(hb, wire)}) stream.insert(stream.end(), wire, wire + n);
  for (int n : {enc.encode(st, wire)}) stream.insert(stream.end(), wire, wire + n);
  Decoder dec;
  Frame f;
  bool got = false;
  size_t used = dec.feed(stream.data(), stream.size(), &f, &got);
  ASSERT_TRUE(got);
  Heartbeat hb_back;
  unpack(f.payload, f.length, &hb_back);
  EXPECT_EQ(hb_back.system_status, kMavStateCritical);
  EXPECT_EQ(hb_back.mavlink_version, 3);
  used += dec.feed(stream.data() + used, stream.size() - used, &f, &got);
  ASSERT_TRUE(got);
  EXPECT_EQ(used, stream.size());
  StatusText st_back;
  unpack(f.payload, f.length, &st_back);
  EXPECT_EQ(st_back.severity, kMavSeverityWarning);
  EXPECT_STREQ(st_back.text, "tracking lost");
  EXPECT_EQ(dec.counters().lost_frames, 0u);
}

// Decodes a whole stream; returns the good frames' sequence numbers.
std::vector<int> decode_all(Decoder* dec, const std::vector<uint8_t>& bytes, size_t chunk) {
  std::vector<int> seqs;
  for (size_t at = 0; at < bytes.size();) {
    const size_t n = std::min(chunk, bytes.size() - at);
    dec->feed_all(bytes.data() + at, n, [&](const Frame& f) { seqs.push_back(f.sequence); });
    at += n;
  }
  return seqs;
}

TEST(Mavlink, DecoderResynchronisesAfterGarbageTruncationAndCorruption) {
  Encoder enc(1, 197);
  uint8_t wire[kMaxFrameBytes];
  std::vector<uint8_t> stream = {0x00, 0xFD, 0x13, 0xFD, 0xFD, 0x55};  // garbage, false starts
  auto append = [&](int seq_expected, int cut, int flip) {
    const int n = enc.encode(sample_odometry(static_cast<uint64_t>(seq_expected)), wire);
    if (flip >= 0) wire[flip] ^= 0x40;
    stream.insert(stream.end(), wire, wire + (cut > 0 ? cut : n));
  };
  append(0, 0, -1);   // seq 0: good
  append(1, 40, -1);  // seq 1: truncated mid-payload
  append(2, 0, 60);   // seq 2: a payload bit flipped
  append(3, 0, -1);   // seq 3: good
  append(4, 0, 1);    // seq 4: length byte corrupted
  append(5, 0, -1);   // seq 5: good
  for (size_t chunk : {size_t{1}, size_t{7}, stream.size()}) {
    Decoder dec;
    EXPECT_EQ(decode_all(&dec, stream, chunk), (std::vector<int>{0, 3, 5})) << "chunk " << chunk;
    EXPECT_EQ(dec.counters().frames, 3u);
    EXPECT_GE(dec.counters().crc_errors, 1u);
    EXPECT_EQ(dec.counters().lost_frames, 3u);  // 1, 2 and 4 never arrived whole
    EXPECT_GT(dec.counters().bytes_skipped, 0u);
  }
}

TEST(Mavlink, DecoderSkipsUnknownMessagesAndSignedFramesAreMeasuredCorrectly) {
  Encoder enc(1, 197);
  uint8_t wire[kMaxFrameBytes + kSignatureBytes];
  const uint8_t payload[3] = {1, 2, 3};
  const MessageSpec unknown{42, 3, 0, "UNKNOWN"};
  std::vector<uint8_t> stream;
  int n = enc.frame(unknown, payload, 3, wire);
  stream.insert(stream.end(), wire, wire + n);
  n = enc.encode(Heartbeat{}, wire);
  stream.insert(stream.end(), wire, wire + n);
  // The same heartbeat, marked signed, with a 13-byte signature appended: the checksum does
  // not cover the flag change, so it must be rejected, and the next frame still found.
  n = enc.encode(Heartbeat{}, wire);
  wire[2] = 0x01;
  stream.insert(stream.end(), wire, wire + n);
  stream.insert(stream.end(), kSignatureBytes, 0xAB);
  n = enc.encode(Heartbeat{}, wire);
  stream.insert(stream.end(), wire, wire + n);
  Decoder dec;
  EXPECT_EQ(decode_all(&dec, stream, 5), (std::vector<int>{1, 3}));
  EXPECT_GE(dec.counters().unknown_messages, 1u);
  EXPECT_GE(dec.counters().crc_errors, 1u);
}

}  // namespace
}  // namespace rgbdtam::mavlink
