// gabarit-hil-relay — the virtual board's test rig, inside the guest. To the
// harness on the host (over virtio-serial) it is a DUT speaking the HIL link;
// behind it is the real board application:
//
//   harness --virtio-serial--> relay --vivid output--> [vivid loop] --V4L2--> gabarit-board
//   harness <--virtio-serial-- relay <--libusb, dummy_hcd-- FunctionFS gadget <-- gabarit-board
//
// Each frame the harness sends is shown on vivid's output until the board
// answers it: the board's POSE carries the CRC-32C of the luma it tracked,
// which names the frame (vivid repeats and drops frames; the board skips a
// repeat). The relay samples the board's lock and strobe lines in gpio-sim
// and stamps the strobe's edge on the guest's monotonic clock, the clock of
// the board's capture and pose times. It starts, watches and restarts the
// board, and injects the rig's faults (gabarit/link/rig_faults.hpp) when the
// harness asks (INJECT), answering with what detected each (INJECTED).
//
// usage: gabarit-hil-relay [options] -- BOARD_PROGRAM [BOARD_ARGS...]
#include <cstdio>

#include "relay.hpp"

namespace gabarit::relay {

bool Relay::board_send(link::MessageType type, std::span<const std::byte> payload, std::span<const std::byte> mangle) {
  if (!usb_.is_open()) return false;
  const link::Header h = sequence_.stamp(type);
  std::vector<std::byte> m(link::message_bytes(payload.size()));
  std::size_t n = 0;
  if (link::encode_message(h, payload, m, n) != Status::kOk) return false;
  for (std::size_t i = 0; i < mangle.size() && i < n; ++i) m[i] ^= mangle[i];
  return usb_.send(m, 500) == link::UsbResult::kOk;
}

void Relay::pump_usb(int ms) {
  if (!usb_.is_open()) {
    if (!usb_.open()) {
      sleep_ms(std::min(ms, 20));  // polling for the device: no hotplug events without udev
      return;
    }
    log("USB: %s (serial %s) open", usb_.product().c_str(), usb_.serial().c_str());
  }
  if (now_us() - last_ping_ > 100000) {  // the host's acks travel on PINGs
    last_ping_ = now_us();
    const link::Ping ping{++ping_token_, now_us()};
    std::byte out[link::kPingBytes];
    (void)board_send(link::MessageType::kPing, std::span<const std::byte>(out, link::encode(ping, out)));
  }
  std::vector<std::byte> m;
  if (usb_.receive(m, static_cast<unsigned>(std::max(ms, 1))) == link::UsbResult::kOk) on_board_message(m);
}

void Relay::on_board_message(const std::vector<std::byte>& m) {
  link::Header h;
  std::span<const std::byte> payload;
  if (link::decode_message(m, h, payload) != Status::kOk) return;
  // In sequence only (go-back-N): a message after a lost one is dropped, and
  // the board sends both again, since the ack (the last taken) stays put.
  if (!sequence_.in_order(h.seq)) {
    ++(link::seq_after(h.seq, sequence_.ack()) ? board_out_of_sequence_ : board_duplicates_);
    return;
  }
  std::uint32_t skipped = 0;
  (void)sequence_.accept(h.seq, skipped);  // in order: nothing skipped
  switch (h.type) {
    case link::MessageType::kCaps: {
      link::Caps caps;
      if (link::decode(payload, caps) == Status::kOk) board_caps_ = caps;
      break;
    }
    case link::MessageType::kStats: {
      link::Stats s;
      if (link::decode(payload, s) == Status::kOk) board_stats_ = s;
      break;
    }
    case link::MessageType::kEvent: {
      link::Event e;
      if (link::decode(payload, e) != Status::kOk) break;
      switch (e.reason) {
        case link::EventReason::kCameraError: ++camera_errors_; break;
        case link::EventReason::kCameraGap: ++camera_gaps_; break;
        case link::EventReason::kCameraLost: ++camera_lost_; break;
        case link::EventReason::kCameraBack: ++camera_back_; break;
        case link::EventReason::kSequenceWrap: ++wraps_; break;
        default: break;
      }
      break;
    }
    case link::MessageType::kPose: {
      link::PoseReport p;
      if (link::decode(payload, p) != Status::kOk) break;
      if (!current_ || p.frame_crc != current_->crc) {
        ++stale_poses_;
        // The board tracked pixels the harness is not waiting for: its
        // reference will not see that frame. Say which, for the report.
        // The newest shown frame with those pixels (a still scene repeats them).
        std::string was = "no frame shown lately";
        for (std::size_t i = 0; i < recent_count_ && i < recent_.size(); ++i) {
          const ShownFrame& shown = recent_[(recent_count_ - 1 - i) % recent_.size()];
          if (shown.crc == p.frame_crc) {
            was = "frame " + std::to_string(shown.frame_id);
            break;
          }
        }
        log("stale pose: the board's tracked frame %u has CRC-32C %08x (%s); waiting for %s", p.frame_id, p.frame_crc, was.c_str(),
            current_ ? ("frame " + std::to_string(current_->frame.frame_id)).c_str() : "no frame");
        break;
      }
      // The strobe follows the pose: its edge, if the sampler saw it.
      if (const std::uint64_t edge = lines_.edge_after(p.done, 20); edge != 0) p.strobed = edge;
      else ++strobes_missed_;
      lines_.forget_edges_before(p.done);
      current_.reset();
      endpoint_->report_pose(p, p.done);
      flush();
      break;
    }
    default: break;  // PONG, BYE: their acks were the point
  }
}

bool Relay::wait_usb_open(int ms) {
  return pump_until([&] { return usb_.is_open(); }, ms);
}

bool Relay::board_hello(const link::Hello& hello, link::Caps& caps) {
  const std::uint64_t end = now_us() + 20000000u;
  while (now_us() < end) {
    if (!wait_usb_open(static_cast<int>((end - now_us()) / 1000))) break;
    board_caps_.reset();
    std::byte out[link::kHelloBytes];
    if (!board_send(link::MessageType::kHello, std::span<const std::byte>(out, link::encode(hello, out)))) continue;
    if (pump_until([&] { return board_caps_ && board_caps_->run_id == hello.run_id; }, 1000)) {
      caps = *board_caps_;
      return true;
    }
  }
  return false;
}

void Relay::keep_board_alive() {
  if (board_.alive()) return;
  if (expecting_kill_) return;
  const int s = board_.last_status();
  log("the board's program ended (%s %d): starting it again", WIFSIGNALED(s) ? "signal" : "status",
      WIFSIGNALED(s) ? WTERMSIG(s) : WEXITSTATUS(s));
  board_restart("the board's program ended");
}

void Relay::board_restart(const char* why) {
  usb_.close();
  sequence_.forget_peer();  // a new program numbers its messages afresh
  ++board_restarts_;
  if (!board_.start(c_)) log("cannot start the board's program");
  current_.reset();
  // The tracker behind the link starts over: the harness must say HELLO again.
  if (endpoint_) {
    endpoint_->report_event(link::EventKind::kRestart, link::EventReason::kBoot, board_.starts(), now_us());
    flush();
  }
  (void)why;
}

void Relay::flush() {
  for (auto m = endpoint_->front_outgoing(); !m.empty(); m = endpoint_->front_outgoing()) {
    harness_.send(m);
    endpoint_->pop_outgoing();
  }
}

void Relay::on_harness_message(std::span<const std::byte> m) {
  endpoint_->on_message(m, now_us());
  if (const link::Hello* hello = endpoint_->pending_hello()) {
    const link::Hello h = *hello;
    current_.reset();
    link::Caps caps;
    if (!board_hello(h, caps)) {
      log("the board did not answer HELLO in 20 s");
      endpoint_->answer_hello(link::Refusal::kNoTable);
    } else {
      endpoint_->set_mode(caps.mode);
      if (caps.refusal != link::Refusal::kNone)
        log("the board refused run %u: %s (its table's CRC-32 %u, the host's %u)", h.run_id, link::refusal_name(caps.refusal),
            caps.table_crc, h.table_crc);
      endpoint_->answer_hello(caps.refusal);
    }
  }
  if (link::Inject in; endpoint_->take_inject(in)) {
    const auto fault = static_cast<RigFault>(in.kind);
    std::optional<link::Injected> a;
    if (in.kind >= 1 && in.kind <= link::kRigFaultCount) {
      log("fault %s", link::rig_fault_name(fault));
      a = inject(fault, in);
    } else {
      a = link::Injected{};
      a->token = in.token;
      a->kind = in.kind;
      a->outcome = link::InjectOutcome::kUnsupported;
    }
    if (a) endpoint_->report_injected(*a);
  }
  // The host's line for the board's console (a board farm reads its verdicts
  // there: docs/hil-farm.md); the relay's output is the board's console.
  if (link::Note note; endpoint_->take_note(note)) {
    std::printf("%s\n", note.text);
    std::fflush(stdout);
  }
  flush();
}

void Relay::take_frames() {
  if (current_) return;
  link::ReadyFrame f;
  if (!endpoint_->next_frame(f)) return;
  const std::uint32_t crc = link::frame_crc(ImageView{f.pixels.data(), f.width, f.height, f.width});
  if (have_screen_ && crc == screen_crc_) {
    // The board cannot tell it from the picture already on the camera (it skips repeats).
    endpoint_->report_failure(link::EventKind::kSkipped, link::EventReason::kSameAsPrevious, 0, now_us());
    flush();
    return;
  }
  Current c;
  c.frame = f;
  c.crc = crc;
  recent_[recent_count_++ % recent_.size()] = {f.frame_id, crc};
  c.shown = now_us();
  c.deadline = c.shown + 5000000u;
  c.reshow = 0;
  current_ = c;
  screen_crc_ = crc;
  have_screen_ = true;
  reshow_current();
}

int Relay::run() {
  std::string error;
  if (!usb_.ready()) return log("libusb: %s", usb_.error().c_str()), 1;
  if (!camera_up(false, error)) return log("camera: %s", error.c_str()), 1;
  if (!lines_.start(c_)) log("GPIO lines not sampled (no --gpio-dir, or its values cannot be read)");
  if (!board_.start(c_)) return log("cannot start %s", c_.board_argv[0].c_str()), 1;
  std::string port = c_.port == "auto" ? find_virtio_port("gabarit.hil") : c_.port;
  if (port.empty() || !harness_.open(port)) return log("no virtio-serial port named gabarit.hil"), 1;
  if (!wait_usb_open(20000)) return log("the board's USB gadget did not appear in 20 s: %s", usb_.error().c_str()), 1;
  link::DeviceDescription device;
  device.clock_hz = 1000000;
  device.frame_slots = 1;  // one frame on the camera at a time
  device.max_frame_bytes = c_.width * c_.height;
  device.device_id = crc32(std::as_bytes(std::span(usb_.serial().data(), usb_.serial().size())));
  device.kind = c_.kind.c_str();
  device.board = c_.board_name.c_str();
  device.software = "gabarit-board";
  if (!c_.table.empty()) {
    std::vector<std::byte> bytes;
    try {
      bytes = app::read_file(c_.table);
    } catch (const app::Error& e) {
      return log("cannot read the table: %s", e.what()), 1;
    }
    device.table_crc = crc32(bytes);
    device.table_bytes = static_cast<std::uint32_t>(bytes.size());
  }
  const link::Caps caps = link::make_caps(device);
  frame_memory_.assign(link::dut_frame_memory_bytes(1, caps.max_frame_bytes), 0);
  endpoint_.emplace(caps, frame_memory_);
  log("ready: harness on %s, board's gadget %04x:%04x serial %s", port.c_str(), c_.usb.vendor_id, c_.usb.product_id,
      usb_.serial().c_str());
  for (;;) {
    pollfd p{harness_.fd(), POLLIN, 0};
    if (::poll(&p, 1, 0) > 0) harness_.read_available([&](std::span<const std::byte> m) { on_harness_message(m); }, *endpoint_);
    if (endpoint_->bye_received()) break;
    take_frames();
    pump_usb(2);
    keep_board_alive();
    reshow_current();
    check_wraps();
    if (now_us() - last_rss_ > 1000000u) {  // STATS.resident_kib: the board program's memory, for soaks
      last_rss_ = now_us();
      endpoint_->set_resident_kib(board_.resident_kib());
    }
    if (current_ && now_us() > current_->deadline) {
      current_.reset();
      endpoint_->report_failure(link::EventKind::kError, link::EventReason::kCameraTimeout, 0, now_us());
      flush();
    }
  }
  // After BYE the harness sends its verdicts for the board's console (a
  // board farm reads them there): read on until it hangs up or is quiet.
  const std::uint64_t drain_end = now_us() + 10000000u;
  for (std::uint64_t quiet_since = now_us(); now_us() < drain_end && now_us() - quiet_since < 2000000u;) {
    pollfd p{harness_.fd(), POLLIN, 0};
    if (::poll(&p, 1, 100) <= 0) continue;
    if ((p.revents & POLLHUP) != 0 && (p.revents & POLLIN) == 0) break;
    harness_.read_available([&](std::span<const std::byte> m) { on_harness_message(m); }, *endpoint_);
    quiet_since = now_us();
  }
  log("run over: %llu camera errors, %llu gaps, %llu losses, %llu reopens, %llu wraps seen by the board; %llu board restarts; "
      "%llu resent messages dropped, %llu out of sequence, %llu stale poses, %llu strobes not seen (%llu samples); USB: %llu timeouts, %llu halts "
      "cleared, %llu reopens, %llu zero-length packets out",
      static_cast<unsigned long long>(camera_errors_), static_cast<unsigned long long>(camera_gaps_),
      static_cast<unsigned long long>(camera_lost_), static_cast<unsigned long long>(camera_back_),
      static_cast<unsigned long long>(wraps_), static_cast<unsigned long long>(board_restarts_),
      static_cast<unsigned long long>(board_duplicates_), static_cast<unsigned long long>(board_out_of_sequence_),
      static_cast<unsigned long long>(stale_poses_),
      static_cast<unsigned long long>(strobes_missed_), static_cast<unsigned long long>(lines_.samples()),
      static_cast<unsigned long long>(usb_.stats().timeouts), static_cast<unsigned long long>(usb_.stats().halts_cleared),
      static_cast<unsigned long long>(usb_.stats().opens), static_cast<unsigned long long>(usb_.stats().zero_length_out));
  // The board stops with its lines low.
  expecting_kill_ = true;
  board_.kill_now(SIGTERM);
  lines_.stop();
  return 0;
}

}  // namespace gabarit::relay

