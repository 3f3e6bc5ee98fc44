// libFuzzer target for the MAVLink decoder: arbitrary bytes, fed in chunk sizes the input
// chooses, must never crash, overrun or hang; every frame it accepts must unpack, and must
// decode to the same payload again after being re-framed by the encoder.
//   tools/fuzz.sh [seconds]
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "rgbdtam/runtime/mavlink.hpp"

using namespace rgbdtam::mavlink;

namespace {
void check_round_trip(const Frame& f) {
  const MessageSpec* spec = find_spec(f.message_id);
  if (spec == nullptr) __builtin_trap();  // the decoder accepts known messages only
  Heartbeat hb;
  StatusText st;
  Odometry od;
  Timesync ts;
  ObstacleDistance obstacles;
  Attitude attitude;
  AttitudeQuaternion attitude_q;
  SetGpsGlobalOrigin origin;
  NamedValueFloat value;
  if (spec == &kTimesync) unpack(f.payload, f.length, &ts);
  if (spec == &kObstacleDistance) unpack(f.payload, f.length, &obstacles);
  if (spec == &kAttitude) unpack(f.payload, f.length, &attitude);
  if (spec == &kAttitudeQuaternion) unpack(f.payload, f.length, &attitude_q);
  if (spec == &kSetGpsGlobalOrigin) unpack(f.payload, f.length, &origin);
  if (spec == &kNamedValueFloat) unpack(f.payload, f.length, &value);
  if (spec == &kHeartbeat) unpack(f.payload, f.length, &hb);
  if (spec == &kStatusText) unpack(f.payload, f.length, &st);
  if (spec == &kOdometry) unpack(f.payload, f.length, &od);
  Encoder enc(f.system_id, f.component_id);
  uint8_t wire[kMaxFrameBytes];
  const int n = enc.frame(*spec, f.payload, spec->payload_bytes, wire);
  Decoder again;
  Frame g;
  bool got = false;
  again.feed(wire, static_cast<size_t>(n), &g, &got);
  if (!got || g.message_id != f.message_id ||
      std::memcmp(g.payload, f.payload, spec->payload_bytes) != 0) {
    __builtin_trap();
  }
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const size_t chunk = 1 + data[0] % 64;
  Decoder dec;
  for (size_t at = 1; at < size;) {
    const size_t n = chunk < size - at ? chunk : size - at;
    dec.feed_all(data + at, n, check_round_trip);
    at += n;
  }
  return 0;
}
