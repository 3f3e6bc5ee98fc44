#include "monitor_state.hpp"

#include <cmath>
#include <cstring>

#include "json_line.hpp"

namespace rgbdtam {

namespace {
// An ODOMETRY that claims a pose (quality 0-100; -1 is a failed one) must carry one: a finite
// position and a unit quaternion. Anything else no receiver may fly on, whoever sent it.
bool claims_a_usable_pose(const mavlink::Odometry& o) {
  if (o.quality < 0 || o.quality > 100) return false;
  double norm2 = 0;
  for (const float v : o.q) {
    if (!std::isfinite(v)) return false;
    norm2 += static_cast<double>(v) * v;
  }
  for (const float v : {o.x, o.y, o.z}) {
    if (!std::isfinite(v)) return false;
  }
  constexpr double kMostNormError = 0.01;
  return std::fabs(std::sqrt(norm2) - 1.0) <= kMostNormError;
}
}  // namespace

MonitorEvent MonitorState::on_frame(const mavlink::Frame& f, int64_t now_ns) {
  if (f.message_id == mavlink::kOdometry.id) {
    mavlink::Odometry o;
    mavlink::unpack(f.payload, f.length, &o);
    ++odometry;
    ++window_count_;
    const bool failed = o.quality == -1;
    // A pose older than the last valid one would make a saved trajectory go back in time.
    const bool in_order = saved_until_usec_ == 0 || o.time_usec > saved_until_usec_;
    if (!failed && (!claims_a_usable_pose(o) || !in_order)) {
      ++malformed;  // counted, never drawn, shown or saved
      return MonitorEvent::kNone;
    }
    last = o;
    ++(failed ? lost : valid);
    if (!failed) saved_until_usec_ = o.time_usec;
    track.push_back({last.x, last.y, last.z, !failed, last.reset_counter});
    return failed ? MonitorEvent::kNone : MonitorEvent::kValidPose;
  }
  if (f.message_id == mavlink::kHeartbeat.id) {
    mavlink::Heartbeat hb;
    mavlink::unpack(f.payload, f.length, &hb);
    ++heartbeats;
    // An autopilot's own HEARTBEAT (the monitor behind a router); rgbdtam's says "invalid".
    if (hb.autopilot != mavlink::kMavAutopilotInvalid) {
      char text[96];
      std::snprintf(text, sizeof(text), "present, system %u (MAV_AUTOPILOT %u)", f.system_id,
                    hb.autopilot);
      autopilot = text;
    } else {
      system_status = hb.system_status;
    }
    return MonitorEvent::kNone;
  }
  if (f.message_id == mavlink::kNamedValueFloat.id) {
    mavlink::NamedValueFloat v;
    mavlink::unpack(f.payload, f.length, &v);
    const std::string name(v.name, strnlen(v.name, sizeof(v.name)));
    if (name == "lat_med_ms") latency_median_ms = v.value;
    if (name == "lat_p95_ms") latency_p95_ms = v.value;
    if (name == "lat_max_ms") latency_max_ms = v.value;
    return MonitorEvent::kNone;
  }
  if (f.message_id == mavlink::kStatusText.id) {
    mavlink::StatusText t;
    mavlink::unpack(f.payload, f.length, &t);
    const char* whole = joiner_.add(t);
    if (whole == nullptr) return MonitorEvent::kNone;  // more chunks to come
    ++status_texts;
    texts.push_back({(now_ns - start_ns_) * 1e-9, t.severity, whole});
    if (texts.size() > kMaxTexts) texts.pop_front();
    // What the firmware says about its autopilot (PoseLink reports it appearing and falling
    // silent).
    constexpr const char* kHeard = "autopilot: heard, ";
    if (std::strncmp(whole, kHeard, std::strlen(kHeard)) == 0) {
      autopilot = std::string("present, ") + (whole + std::strlen(kHeard));
    } else if (std::strncmp(whole, "autopilot: silent", 17) == 0) {
      autopilot = "silent";
    }
    return MonitorEvent::kText;
  }
  return MonitorEvent::kNone;
}

void MonitorState::tick(int64_t now_ns, const mavlink::DecoderCounters& counters) {
  link = counters;
  if (now_ns - window_start_ns_ >= 1'000'000'000) {
    rate_hz = window_count_ / ((now_ns - window_start_ns_) * 1e-9);
    window_start_ns_ = now_ns;
    window_count_ = 0;
  }
}

const char* MonitorState::state_name() const {
  if (odometry == 0) return "waiting";
  return last.quality < 0 ? "LOST" : "tracking";
}

void MonitorState::write_json(std::FILE* out, size_t since) const {
  JsonLine j(out);
  j.text("state", state_name())
      .number("rate_hz", rate_hz, 1)
      .integer("quality", last.quality)
      .integer("reset_counter", last.reset_counter)
      .integer("system_status", system_status)
      .integer("odometry", static_cast<long long>(odometry))
      .integer("valid", static_cast<long long>(valid))
      .integer("malformed", static_cast<long long>(malformed))
      .integer("lost", static_cast<long long>(lost))
      .integer("heartbeats", static_cast<long long>(heartbeats))
      .integer("crc_errors", static_cast<long long>(link.crc_errors))
      .integer("sequence_gaps", static_cast<long long>(link.lost_frames))
      .integer("bytes_skipped", static_cast<long long>(link.bytes_skipped))
      .text("autopilot", autopilot.c_str())
      .number("latency_median_ms", latency_median_ms, 2)
      .number("latency_p95_ms", latency_p95_ms, 2)
      .number("latency_max_ms", latency_max_ms, 2)
      .integer("track_size", static_cast<long long>(track.size()))
      .integer("track_from", static_cast<long long>(since));
  std::FILE* s = j.member("track");  // [x, y, z, valid, reset counter] in m, local FRD
  std::fputc('[', s);
  for (size_t i = since; i < track.size(); ++i) {
    const MonitorPoint& p = track[i];
    std::fputs(i == since ? "[" : ",[", s);
    for (float v : {p.x_m, p.y_m, p.z_m}) {
      if (std::isfinite(v)) {
        std::fprintf(s, "%.4f,", static_cast<double>(v));
      } else {
        std::fputs("null,", s);  // a lost frame's position may be NaN
      }
    }
    std::fprintf(s, "%d,%u]", p.valid ? 1 : 0, p.reset_counter);
  }
  std::fputc(']', s);
  s = j.member("texts");
  std::fputc('[', s);
  for (size_t i = 0; i < texts.size(); ++i) {
    std::fprintf(s, "%s[%.2f,%u,", i == 0 ? "" : ",", texts[i].time_s, texts[i].severity);
    write_json_string(s, texts[i].text.c_str());
    std::fputc(']', s);
  }
  std::fputc(']', s);
  j.end();
}

}  // namespace rgbdtam
