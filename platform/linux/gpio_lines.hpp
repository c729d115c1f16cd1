// The board's GPIO lines, behind one small interface so that the libgpiod
// version is one file's concern (gpio_lines_gpiod_v1.cpp is the libgpiod 1.6
// implementation Debian 12 ships; a libgpiod 2 port replaces that file only).
//
//   lock    output, high while tracking is confident
//   strobe  output, one pulse per processed frame
//   trigger input (optional), each rising edge starts or stops tracking
//
// Outputs are requested low and returned low (the documented safe level)
// by release() and by the destructor.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

namespace gabarit::board {

struct GpioOptions {
  std::string chip;            // "gpiochip0", "/dev/gpiochip0" or a chip label; empty: no GPIO
  int lock_line = -1;          // line offsets on that chip; -1: not used
  int strobe_line = -1;
  int trigger_line = -1;
  std::uint32_t strobe_us = 100;  // strobe pulse width
};

class GpioLines {
 public:
  GpioLines();
  ~GpioLines();
  GpioLines(const GpioLines&) = delete;
  GpioLines& operator=(const GpioLines&) = delete;

  // Requests the lines. False with error() set on failure (nothing held).
  [[nodiscard]] bool open(const GpioOptions& options, const std::string& consumer);
  void release();
  const std::string& error() const;

  // Outputs: false (with error()) if the kernel refused the write.
  [[nodiscard]] bool set_lock(bool high);
  [[nodiscard]] bool pulse_strobe();
  // The trigger's event file descriptor for poll(), -1 without a trigger.
  int trigger_fd() const;
  // Reads the pending trigger events; returns the number of rising edges.
  [[nodiscard]] int read_trigger_rising_edges();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace gabarit::board
