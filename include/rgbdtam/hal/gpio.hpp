#pragma once
// GPIO outputs: the thin libgpiod backend for boards, and a fake chip for host emulation and
// tests that records what was written.

#include <cstdint>

#include "rgbdtam/core/status.hpp"
#include "rgbdtam/port/gpio_outputs.hpp"

struct gpiod_chip;
struct gpiod_line;

namespace rgbdtam {

class FakeGpio : public GpioOutputs {
 public:
  static constexpr int kLines = 64;
  void set(int line, bool on) override;
  bool level(int line) const { return level_[line]; }
  uint32_t writes(int line) const { return writes_[line]; }
  uint32_t rising_edges(int line) const { return rising_[line]; }

 private:
  bool level_[kLines] = {};
  uint32_t writes_[kLines] = {};
  uint32_t rising_[kLines] = {};
};

// Requests the given output lines (-1 = unused) of a chip through libgpiod, at open.
class LibgpiodOutputs : public GpioOutputs {
 public:
  static constexpr int kMaxLines = 4;
  ~LibgpiodOutputs() override;
  Status open(const char* chip, const int* lines, int count);
  void set(int line, bool on) override;
  uint32_t errors() const { return errors_; }

 private:
  gpiod_chip* chip_ = nullptr;
  gpiod_line* lines_[kMaxLines] = {};
  int offsets_[kMaxLines] = {};
  int count_ = 0;
  uint32_t errors_ = 0;
};

}  // namespace rgbdtam
