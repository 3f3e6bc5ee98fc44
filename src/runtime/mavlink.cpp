#include "rgbdtam/runtime/mavlink.hpp"

#include <algorithm>
#include <cstring>

namespace rgbdtam::mavlink {
namespace {
constexpr uint8_t kIncompatSigned = 0x01;

// Little-endian field writer and reader over a payload buffer.
class Writer {
 public:
  explicit Writer(uint8_t* p) : p_(p) {}
  template <typename T>
  void put(T v) {
    std::memcpy(p_ + n_, &v, sizeof(T));  // MAVLink is little-endian, as are our targets
    n_ += static_cast<int>(sizeof(T));
  }
  template <typename T, int N>
  void put(const T (&v)[N]) {
    for (const T& x : v) put(x);
  }
  int size() const { return n_; }

 private:
  uint8_t* p_;
  int n_ = 0;
};

class Reader {
 public:
  explicit Reader(const uint8_t* p) : p_(p) {}
  template <typename T>
  void get(T* v) {
    std::memcpy(v, p_ + n_, sizeof(T));
    n_ += static_cast<int>(sizeof(T));
  }
  template <typename T, int N>
  void get(T (*v)[N]) {
    for (T& x : *v) get(&x);
  }

 private:
  const uint8_t* p_;
  int n_ = 0;
};

// The frame payload zero-padded to the message's full length (MAVLink v2 truncation).
const uint8_t* padded(const uint8_t* payload, int length, int full, uint8_t* scratch) {
  if (length >= full) return payload;
  std::memset(scratch, 0, static_cast<size_t>(full));
  std::memcpy(scratch, payload, static_cast<size_t>(length));
  return scratch;
}
}  // namespace

uint16_t crc_accumulate(uint8_t byte, uint16_t crc) {
  uint8_t t = static_cast<uint8_t>(byte ^ (crc & 0xFF));
  t = static_cast<uint8_t>(t ^ (t << 4));
  return static_cast<uint16_t>((crc >> 8) ^ (t << 8) ^ (t << 3) ^ (t >> 4));
}

uint16_t crc_accumulate(const uint8_t* bytes, size_t n, uint16_t crc) {
  for (size_t i = 0; i < n; ++i) crc = crc_accumulate(bytes[i], crc);
  return crc;
}

const MessageSpec* find_spec(uint32_t id) {
  static constexpr const MessageSpec* kKnown[] = {
      &kHeartbeat, &kStatusText,         &kOdometry,           &kTimesync,       &kObstacleDistance,
      &kAttitude,  &kAttitudeQuaternion, &kSetGpsGlobalOrigin, &kNamedValueFloat};
  for (const MessageSpec* s : kKnown) {
    if (s->id == id) return s;
  }
  return nullptr;
}

namespace {
// Each message's fields in wire order, written once for packing and unpacking: sorted by type
// size (stable), then the extensions as declared.
template <typename Message>
struct Fields;

template <>
struct Fields<Heartbeat> {
  template <typename M, typename F>
  static void each(M& m, F&& f) {
    f(m.custom_mode);
    f(m.type);
    f(m.autopilot);
    f(m.base_mode);
    f(m.system_status);
    f(m.mavlink_version);
  }
};

template <>
struct Fields<StatusText> {
  template <typename M, typename F>
  static void each(M& m, F&& f) {
    f(m.severity);
    f(m.text);
    f(m.id);
    f(m.chunk_seq);
  }
};

template <>
struct Fields<Timesync> {
  template <typename M, typename F>
  static void each(M& m, F&& f) {
    f(m.tc1);
    f(m.ts1);
    f(m.target_system);
    f(m.target_component);
  }
};

template <>
struct Fields<Odometry> {
  template <typename M, typename F>
  static void each(M& m, F&& f) {
    f(m.time_usec);
    f(m.x);
    f(m.y);
    f(m.z);
    f(m.q);
    f(m.vx);
    f(m.vy);
    f(m.vz);
    f(m.rollspeed);
    f(m.pitchspeed);
    f(m.yawspeed);
    f(m.pose_covariance);
    f(m.velocity_covariance);
    f(m.frame_id);
    f(m.child_frame_id);
    f(m.reset_counter);
    f(m.estimator_type);
    f(m.quality);
  }
};

template <>
struct Fields<ObstacleDistance> {
  template <typename M, typename F>
  static void each(M& m, F&& f) {
    f(m.time_usec);
    f(m.distances);
    f(m.min_distance);
    f(m.max_distance);
    f(m.sensor_type);
    f(m.increment);
    f(m.increment_f);
    f(m.angle_offset);
    f(m.frame);
  }
};

template <>
struct Fields<Attitude> {
  template <typename M, typename F>
  static void each(M& m, F&& f) {
    f(m.time_boot_ms);
    f(m.roll);
    f(m.pitch);
    f(m.yaw);
    f(m.rollspeed);
    f(m.pitchspeed);
    f(m.yawspeed);
  }
};

template <>
struct Fields<AttitudeQuaternion> {
  template <typename M, typename F>
  static void each(M& m, F&& f) {
    f(m.time_boot_ms);
    f(m.q);
    f(m.rollspeed);
    f(m.pitchspeed);
    f(m.yawspeed);
    f(m.repr_offset_q);
  }
};

template <>
struct Fields<SetGpsGlobalOrigin> {
  template <typename M, typename F>
  static void each(M& m, F&& f) {
    f(m.latitude);
    f(m.longitude);
    f(m.altitude);
    f(m.target_system);
    f(m.time_usec);
  }
};

template <>
struct Fields<NamedValueFloat> {
  template <typename M, typename F>
  static void each(M& m, F&& f) {
    f(m.time_boot_ms);
    f(m.value);
    f(m.name);
  }
};

template <typename M>
int pack_fields(const M& m, uint8_t* payload) {
  Writer w(payload);
  Fields<M>::each(m, [&](const auto& v) { w.put(v); });
  return w.size();
}

template <typename M>
void unpack_fields(const uint8_t* payload, int length, M* m) {
  uint8_t scratch[kMaxPayloadBytes];
  Reader r(padded(payload, length, M::kSpec.payload_bytes, scratch));
  Fields<M>::each(*m, [&](auto& v) { r.get(&v); });
}
}  // namespace

int pack(const Heartbeat& m, uint8_t* payload) { return pack_fields(m, payload); }
int pack(const StatusText& m, uint8_t* payload) { return pack_fields(m, payload); }
int pack(const Timesync& m, uint8_t* payload) { return pack_fields(m, payload); }
int pack(const Odometry& m, uint8_t* payload) { return pack_fields(m, payload); }
int pack(const ObstacleDistance& m, uint8_t* payload) { return pack_fields(m, payload); }
int pack(const Attitude& m, uint8_t* payload) { return pack_fields(m, payload); }
int pack(const AttitudeQuaternion& m, uint8_t* payload) { return pack_fields(m, payload); }
int pack(const SetGpsGlobalOrigin& m, uint8_t* payload) { return pack_fields(m, payload); }
int pack(const NamedValueFloat& m, uint8_t* payload) { return pack_fields(m, payload); }

void unpack(const uint8_t* p, int length, Heartbeat* m) { unpack_fields(p, length, m); }
void unpack(const uint8_t* p, int length, StatusText* m) { unpack_fields(p, length, m); }
void unpack(const uint8_t* p, int length, Timesync* m) { unpack_fields(p, length, m); }
void unpack(const uint8_t* p, int length, Odometry* m) { unpack_fields(p, length, m); }
void unpack(const uint8_t* p, int length, ObstacleDistance* m) { unpack_fields(p, length, m); }
void unpack(const uint8_t* p, int length, Attitude* m) { unpack_fields(p, length, m); }
void unpack(const uint8_t* p, int length, AttitudeQuaternion* m) { unpack_fields(p, length, m); }
void unpack(const uint8_t* p, int length, SetGpsGlobalOrigin* m) { unpack_fields(p, length, m); }
void unpack(const uint8_t* p, int length, NamedValueFloat* m) { unpack_fields(p, length, m); }

const char* StatusTextJoiner::add(const StatusText& m) {
  if (m.id == 0 || m.chunk_seq == 0) used_ = 0;
  const size_t chars = std::min(strnlen(m.text, sizeof(m.text)), sizeof(text_) - 1 - used_);
  std::memcpy(text_ + used_, m.text, chars);
  used_ += chars;
  text_[used_] = '\0';
  const bool more = m.id != 0 && chars == sizeof(m.text);  // the last chunk holds a NUL
  return more ? nullptr : text_;
}

int Encoder::frame(const MessageSpec& spec, const uint8_t* payload, int length, uint8_t* out) {
  while (length > 1 && payload[length - 1] == 0) --length;  // v2: trailing zeros are implied
  out[0] = kMagicV2;
  out[1] = static_cast<uint8_t>(length);
  out[2] = 0;  // incompat flags: unsigned
  out[3] = 0;  // compat flags
  out[4] = sequence_++;
  out[5] = system_id_;
  out[6] = component_id_;
  out[7] = static_cast<uint8_t>(spec.id & 0xFF);
  out[8] = static_cast<uint8_t>((spec.id >> 8) & 0xFF);
  out[9] = static_cast<uint8_t>((spec.id >> 16) & 0xFF);
  std::memcpy(out + kHeaderBytes, payload, static_cast<size_t>(length));
  uint16_t crc = crc_accumulate(out + 1, static_cast<size_t>(kHeaderBytes - 1 + length), kCrcInit);
  crc = crc_accumulate(spec.crc_extra, crc);
  out[kHeaderBytes + length] = static_cast<uint8_t>(crc & 0xFF);
  out[kHeaderBytes + length + 1] = static_cast<uint8_t>(crc >> 8);
  return kHeaderBytes + length + kChecksumBytes;
}

size_t Decoder::feed(const uint8_t* bytes, size_t n, Frame* frame, bool* got) {
  *got = false;
  size_t used = 0;
  for (;;) {
    // Drop what cannot start a frame.
    int start = 0;
    while (start < have_ && buffer_[start] != kMagicV2) ++start;
    if (start > 0) {
      counters_.bytes_skipped += static_cast<uint64_t>(start);
      std::memmove(buffer_, buffer_ + start, static_cast<size_t>(have_ - start));
      have_ -= start;
    }
    need_ = kHeaderBytes;
    if (have_ >= 3) {
      need_ = kHeaderBytes + buffer_[1] + kChecksumBytes +
              ((buffer_[2] & kIncompatSigned) != 0 ? kSignatureBytes : 0);
    }
    if (have_ >= need_) {
      if (finish(frame)) {
        std::memmove(buffer_, buffer_ + need_, static_cast<size_t>(have_ - need_));
        have_ -= need_;
        *got = true;
        return used;
      }
      // Not a frame after all: resynchronise on the next magic byte after this one.
      ++counters_.bytes_skipped;
      std::memmove(buffer_, buffer_ + 1, static_cast<size_t>(have_ - 1));
      --have_;
      continue;
    }
    if (used == n) return used;
    buffer_[have_++] = bytes[used++];
  }
}

bool Decoder::finish(Frame* frame) {
  const uint8_t length = buffer_[1];
  const uint8_t incompat = buffer_[2];
  const uint32_t id = buffer_[7] | (buffer_[8] << 8) | (static_cast<uint32_t>(buffer_[9]) << 16);
  const MessageSpec* spec = find_spec(id);
  if ((incompat & ~kIncompatSigned) != 0 || length == 0) return false;
  if (spec == nullptr) {
    ++counters_.unknown_messages;
    return false;
  }
  uint16_t crc =
      crc_accumulate(buffer_ + 1, static_cast<size_t>(kHeaderBytes - 1 + length), kCrcInit);
  crc = crc_accumulate(spec->crc_extra, crc);
  const uint16_t sent = static_cast<uint16_t>(buffer_[kHeaderBytes + length] |
                                              (buffer_[kHeaderBytes + length + 1] << 8));
  if (crc != sent || length > spec->payload_bytes) {
    ++counters_.crc_errors;
    return false;
  }
  frame->length = length;
  frame->sequence = buffer_[4];
  frame->system_id = buffer_[5];
  frame->component_id = buffer_[6];
  frame->message_id = id;
  std::memset(frame->payload, 0, sizeof(frame->payload));
  std::memcpy(frame->payload, buffer_ + kHeaderBytes, length);
  if (synced_sequence_) {
    counters_.lost_frames += static_cast<uint8_t>(frame->sequence - next_sequence_);
  }
  synced_sequence_ = true;
  next_sequence_ = static_cast<uint8_t>(frame->sequence + 1);
  ++counters_.frames;
  return true;
}

}  // namespace rgbdtam::mavlink
