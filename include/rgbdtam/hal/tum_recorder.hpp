#pragma once
// Records what a sensor delivers as a TUM RGB-D folder (rgb/, depth/, rgb.txt, depth.txt) that
// `rgbdtam replay` and the benchmark tools read: 8-bit grey colour PNGs named by colour
// timestamp, 16-bit depth PNGs named by depth timestamp. PNG encoding and writing run on the
// recorder's own thread behind a bounded queue of frame slots, so the sensor never waits; a
// frame that finds the queue full is dropped and counted.

#include <atomic>

#include "rgbdtam/core/image.hpp"
#include "rgbdtam/hal/png_encoder.hpp"
#include "rgbdtam/port/latency_stats.hpp"
#include "rgbdtam/port/messages.hpp"
#include "rgbdtam/port/spsc_ring.hpp"
#include "rgbdtam/port/thread_placement.hpp"
#include "rgbdtam/port/worker.hpp"

namespace rgbdtam {

struct RecorderCounters {
  uint32_t written = 0;  // colour frames on disk
  uint32_t depth_written = 0;
  uint32_t dropped = 0;  // the queue was full
  uint64_t bytes = 0;
};

class TumRecorder {
 public:
  static constexpr int kQueueSlots = 8;
  ~TumRecorder();
  // Creates out_dir (which must not hold a recording already) and its lists; frames of other
  // sizes are refused (counted as dropped).
  Status open(const char* out_dir, const SensorImageSize& size);
  Status start(const ThreadPlacement& placement);
  // Sensor side: copies the frame into a free slot; false when the queue is full (counted).
  bool push(const SensorFrame& frame);
  // Writes what is queued, joins, closes the lists; the first write error, if any.
  Status finish();
  // A write failed (a full disk, a lost mount): nothing more is written; finish() says why.
  bool failed() const { return failed_.load(std::memory_order_acquire); }

  RecorderCounters counters() const;
  const LatencyStats& time_per_frame() const { return per_frame_; }

 private:
  struct Slot {
    ImageU8 gray;
    ImageU16 depth;
    int64_t timestamp_ns = 0;
    int64_t depth_timestamp_ns = 0;
    bool has_depth = false;
  };
  // The module on the recorder's thread.
  struct Writer {
    TumRecorder* recorder;
    void step(const Slot& s);
    void tick() {}
    void finish() {}
  };
  void keep_first_error(const Status& s);  // and stop writing
  Status write_frame(const Slot& s);
  Status write_file(const char* relative, const uint8_t* bytes, size_t n);
  // Writes the encoder's output as <folder>/<stamp>.png and lists it.
  Status store_encoded(const char* folder, int64_t stamp_ns, int list_fd);

  char dir_[400] = {};
  SensorImageSize size_;
  int rgb_list_ = -1, depth_list_ = -1;
  int64_t last_depth_ns_ = -1;  // two colour frames may share one depth frame
  SpscRing<Slot> queue_;
  PngEncoder encoder_;
  LatencyStats per_frame_;
  std::atomic<uint32_t> written_{0}, depth_written_{0}, dropped_{0};
  std::atomic<uint64_t> bytes_{0};
  Status error_;
  std::atomic<bool> failed_{false};
  Writer writer_{this};
  WorkerThread<Slot, Writer> worker_;
};

}  // namespace rgbdtam
