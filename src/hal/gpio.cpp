#include "rgbdtam/hal/gpio.hpp"

#include <errno.h>
#include <gpiod.h>

#include <cstring>

namespace rgbdtam {

void FakeGpio::set(int line, bool on) {
  if (line < 0 || line >= kLines) return;
  if (on && !level_[line]) ++rising_[line];
  level_[line] = on;
  ++writes_[line];
}

LibgpiodOutputs::~LibgpiodOutputs() {
  for (int i = 0; i < count_; ++i) gpiod_line_release(lines_[i]);
  if (chip_ != nullptr) gpiod_chip_close(chip_);
}

Status LibgpiodOutputs::open(const char* chip, const int* lines, int count) {
  chip_ = gpiod_chip_open(chip);
  if (chip_ == nullptr) {
    return Status::error(StatusCode::kIoError, "GPIO chip '%s': %s", chip, std::strerror(errno));
  }
  for (int i = 0; i < count && count_ < kMaxLines; ++i) {
    if (lines[i] < 0) continue;
    gpiod_line* line = gpiod_chip_get_line(chip_, static_cast<unsigned>(lines[i]));
    if (line == nullptr || gpiod_line_request_output(line, "rgbdtam", 0) != 0) {
      return Status::error(StatusCode::kIoError, "GPIO chip '%s' line %d as output: %s", chip,
                           lines[i], std::strerror(errno));
    }
    lines_[count_] = line;
    offsets_[count_] = lines[i];
    ++count_;
  }
  return Status::ok();
}

void LibgpiodOutputs::set(int line, bool on) {
  for (int i = 0; i < count_; ++i) {
    if (offsets_[i] != line) continue;
    if (gpiod_line_set_value(lines_[i], on ? 1 : 0) != 0) ++errors_;
    return;
  }
}

}  // namespace rgbdtam
