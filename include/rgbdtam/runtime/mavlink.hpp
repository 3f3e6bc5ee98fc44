#pragma once
// MAVLink v2 framing and the messages the pose link sends and reads (definitions:
// common.xml / minimal.xml of the MAVLink project). Framing, the X.25 checksum and each
// message's CRC_EXTRA are written here once; the runtime's link, the monitor and the tests all
// use this code. No signing (incompat_flags = 0).
//
// Frame: 0xFD, payload length, incompat flags, compat flags, sequence, system id, component id,
// message id (3 bytes, little-endian), payload (trailing zero bytes dropped, at least one kept),
// checksum (X.25 over length..payload, then CRC_EXTRA; little-endian).

#include <cstddef>
#include <cstdint>

#include "rgbdtam/port/status_text.hpp"

namespace rgbdtam::mavlink {

constexpr uint8_t kMagicV2 = 0xFD;
constexpr int kHeaderBytes = 10;
constexpr int kChecksumBytes = 2;
constexpr int kMaxPayloadBytes = 255;
constexpr int kMaxFrameBytes = kHeaderBytes + kMaxPayloadBytes + kChecksumBytes;
constexpr int kSignatureBytes = 13;  // received only: this link does not sign

// X.25 (CRC-16/MCRF4XX) as MAVLink uses it: start at 0xFFFF, accumulate byte by byte.
constexpr uint16_t kCrcInit = 0xFFFF;
uint16_t crc_accumulate(uint8_t byte, uint16_t crc);
uint16_t crc_accumulate(const uint8_t* bytes, size_t n, uint16_t crc);

// Message ids, wire payload lengths (with extensions) and CRC_EXTRA; each message struct below
// names its own as kSpec. A test recomputes every CRC_EXTRA from the XML definitions.
struct MessageSpec {
  uint32_t id;
  uint8_t payload_bytes;
  uint8_t crc_extra;
  const char* name;
};
constexpr MessageSpec kHeartbeat{0, 9, 50, "HEARTBEAT"};
constexpr MessageSpec kStatusText{253, 54, 83, "STATUSTEXT"};
constexpr MessageSpec kOdometry{331, 233, 91, "ODOMETRY"};
constexpr MessageSpec kTimesync{111, 18, 34, "TIMESYNC"};
constexpr MessageSpec kObstacleDistance{330, 167, 23, "OBSTACLE_DISTANCE"};
constexpr MessageSpec kAttitude{30, 28, 39, "ATTITUDE"};  // received from the autopilot
constexpr MessageSpec kAttitudeQuaternion{31, 48, 246, "ATTITUDE_QUATERNION"};  // received
constexpr MessageSpec kSetGpsGlobalOrigin{48, 21, 41, "SET_GPS_GLOBAL_ORIGIN"};
constexpr MessageSpec kNamedValueFloat{251, 18, 170, "NAMED_VALUE_FLOAT"};
// The spec of a message id this link knows, or null.
const MessageSpec* find_spec(uint32_t id);

// Enumerations used (values from common.xml / minimal.xml).
enum : uint8_t {
  kMavTypeOnboardController = 18,
  kMavAutopilotInvalid = 8,
  kMavStateStandby = 3,
  kMavStateActive = 4,
  kMavStateCritical = 5,
  kMavFrameLocalFrd = 20,
  kMavFrameBodyFrd = 12,
  kMavEstimatorTypeVision = 2,
  kMavDistanceSensorInfrared = 2,
  kMavSeverityError = 3,
  kMavSeverityWarning = 4,
  kMavSeverityInfo = 6,
};

struct Heartbeat {
  static constexpr const MessageSpec& kSpec = kHeartbeat;
  uint32_t custom_mode = 0;
  uint8_t type = kMavTypeOnboardController;
  uint8_t autopilot = kMavAutopilotInvalid;
  uint8_t base_mode = 0;
  uint8_t system_status = kMavStateActive;
  uint8_t mavlink_version = 3;
};

struct StatusText {
  static constexpr const MessageSpec& kSpec = kStatusText;
  uint8_t severity = kMavSeverityInfo;
  char text[50] = {};  // not NUL-terminated when all 50 are used
  uint16_t id = 0;
  uint8_t chunk_seq = 0;
};

// A request has tc1 = 0 and ts1 = the sender's time; the answer has tc1 = the answerer's time
// and the request's ts1. Times in ns.
struct Timesync {
  static constexpr const MessageSpec& kSpec = kTimesync;
  int64_t tc1 = 0;
  int64_t ts1 = 0;
  uint8_t target_system = 0;
  uint8_t target_component = 0;
};

struct Odometry {
  static constexpr const MessageSpec& kSpec = kOdometry;
  uint64_t time_usec = 0;
  float x = 0, y = 0, z = 0;                          // m, in frame_id
  float q[4] = {1, 0, 0, 0};                          // w, x, y, z: frame_id to child_frame_id
  float vx = 0, vy = 0, vz = 0;                       // m/s, in child_frame_id
  float rollspeed = 0, pitchspeed = 0, yawspeed = 0;  // rad/s
  float pose_covariance[21] = {};  // upper triangle of the 6x6 (x y z roll pitch yaw), row-major
  float velocity_covariance[21] = {};
  uint8_t frame_id = kMavFrameLocalFrd;
  uint8_t child_frame_id = kMavFrameBodyFrd;
  uint8_t reset_counter = 0;
  uint8_t estimator_type = kMavEstimatorTypeVision;
  int8_t quality = 0;  // %, -1 = failed, 0 = unknown
};

// Obstacles around the body, in sectors clockwise from angle_offset (deg from forward).
struct ObstacleDistance {
  static constexpr const MessageSpec& kSpec = kObstacleDistance;
  uint64_t time_usec = 0;
  uint16_t distances[72] = {};                  // cm; max_distance + 1: none; UINT16_MAX: unknown
  uint16_t min_distance = 0, max_distance = 0;  // cm
  uint8_t sensor_type = kMavDistanceSensorInfrared;
  uint8_t increment = 0;   // deg, whole; increment_f wins when non-zero
  float increment_f = 0;   // deg
  float angle_offset = 0;  // deg, sector 0's, clockwise from forward
  uint8_t frame = kMavFrameBodyFrd;
};

// The autopilot's attitude: body (front-right-down) in its local level frame (north-east-down),
// stamped in its boot clock. ATTITUDE says the same in Euler angles.
struct AttitudeQuaternion {
  static constexpr const MessageSpec& kSpec = kAttitudeQuaternion;
  uint32_t time_boot_ms = 0;
  float q[4] = {1, 0, 0, 0};                          // w, x, y, z (q1..q4 on the wire)
  float rollspeed = 0, pitchspeed = 0, yawspeed = 0;  // rad/s, body axes
  float repr_offset_q[4] = {};                        // display only; ignored
};

struct Attitude {
  static constexpr const MessageSpec& kSpec = kAttitude;
  uint32_t time_boot_ms = 0;
  float roll = 0, pitch = 0, yaw = 0;                 // rad
  float rollspeed = 0, pitchspeed = 0, yawspeed = 0;  // rad/s
};

// Where the autopilot's local origin is on Earth, for flying without GPS.
struct SetGpsGlobalOrigin {
  static constexpr const MessageSpec& kSpec = kSetGpsGlobalOrigin;
  int32_t latitude = 0, longitude = 0;  // degE7
  int32_t altitude = 0;                 // mm above mean sea level
  uint8_t target_system = 0;
  uint64_t time_usec = 0;
};

// A named value a ground station plots (the link's latency, once a second).
struct NamedValueFloat {
  static constexpr const MessageSpec& kSpec = kNamedValueFloat;
  uint32_t time_boot_ms = 0;
  float value = 0;
  char name[10] = {};  // not NUL-terminated when all 10 are used
};

// Payload (wire order) of each message; returns the full, untruncated length.
int pack(const Heartbeat& m, uint8_t* payload);
int pack(const StatusText& m, uint8_t* payload);
int pack(const Timesync& m, uint8_t* payload);
int pack(const Attitude& m, uint8_t* payload);
int pack(const AttitudeQuaternion& m, uint8_t* payload);
int pack(const SetGpsGlobalOrigin& m, uint8_t* payload);
int pack(const NamedValueFloat& m, uint8_t* payload);

// Joins STATUSTEXT chunks back into whole texts, as a ground station does.
class StatusTextJoiner {
 public:
  // The whole text when m completes one (a text that fits one message completes at once),
  // else nullptr while more chunks are due.
  const char* add(const StatusText& m);

