// GpioLines on libgpiod 1.x (the C API; its C++ bindings would throw).
#include <gpiod.h>
#include <poll.h>
#include <time.h>

#include <cerrno>
#include <cstring>

#include "gpio_lines.hpp"

namespace gabarit::board {

struct GpioLines::Impl {
  gpiod_chip* chip = nullptr;
  gpiod_line* lock = nullptr;
  gpiod_line* strobe = nullptr;
  gpiod_line* trigger = nullptr;
  std::uint32_t strobe_us = 100;
  std::string error;

  bool fail(const std::string& what) {
    error = what + ": " + std::strerror(errno);
    return false;
  }
  bool request_output(int offset, const std::string& consumer, gpiod_line*& out, const char* role) {
    if (offset < 0) return true;
    out = gpiod_chip_get_line(chip, static_cast<unsigned>(offset));
    if (out == nullptr) return fail(std::string(role) + " line " + std::to_string(offset));
    if (gpiod_line_request_output(out, consumer.c_str(), 0) < 0) {
      out = nullptr;
      return fail(std::string("requesting ") + role + " line " + std::to_string(offset) + " as output");
    }
    return true;
  }
};

GpioLines::GpioLines() : impl_(std::make_unique<Impl>()) {}
GpioLines::~GpioLines() { release(); }
const std::string& GpioLines::error() const { return impl_->error; }

bool GpioLines::open(const GpioOptions& o, const std::string& consumer) {
  release();
  Impl& d = *impl_;
  d.strobe_us = o.strobe_us;
  if (o.chip.empty()) return true;
  d.chip = gpiod_chip_open_lookup(o.chip.c_str());
  if (d.chip == nullptr) return d.fail("GPIO chip '" + o.chip + "'");
  bool ok = d.request_output(o.lock_line, consumer, d.lock, "lock") && d.request_output(o.strobe_line, consumer, d.strobe, "strobe");
  if (ok && o.trigger_line >= 0) {
    d.trigger = gpiod_chip_get_line(d.chip, static_cast<unsigned>(o.trigger_line));
    if (d.trigger == nullptr) {
      ok = d.fail("trigger line " + std::to_string(o.trigger_line));
    } else if (gpiod_line_request_rising_edge_events(d.trigger, consumer.c_str()) < 0) {
      d.trigger = nullptr;
      ok = d.fail("requesting trigger line " + std::to_string(o.trigger_line) + " for rising edges");
    }
  }
  if (!ok) {
    const std::string why = d.error;
    release();
    d.error = why;
  }
  return ok;
}

void GpioLines::release() {
  Impl& d = *impl_;
  for (gpiod_line** line : {&d.lock, &d.strobe}) {
    if (*line != nullptr) {
      (void)gpiod_line_set_value(*line, 0);  // the safe level; nothing more to do if this fails on the way out
      gpiod_line_release(*line);
      *line = nullptr;
    }
  }
  if (d.trigger != nullptr) gpiod_line_release(d.trigger);
  d.trigger = nullptr;
  if (d.chip != nullptr) gpiod_chip_close(d.chip);
  d.chip = nullptr;
}

bool GpioLines::set_lock(bool high) {
  Impl& d = *impl_;
  if (d.lock == nullptr) return true;
  return gpiod_line_set_value(d.lock, high ? 1 : 0) == 0 || d.fail("setting the lock line");
}

bool GpioLines::pulse_strobe() {
  Impl& d = *impl_;
  if (d.strobe == nullptr) return true;
  if (gpiod_line_set_value(d.strobe, 1) < 0) return d.fail("raising the strobe line");
  timespec width{static_cast<time_t>(d.strobe_us / 1000000u), static_cast<long>(d.strobe_us % 1000000u) * 1000L};
  while (nanosleep(&width, &width) < 0 && errno == EINTR) {
  }
  return gpiod_line_set_value(d.strobe, 0) == 0 || d.fail("lowering the strobe line");
}

int GpioLines::trigger_fd() const { return impl_->trigger != nullptr ? gpiod_line_event_get_fd(impl_->trigger) : -1; }

int GpioLines::read_trigger_rising_edges() {
  Impl& d = *impl_;
  if (d.trigger == nullptr) return 0;
  int rising = 0;
  const int fd = gpiod_line_event_get_fd(d.trigger);
  for (;;) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 0) <= 0 || (p.revents & POLLIN) == 0) break;
    gpiod_line_event event{};
    if (gpiod_line_event_read(d.trigger, &event) < 0) {
      d.fail("reading a trigger event");
      return -1;
    }
    if (event.event_type == GPIOD_LINE_EVENT_RISING_EDGE) ++rising;
  }
  return rising;
}

}  // namespace gabarit::board
