// The virtual board's relay, its camera (vivid's output shown to the board's
// capture) and the rig's faults (gabarit/link/rig_faults.hpp), injected when
// the harness asks.
#include "relay.hpp"

namespace gabarit::relay {

bool Relay::camera_up(bool wrap_sequence, std::string& error) {
  for (int i = 0; i < 50 && ::access(c_.output.c_str(), F_OK) != 0; ++i) sleep_ms(20);
  if (!vivid::setup(c_.capture, c_.output, c_.width, c_.height, error)) return false;
  if (!vivid::set_control(c_.capture, vivid::kWrapSequence, wrap_sequence ? 1 : 0, error)) return false;
  if (!output_.open(c_.output, error)) return false;
  // Something from the output on the capture side before the board opens
  // it: the frame being shown, else a black one (never vivid's test pattern).
  std::vector<std::uint8_t> black;
  const std::uint8_t* pixels = nullptr;
  std::uint32_t w = 0, h = 0;
  if (current_) {
    pixels = current_->frame.pixels.data(), w = current_->frame.width, h = current_->frame.height;
  } else if (!shown_.empty()) {
    pixels = shown_.data(), w = shown_width_, h = shown_height_;
  } else {
    black.assign(std::size_t{c_.width} * c_.height, 0);
    pixels = black.data(), w = c_.width, h = c_.height;
  }
  if (!output_.show(pixels, w, h, 0, error)) return false;
  // vivid starts looping only once its output thread has taken the buffer:
  // until the capture side shows this very frame, the board must not open
  // it (it would track vivid's test pattern).
  if (!loop_shows(pixels, w, h, error)) return false;
  // The board opens the camera only through this link, once it is set up,
  // as a udev rule would publish it.
  ::unlink(c_.camera_link.c_str());
  if (::symlink(c_.capture.c_str(), c_.camera_link.c_str()) != 0) return error = "making " + c_.camera_link, false;
  return true;
}

bool Relay::loop_shows(const std::uint8_t* pixels, std::uint32_t w, std::uint32_t h, std::string& error) {
  const std::uint32_t want = link::frame_crc(ImageView{pixels, w, h, w});
  board::V4l2Capture capture;
  board::CaptureOptions o;
  o.device = c_.capture;
  o.pixel_format = board::kFourccGrey;
  o.buffers = 2;
  if (!capture.open(o)) return error = "checking the loop: " + capture.error(), false;
  const std::uint64_t end = now_us() + 3000000u;
  while (now_us() < end) {
    pollfd p{capture.fd(), POLLIN, 0};
    if (::poll(&p, 1, 100) <= 0) continue;
    board::CapturedFrame f;
    const board::CaptureEvent e = capture.dequeue(f);
    if (e == board::CaptureEvent::kDeviceLost) return error = "checking the loop: " + capture.error(), false;
    if (e != board::CaptureEvent::kFrame) continue;
    const std::size_t stride = capture.layout().bytes_per_line;
    const bool whole = f.bytes_used >= std::size_t{h} * stride;  // a short buffer cannot show the frame
    const std::uint32_t crc = whole ? link::frame_crc(ImageView{f.data, w, h, stride}) : ~want;
    (void)capture.requeue(f.index);
    if (crc == want) return true;
  }
  return error = "vivid's capture side did not show the output's frame in 3 s (Loop Video off?)", false;
}

void Relay::camera_down() {
  ::unlink(c_.camera_link.c_str());
  output_.close();
}

bool Relay::reload_camera(int absent_ms, bool wrap_sequence, std::string& error) {
  // The capture is disconnected before the output closes: the other way
  // round, vivid's capture went on streaming for a frame or two without its
  // loop's input, and the board tracked pixels the harness never sent (its
  // reference could not follow them; seen as "stale pose" lines in the log).
  std::string ignored;
  (void)vivid::set_control(c_.capture, vivid::kDisconnect, 1, ignored);
  camera_down();
  // The board closes the device when it sees it gone; until then the module is in use.
  if (!pump_until([&] { return run_command("rmmod vivid 2>/dev/null") == 0; }, 5000))
    return error = "vivid could not be unloaded in 5 s (the board kept it open)", false;
  pump_until([] { return false; }, absent_ms);
  if (run_command("insmod " + c_.vivid_module + " " + c_.vivid_params) != 0) return error = "insmod vivid failed", false;
  return camera_up(wrap_sequence, error);
}

void Relay::reshow_current() {
  if (!current_ || !output_.is_open()) return;
  const std::uint64_t t = now_us();
  if (t < current_->reshow) return;
  // A reloaded camera starts black: show the frame again now and then.
  std::string error;
  if (!output_.show(current_->frame.pixels.data(), current_->frame.width, current_->frame.height, 0, error)) {
    log("vivid output: %s", error.c_str());
    output_.close();
  }
  if (shown_.data() != current_->frame.pixels.data()) {  // kept for a camera reloaded between frames
    shown_.assign(current_->frame.pixels.begin(), current_->frame.pixels.end());
    shown_width_ = current_->frame.width;
    shown_height_ = current_->frame.height;
  }
  current_->reshow = t + 500000u;
}

std::optional<link::Injected> Relay::inject(RigFault fault, const link::Inject& request) {
  link::Injected a;
  a.token = request.token;
  a.kind = request.kind;
  a.outcome = link::InjectOutcome::kFailed;
  a.started = now_us();
  a.attempts = 1;
  std::string error, evidence;
  std::optional<bool> detected;
  switch (fault) {
    case RigFault::kSequenceWrap:
      // vivid starts a stream at 2^32 - 128 with its wrap control on: the
      // camera is restarted with it armed, and the fault ends when the board
      // has seen the sequence go back, 128 frames later, while tracking goes on.
      if (!reload_camera(0, true, error)) break;
      a.ended = now_us();
      pending_wraps_.push_back({a, wraps_, now_us() + 15000000u});
      return std::nullopt;
    case RigFault::kCameraError:
    case RigFault::kCameraDrop:
    case RigFault::kCameraDisconnect:
    case RigFault::kModuleReload: detected = inject_camera(fault, a.attempts, evidence, error); break;
    default: detected = inject_link(fault, evidence, error); break;
  }
  if (detected) a.outcome = *detected ? link::InjectOutcome::kDetected : link::InjectOutcome::kUndetected;
  char text_out[160] = {};
  std::snprintf(text_out, sizeof text_out, "%s", (error.empty() ? evidence : error).c_str());
  a.ended = now_us();
  link::set_text(a.evidence, text_out);
  return a;
}

std::optional<bool> Relay::inject_camera(RigFault fault, std::uint16_t& attempts, std::string& evidence, std::string& error) {
  const auto done = [&](bool detected, const std::string& what) -> std::optional<bool> {
    evidence = what;
    return detected;
  };
  switch (fault) {
    case RigFault::kCameraError: {
      // vivid loses some injections (no capture buffer queued at its tick): up to five tries.
      const std::uint64_t before = camera_errors_;
      for (attempts = 1; attempts <= 5; ++attempts) {
        if (!vivid::set_control(c_.capture, vivid::kDqbufError, 1, error)) break;
        if (pump_until([&] { return camera_errors_ > before; }, 300)) break;
      }
      if (!error.empty()) return std::nullopt;
      if (attempts > 5) attempts = 5;
      return done(camera_errors_ > before, text("board: %llu error-flagged buffer(s) skipped", static_cast<unsigned long long>(camera_errors_ - before)));
    }
    case RigFault::kCameraDrop: {
      const std::uint64_t before = camera_gaps_;
      if (!vivid::set_control(c_.capture, vivid::kDroppedPercent, 50, error)) return std::nullopt;
      pump_until([&] { return camera_gaps_ > before; }, 1000);
      std::string ignored;
      (void)vivid::set_control(c_.capture, vivid::kDroppedPercent, 0, ignored);
      return done(camera_gaps_ > before, text("board: %llu sequence gap(s) reported", static_cast<unsigned long long>(camera_gaps_ - before)));
    }
    case RigFault::kCameraDisconnect:
    case RigFault::kModuleReload: {
      const std::uint64_t lost = camera_lost_, back = camera_back_;
      if (!reload_camera(fault == RigFault::kModuleReload ? 1000 : 0, false, error)) return std::nullopt;
      pump_until([&] { return camera_back_ > back; }, 5000);
      return done(camera_lost_ > lost && camera_back_ > back, text("board: camera lost (%llu) and reopened (%llu)",
           static_cast<unsigned long long>(camera_lost_ - lost), static_cast<unsigned long long>(camera_back_ - back)));
    }
    default: break;
  }
  return std::nullopt;
}

std::optional<bool> Relay::inject_link(RigFault fault, std::string& evidence, std::string& error) {
  const auto done = [&](bool detected, const std::string& what) -> std::optional<bool> {
    evidence = what;
    return detected;
  };
  switch (fault) {
    case RigFault::kUsbStall: {
      const std::uint64_t cleared = usb_.stats().halts_cleared;
      if (!usb_.halt_in_endpoint()) {
        error = usb_.error();
        return std::nullopt;
      }
      pump_until([&] { return usb_.stats().halts_cleared > cleared; }, 2000);
      return done(usb_.stats().halts_cleared > cleared, text("host: LIBUSB_ERROR_PIPE on IN, halt cleared"));
    }
    case RigFault::kUsbUnplug: {
      const std::string udc = read_file(c_.gadget_dir + "/UDC");
      const std::uint64_t losses = usb_.stats().losses, opens = usb_.stats().opens;
      if (udc.empty() || !write_file(c_.gadget_dir + "/UDC", "\n")) {
        error = "unbinding " + c_.gadget_dir + "/UDC";
        return std::nullopt;
      }
      pump_until([&] { return usb_.stats().losses > losses || !usb_.is_open(); }, 1000);
      sleep_ms(100);
      if (!write_file(c_.gadget_dir + "/UDC", udc + "\n")) {
        error = "binding the gadget again";
        return std::nullopt;
      }
      pump_until([&] { return usb_.stats().opens > opens; }, 5000);
      return done(usb_.stats().opens > opens, text("host: device gone and reopened by polling (%llu loss(es))",
           static_cast<unsigned long long>(usb_.stats().losses - losses)));
    }
    case RigFault::kUsbTimeout: {
      // Transfers given 1 ms: they expire, some with part of a message moved.
      const std::uint64_t timeouts = usb_.stats().timeouts;
      const std::uint64_t end = now_us() + 200000u;
      std::vector<std::byte> m;
      while (now_us() < end && usb_.is_open()) {
        if (usb_.receive(m, 1) == link::UsbResult::kOk) on_board_message(m);
      }
      return done(usb_.stats().timeouts > timeouts, text("host: %llu transfer timeout(s), %llu with a partial message kept",
           static_cast<unsigned long long>(usb_.stats().timeouts - timeouts),
           static_cast<unsigned long long>(usb_.stats().partial_timeouts)));
    }
    case RigFault::kBoardKill: {
      expecting_kill_ = true;
      board_.kill_now(SIGKILL);  // reaped: its line requests are released
      lines_.begin_down(now_us());
      usb_.close();
      pump_until([] { return false; }, 300);  // down for a while: the lines must sit at their safe level
      const bool safe = lines_.end_down();
      expecting_kill_ = false;
      board_restart("killed");
      const bool back = wait_usb_open(10000);
      return done(back && safe, text("board: killed (SIGKILL), lines low while down: %s, USB back: %s", safe ? "yes" : "NO",
           back ? "yes" : "NO"));
    }
    case RigFault::kUsbCorrupt: {
      board_stats_.reset();
      std::byte req[1] = {};
      (void)board_send(link::MessageType::kStats, std::span<const std::byte>(req, 0));
      pump_until([&] { return board_stats_.has_value(); }, 1000);
      const std::uint32_t bad_before = board_stats_ ? board_stats_->bad_crc : 0;
      // A PING with one payload bit flipped after its CRC.
      const link::Ping ping{++ping_token_, now_us()};
      std::byte out[link::kPingBytes];
      std::byte mangle[link::kHeaderBytes + 1] = {};
      mangle[link::kHeaderBytes] = std::byte{0x10};
      (void)board_send(link::MessageType::kPing, std::span<const std::byte>(out, link::encode(ping, out)), mangle);
      board_stats_.reset();
      (void)board_send(link::MessageType::kStats, std::span<const std::byte>(req, 0));
      pump_until([&] { return board_stats_.has_value(); }, 1000);
      const std::uint32_t bad_after = board_stats_ ? board_stats_->bad_crc : 0;
      return done(bad_after == bad_before + 1, text("board: bad CRC count %u -> %u", bad_before, bad_after));
    }
    default: break;
  }
  return std::nullopt;
}

void Relay::check_wraps() {
  for (auto it = pending_wraps_.begin(); it != pending_wraps_.end();) {
    if (wraps_ > it->wraps_before || now_us() > it->deadline) {
      link::Injected a = it->answer;
      const bool seen = wraps_ > it->wraps_before;
      a.outcome = seen ? link::InjectOutcome::kDetected : link::InjectOutcome::kUndetected;
      a.ended = now_us();
      link::set_text(a.evidence, seen ? "board: sequence number went back (wrapped past 2^32)" : "no wrap seen in 15 s");
      endpoint_->report_injected(a);
      flush();
      it = pending_wraps_.erase(it);
    } else {
      ++it;
    }
  }
}

}  // namespace gabarit::relay
