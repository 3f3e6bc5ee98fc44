#pragma once
// A byte transport for the pose link: serial or UDP (src/hal), or a test double. Called from
// the link task's thread only. Both calls are non-blocking.

#include <cstddef>
#include <cstdint>

namespace rgbdtam {

struct LinkCounters {
  uint64_t tx_frames = 0;  // whole frames handed to the transport
  uint64_t tx_bytes = 0;
  uint64_t rx_bytes = 0;
  uint64_t drops = 0;       // frames refused because the transport could not take them now
  uint64_t errors = 0;      // failed system calls (the frame is lost)
  int last_error = 0;       // errno of the latest, for the report
  uint64_t lost_bytes = 0;  // queued but never written: the transport failed under them
};

class ByteLink {
 public:
  virtual ~ByteLink() = default;
  // Queues one whole frame, or none of it (a frame is never split by a refusal); false when
  // refused (counted in drops or errors).
  virtual bool send(const uint8_t* bytes, size_t n) = 0;
  // Moves queued bytes towards the wire; returns the bytes still waiting.
  virtual size_t flush() { return 0; }
  // Up to n received bytes; 0 when none are waiting.
  virtual size_t receive(uint8_t* bytes, size_t n) = 0;
  // Bytes per second the medium carries (0: not limited, e.g. UDP on loopback).
  virtual uint32_t line_rate_bytes_per_s() const { return 0; }
  const LinkCounters& counters() const { return counters_; }

 protected:
  LinkCounters counters_;
};

}  // namespace rgbdtam