 private:
  char text_[kMaxStatusTextChars + 1] = {};
  size_t used_ = 0;
};
int pack(const Odometry& m, uint8_t* payload);
int pack(const ObstacleDistance& m, uint8_t* payload);
// From a received payload (length as received; truncated zeros are restored).
void unpack(const uint8_t* payload, int length, Heartbeat* m);
void unpack(const uint8_t* payload, int length, StatusText* m);
void unpack(const uint8_t* payload, int length, Timesync* m);
void unpack(const uint8_t* payload, int length, Odometry* m);
void unpack(const uint8_t* payload, int length, ObstacleDistance* m);
void unpack(const uint8_t* payload, int length, Attitude* m);
void unpack(const uint8_t* payload, int length, AttitudeQuaternion* m);
void unpack(const uint8_t* payload, int length, SetGpsGlobalOrigin* m);
void unpack(const uint8_t* payload, int length, NamedValueFloat* m);

// Frames messages from one system/component, with its own sequence counter.
class Encoder {
 public:
  Encoder(uint8_t system_id, uint8_t component_id)
      : system_id_(system_id), component_id_(component_id) {}
  // Writes a whole frame into out (kMaxFrameBytes); returns its length.
  template <typename Message>
  int encode(const Message& m, uint8_t* out) {
    uint8_t payload[kMaxPayloadBytes];
    const int n = pack(m, payload);
    return frame(Message::kSpec, payload, n, out);
  }
  int frame(const MessageSpec& spec, const uint8_t* payload, int length, uint8_t* out);