int main(int argc, char** argv) {
  using namespace gabarit;
  using namespace gabarit::relay;
  ::signal(SIGPIPE, SIG_IGN);
  Config c;
  int i = 1;
  const auto value = [&](const char* name) -> std::string {
    if (i + 1 >= argc) {
      std::fprintf(stderr, "gabarit-hil-relay: %s needs a value\n", name);
      std::exit(2);
    }
    return argv[++i];
  };
  for (; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--") {
      ++i;
      break;
    }
    if (a == "--help") {
      std::puts("usage: gabarit-hil-relay [--port DEV] [--capture DEV] [--output DEV] [--camera-link PATH] [--size WxH]\n"
                "         [--vivid-module KO] [--gadget DIR] [--usb VID:PID[:SERIAL]] [--gpio-dir DIR] [--lock-line N]\n"
                "         [--strobe-line N] [--board-log FILE] [--table T]\n"
                "         [--kind TEXT] [--name TEXT] -- BOARD_PROGRAM [ARGS...]\n"
                "The virtual board's HIL rig (platform/linux/virtual-board/README.md).");
      return 0;
    }
    if (a == "--port") c.port = value("--port");
    else if (a == "--capture") c.capture = value("--capture");
    else if (a == "--output") c.output = value("--output");
    else if (a == "--camera-link") c.camera_link = value("--camera-link");
    else if (a == "--vivid-module") c.vivid_module = value("--vivid-module");
    else if (a == "--gadget") c.gadget_dir = value("--gadget");
    else if (a == "--gpio-dir") c.gpio_dir = value("--gpio-dir");
    else if (a == "--lock-line") c.lock_line = std::atoi(value("--lock-line").c_str());
    else if (a == "--strobe-line") c.strobe_line = std::atoi(value("--strobe-line").c_str());
    else if (a == "--board-log") c.board_log = value("--board-log");
    else if (a == "--table") c.table = value("--table");
    else if (a == "--kind") c.kind = value("--kind");
    else if (a == "--name") c.board_name = value("--name");
    else if (a == "--size") {
      const std::string s = value("--size");
      if (std::sscanf(s.c_str(), "%ux%u", &c.width, &c.height) != 2) return std::fprintf(stderr, "gabarit-hil-relay: --size WxH\n"), 2;
    } else if (a == "--usb") {
      std::string error;
      if (!link::parse_usb_identity(value("--usb"), c.usb, error)) return std::fprintf(stderr, "gabarit-hil-relay: --usb %s\n", error.c_str()), 2;
    } else {
      std::fprintf(stderr, "gabarit-hil-relay: unknown option %s (see --help)\n", a.c_str());
      return 2;
    }
  }
  for (; i < argc; ++i) c.board_argv.emplace_back(argv[i]);
  if (c.board_argv.empty()) return std::fprintf(stderr, "gabarit-hil-relay: no board program after --\n"), 2;
  Relay relay(std::move(c));
  return relay.run();
}
