#pragma once
// GPIO outputs behind a seam: the runtime's status LED and frame trigger write lines; hal
// implements them with libgpiod, or a fake chip for host emulation and tests.

namespace rgbdtam {

class GpioOutputs {
 public:
  virtual ~GpioOutputs() = default;
  // Sets one requested output line; only the line numbers given at open are used.
  virtual void set(int line, bool on) = 0;
};

}  // namespace rgbdtam