 private:
  uint8_t system_id_, component_id_;
  uint8_t sequence_ = 0;
};

// A received frame; payload is zero-padded to the message's full length.
struct Frame {
  uint8_t sequence = 0;
  uint8_t system_id = 0;
  uint8_t component_id = 0;
  uint32_t message_id = 0;
  uint8_t length = 0;  // as received
  uint8_t payload[kMaxPayloadBytes] = {};
};

// The message a received frame of M's id holds.
template <typename M>
M unpacked(const Frame& f) {
  M m;
  unpack(f.payload, f.length, &m);
  return m;
}

struct DecoderCounters {
  uint64_t frames = 0;            // good frames of known messages
  uint64_t crc_errors = 0;        // complete frames whose checksum did not match
  uint64_t unknown_messages = 0;  // complete frames of ids this link does not know
  uint64_t bytes_skipped = 0;     // bytes outside any frame (garbage, resynchronisation)
  uint64_t lost_frames = 0;       // gaps in the sender's sequence numbers
};

// Byte-stream decoder: survives garbage, truncation and bad checksums by resynchronising on
// the next 0xFD after a failed frame. Holds one frame in progress; never allocates.
class Decoder {
 public:
  // Consumes bytes until a frame completes; returns the bytes consumed and sets *got when
  // *frame holds a good frame. Call again with the rest.
  size_t feed(const uint8_t* bytes, size_t n, Frame* frame, bool* got);
  // Feeds all n bytes, calling on_frame(const Frame&) for every good frame they complete.
  template <typename OnFrame>
  void feed_all(const uint8_t* bytes, size_t n, OnFrame&& on_frame) {
    Frame frame;
    for (size_t used = 0;;) {
      bool got = false;
      used += feed(bytes + used, n - used, &frame, &got);
      if (!got) return;
      on_frame(static_cast<const Frame&>(frame));
    }
  }
  const DecoderCounters& counters() const { return counters_; }

 private:
  bool finish(Frame* frame);
  uint8_t buffer_[kMaxFrameBytes + kSignatureBytes] = {};
  int have_ = 0;  // bytes of the frame in progress
  int need_ = 0;  // its total length once the header is known
  bool synced_sequence_ = false;
  uint8_t next_sequence_ = 0;
  DecoderCounters counters_;
};

}  // namespace rgbdtam::mavlink
