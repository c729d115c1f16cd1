// gabarit-board — the tracker as it runs on an ARM Linux board: frames from a
// V4L2 capture device, the table mapped from a file and validated once, one
// pose line per frame on stdout (and optionally as UDP datagrams, and as the
// HIL link's POSE messages over a USB gadget: --link usb), a lock and a strobe
// GPIO output and an optional trigger input. It survives the camera going
// away (reported, then reopened with back-off) and the USB cable going away
// (nothing unacknowledged is lost), and shuts down cleanly on SIGINT/SIGTERM
// with the GPIO outputs low.
#include <poll.h>
#include <signal.h>
#include <sys/signalfd.h>
#include <sys/utsname.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "frame_counter.hpp"
#include "gabarit/app/args.hpp"
#include "gabarit/app/files.hpp"
#include "gabarit/app/pose_row.hpp"
#include "gabarit/app/hosted_session.hpp"
#include "gabarit/app/scratch.hpp"
#include "gabarit/app/session_profile_io.hpp"
#include "gabarit/crc32.hpp"
#include "gabarit/link/session_report.hpp"
#include "board_link.hpp"
#include "gabarit/tracking_session.hpp"
#include "gpio_lines.hpp"
#include "luma.hpp"
#include "udp_sender.hpp"
#include "v4l2_capture.hpp"

namespace {

using namespace gabarit;
using board::CaptureEvent;

constexpr const char* kPoseHeader = "frame,x,y,theta_deg,depth,votes,score,status,sequence,timestamp_us";

struct Config {
  board::CaptureOptions capture;
  board::GpioOptions gpio;
  std::string table_path;
  std::string init_text;
  std::string udp;
  bool binary = false;
  bool start_stopped = false;
  app::VoterChoice voter = app::VoterChoice::kAuto;
  std::uint64_t max_frames = 0;        // 0: until stopped
  int frame_timeout_ms = 2000;         // report a stall after this long without a frame
  int reopen_min_ms = 250;             // first wait after losing the device (lets an unplug settle)
  int reopen_max_ms = 2000;            // back-off ceiling between reopen attempts
  bool frame_crc = false;
  bool quiet = false;
  bool usb = false;                    // --link usb
  board::UsbGadgetOptions usb_gadget;
  std::uint32_t window_width = 0, window_height = 0;  // 0: the whole frame
  bool skip_repeats = false;
  app::SessionProfile profile;  // the session's defaults, as gabarit track
};

std::uint32_t parse_format(const std::string& text) {
  if (text == "auto") return 0;
  if (text == "GREY") return board::kFourccGrey;
  if (text == "YUYV") return board::kFourccYuyv;
  if (text == "NV12") return board::kFourccNv12;
  throw app::UsageError("--format '" + text + "': want auto, GREY, YUYV or NV12");
}

Config parse(int argc, char** argv, bool& help_shown) {
  app::Args args(
      "gabarit-board", "--device /dev/videoN --table T --init X,Y[,THETA[,DEPTH]] [options]",
      "Tracks the table's model in frames from a V4L2 capture device. Writes one line per tracked frame to\n"
      "stdout: frame,x,y,theta_deg,depth,votes,score,status (as `gabarit track`), then the driver's frame\n"
      "sequence number and timestamp. Progress and problems go to stderr. The camera going away is reported\n"
      "and the device reopened with back-off. SIGINT/SIGTERM end the run; GPIO outputs are left low.",
      {{"--device", "PATH", "V4L2 capture device (default /dev/video0)"},
       {"--table", "T", "table file (gabarit tables build)", false, true},
       {"--init", "X,Y[,THETA[,DEPTH]]", "pose before the first frame (with --link usb: the host's HELLO gives it)"},
       {"--link", "usb", "also speak the HIL link (docs/hil-protocol.md) over a USB FunctionFS gadget: poses and\n"
        "                          events out; start (HELLO, with the table's CRC), stop, stats in. Tracks only\n"
        "                          during a run the host started"},
       {"--usb-ffs", "DIR", "with --link usb: the mounted FunctionFS instance (default /dev/usb-ffs/gabarit)"},
       {"--usb-gadget", "DIR", "with --link usb: the gadget's configfs folder, bound to the UDC once the descriptors\n"
        "                          are written (platform/linux/usb-gadget.sh makes it; default: bound by someone else)"},
       {"--usb-udc", "NAME", "with --usb-gadget: the USB device controller (default: the first in /sys/class/udc)"},
       {"--window", "WxH", "track the top-left WxH pixels of each frame (a sensor window; default the whole frame)"},
       {"--skip-repeats", "", "do not track a frame identical to the one captured before it or to the last one\n"
        "                          tracked (a camera that shows a frame several times, as a replay through vivid does;\n"
        "                          the picture on the camera when a run starts is not new either)"},
       {"--format", "auto|GREY|YUYV|NV12", "pixel format to request (default auto: the first of these offered)"},
       {"--size", "WxH", "frame size to request (default: the device's current size)"},
       {"--binary", "", "binary detector on frames whatever the table says"},
       {"--voter", "auto|csr|dense", "voting method; results are identical (default auto)"},
       {"--frames", "N", "stop after N tracked frames (default: run until signalled)"},
       {"--frame-timeout-ms", "MS", "report a stall after MS without a frame (default 2000)"},
       {"--reopen-min-ms", "MS", "wait after losing the device before reopening it; doubles per failed attempt (default 250)"},
       {"--reopen-max-ms", "MS", "longest wait between attempts to reopen a lost device (default 2000)"},
       {"--udp", "HOST:PORT", "also send each pose line as a UDP datagram"},
       {"--gpio-chip", "CHIP", "GPIO chip for the lines below (gpiochipN, /dev/gpiochipN or a label)"},
       {"--lock-line", "N", "output: high while tracking is confident"},
       {"--strobe-line", "N", "output: one pulse per tracked frame"},
       {"--strobe-us", "US", "strobe pulse width in microseconds (default 100)"},
       {"--trigger-line", "N", "input: each rising edge starts or stops tracking"},
       {"--start-stopped", "", "with --trigger-line: wait for the first edge before tracking"},
       {"--frame-crc", "", "append the CRC-32 of each tracked frame's luma (width x height bytes, row by row):\n"
        "                          which frame was tracked, for tests that replay a recording through a camera"},
       {"--quiet", "", "no progress lines on stderr"}});
  for (app::Option& o : app::session_option_group()) args.add(std::move(o));  // as gabarit track
  std::vector<std::string> list(argv + 1, argv + argc);
  help_shown = !args.parse(list);
  Config c;
  if (help_shown) return c;
  c.capture.device = args.get_or("--device", c.capture.device);
  c.capture.pixel_format = parse_format(args.get_or("--format", "auto"));
  if (args.has("--size")) {
    const app::FrameSize size = app::parse_size(args.get("--size"), "--size", 8, 8192);
    c.capture.width = size.width;
    c.capture.height = size.height;
  }
  c.table_path = args.get("--table");
  if (args.has("--link")) {
    if (args.get("--link") != "usb") throw app::UsageError("--link '" + args.get("--link") + "': want usb");
    c.usb = true;
  }
  c.init_text = args.get_or("--init", "");
  if (c.init_text.empty() && !c.usb) throw app::UsageError("--init is required (or --link usb, whose host gives the pose)");
  for (const char* o : {"--usb-ffs", "--usb-gadget", "--usb-udc"})
    if (args.has(o) && !c.usb) throw app::UsageError(std::string(o) + " needs --link usb");
  c.usb_gadget.ffs_dir = args.get_or("--usb-ffs", "/dev/usb-ffs/gabarit");
  c.usb_gadget.gadget_dir = args.get_or("--usb-gadget", "");
  c.usb_gadget.udc = args.get_or("--usb-udc", "auto");
  if (args.has("--usb-udc") && c.usb_gadget.gadget_dir.empty()) throw app::UsageError("--usb-udc needs --usb-gadget");
  c.usb_gadget.max_message = link::message_bytes(link::kMinPayload);
  if (args.has("--window")) {
    const app::FrameSize w = app::parse_size(args.get("--window"), "--window", 8, 8192);
    c.window_width = w.width;
    c.window_height = w.height;
  }
  c.skip_repeats = args.has("--skip-repeats");
  c.binary = args.has("--binary");
  c.voter = app::parse_voter(args.get_or("--voter", "auto"), "--voter");
  c.max_frames = static_cast<std::uint64_t>(args.integer("--frames", 0, 0, INT64_MAX));
  c.frame_timeout_ms = static_cast<int>(args.integer("--frame-timeout-ms", 2000, 10, 3600000));
  c.reopen_min_ms = static_cast<int>(args.integer("--reopen-min-ms", 250, 1, 600000));
  c.reopen_max_ms = static_cast<int>(args.integer("--reopen-max-ms", 2000, 1, 600000));
  if (c.reopen_max_ms < c.reopen_min_ms) throw app::UsageError("--reopen-max-ms is smaller than --reopen-min-ms");
  c.udp = args.get_or("--udp", "");
  c.gpio.chip = args.get_or("--gpio-chip", "");
  c.gpio.lock_line = static_cast<int>(args.integer("--lock-line", -1, 0, 65535));
  c.gpio.strobe_line = static_cast<int>(args.integer("--strobe-line", -1, 0, 65535));
  c.gpio.trigger_line = static_cast<int>(args.integer("--trigger-line", -1, 0, 65535));
  c.gpio.strobe_us = static_cast<std::uint32_t>(args.integer("--strobe-us", 100, 1, 1000000));
  const bool any_line = c.gpio.lock_line >= 0 || c.gpio.strobe_line >= 0 || c.gpio.trigger_line >= 0;
  if (any_line && c.gpio.chip.empty()) throw app::UsageError("--lock-line/--strobe-line/--trigger-line need --gpio-chip");
  if (!c.gpio.chip.empty() && !any_line) throw app::UsageError("--gpio-chip given without any line");
  c.start_stopped = args.has("--start-stopped");
  if (c.start_stopped && c.gpio.trigger_line < 0) throw app::UsageError("--start-stopped needs --trigger-line");
  c.frame_crc = args.has("--frame-crc");
  c.profile = app::read_session_profile(args);
  if (args.has("--save-profile")) app::write_file(args.get("--save-profile"), app::format_profile(c.profile));
  c.quiet = args.has("--quiet");
  return c;
}

std::uint32_t luma_crc32(const ImageView& image) {
  std::uint32_t crc = 0;
  for (std::uint32_t y = 0; y < image.height; ++y)
    crc = crc32_update(crc, {reinterpret_cast<const std::byte*>(image.pixels + std::size_t{y} * image.stride), image.width});
  return crc;
}

std::uint64_t monotonic_us() {
  timespec t{};
  ::clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<std::uint64_t>(t.tv_sec) * 1000000u + static_cast<std::uint64_t>(t.tv_nsec) / 1000u;
}

// What the board adds to its profile: the voter and the detector it was told.
app::SessionExtras extras(const Config& c) {
  app::SessionExtras e;
  e.voter = c.voter;
  if (c.binary) e.detector = Detector{table_format::DetectorKind::kBinary, 0};
  return e;
}

class Board : private board::BoardLink::Handler {
 public:
  Board(const Config& c, const TableView& table, std::uint32_t table_crc, std::uint32_t table_bytes, int signal_fd)
      : c_(c),
        table_crc_(table_crc),
        table_bytes_(table_bytes),
        signal_fd_(signal_fd),
        session_(table, c.profile, extras(c)),
        running_(!c.start_stopped) {
    if (!c.init_text.empty() && !session_.start(app::parse_init_pose(c.init_text, table, "--init")))
      throw app::UsageError("--init: not a usable starting pose");
  }

  int run() {
    if (!gpio_.open(c_.gpio, "gabarit-board")) return fail("GPIO: " + gpio_.error());
    if (!c_.udp.empty() && !udp_.open(c_.udp)) return fail(udp_.error());
    if (c_.usb) {
      if (!gadget_.open(c_.usb_gadget)) return fail("USB: " + gadget_.error());
      progress("USB link: FunctionFS at %s%s", c_.usb_gadget.ffs_dir.c_str(), c_.usb_gadget.gadget_dir.empty() ? "" : ", gadget bound");
    }
    std::printf("%s%s\n", kPoseHeader, c_.frame_crc ? ",luma_crc32" : "");
    bool reported_open_failure = false;
    while (!stop_) {
      if (!capture_.is_open()) {
        if (capture_.open(c_.capture)) {
          const auto& l = capture_.layout();
          progress("capturing %ux%u %s from %s", l.width, l.height, board::fourcc_text(l.pixel_format).text, c_.capture.device.c_str());
          if (c_.window_width > l.width || c_.window_height > l.height)
            return fail("--window " + std::to_string(c_.window_width) + "x" + std::to_string(c_.window_height) +
                        " is larger than the camera's frames");
          if (losses_ > 0) camera_event(link::EventKind::kRestart, link::EventReason::kCameraBack, static_cast<std::uint32_t>(losses_));
          counter_.restart();
          luma_.assign(board::luma_scratch_bytes(l), 0);
          backoff_ms_ = c_.reopen_min_ms;
          reported_open_failure = false;
        } else {
          if (!reported_open_failure) std::fprintf(stderr, "gabarit-board: %s; retrying\n", capture_.error().c_str());
          reported_open_failure = true;
          wait_for_signal(backoff_ms_);
          backoff_ms_ = std::min(backoff_ms_ * 2, c_.reopen_max_ms);
          continue;
        }
      }
      pollfd fds[4] = {{capture_.fd(), POLLIN, 0}, {signal_fd_, POLLIN, 0}, {gadget_.event_fd(), POLLIN, 0},
                       {gpio_.trigger_fd(), POLLIN, 0}};
      const int n = ::poll(fds, 4, c_.frame_timeout_ms);
      if (n < 0 && errno != EINTR) return fail(std::string("poll: ") + std::strerror(errno));
      if (n == 0) {
        ++stalls_;
        progress("no frame for %d ms", c_.frame_timeout_ms);
        continue;
      }
      if (fds[1].revents != 0) {
        signalfd_siginfo info{};
        if (::read(signal_fd_, &info, sizeof info) == static_cast<ssize_t>(sizeof info))
          progress("signal %u: stopping", info.ssi_signo);
        stop_ = true;
        break;
      }
      if (fds[2].revents != 0) link_.service(*this);
      if (c_.usb) link_.tick(monotonic_us());
      if (fds[3].revents != 0) on_trigger();
      if ((fds[0].revents & (POLLERR | POLLHUP | POLLNVAL)) != 0) {
        device_lost("the device reported an error (unplugged?)");
        continue;
      }
      if ((fds[0].revents & POLLIN) != 0) drain_frames();
    }
    if (!gpio_.set_lock(false)) std::fprintf(stderr, "gabarit-board: %s\n", gpio_.error().c_str());
    gpio_.release();
    capture_.close();
    gadget_.close();
    std::fflush(stdout);
    std::fprintf(stderr,
                 "gabarit-board: %llu frames tracked, %llu delivered, %llu dropped by the driver, %llu flagged bad, "
                 "%llu unusable, %llu repeats skipped, %llu device losses, %llu stalls, %llu UDP sends failed\n",
                 ull(tracked_), ull(counter_total_delivered()), ull(dropped_), ull(error_frames_), ull(bad_frames_),
                 ull(repeats_), ull(losses_), ull(stalls_), ull(udp_.failed()));
    if (c_.usb) {
      const board::UsbGadgetStats u = gadget_.stats();
      std::fprintf(stderr,
                   "gabarit-board: USB: %llu messages out, %llu in, %llu host connects, %llu disconnects, %llu resent, "
                   "%llu lost to write errors before a resend, %llu bad CRC in\n",
                   ull(u.messages_out), ull(u.messages_in), ull(u.enables), ull(u.disables), ull(link_.resent()),
                   ull(u.write_errors), ull(link_.link_stats().bad_crc));
    }
    return 0;
  }

 private:
  static unsigned long long ull(std::uint64_t v) { return static_cast<unsigned long long>(v); }
  std::uint64_t counter_total_delivered() const { return delivered_; }

  template <class... A>
  void progress(const char* format, A... a) {
    if (c_.quiet) return;
    std::fprintf(stderr, "gabarit-board: ");
    std::fprintf(stderr, format, a...);
    std::fputc('\n', stderr);
  }

  int fail(const std::string& message) {
    std::fprintf(stderr, "gabarit-board: error: %s\n", message.c_str());
    gpio_.release();
    return 1;
  }

  // Waits `ms` for a signal (then stops), serving the USB link meanwhile.
  void wait_for_signal(int ms) {
    const std::uint64_t end = monotonic_us() + static_cast<std::uint64_t>(ms) * 1000u;
    for (std::uint64_t now = monotonic_us(); now < end && !stop_; now = monotonic_us()) {
      pollfd p[2] = {{signal_fd_, POLLIN, 0}, {gadget_.event_fd(), POLLIN, 0}};
      if (::poll(p, 2, static_cast<int>((end - now + 999) / 1000)) <= 0) continue;
      if (p[1].revents != 0) link_.service(*this);
      if (c_.usb) link_.tick(monotonic_us());
      if (p[0].revents != 0) {
        signalfd_siginfo info{};
        if (::read(signal_fd_, &info, sizeof info) == static_cast<ssize_t>(sizeof info)) progress("signal %u: stopping", info.ssi_signo);
        stop_ = true;
      }
    }
  }

  void camera_event(link::EventKind kind, link::EventReason reason, std::uint32_t detail) {
    if (!c_.usb) return;
    link::Event e;
    e.kind = kind;
    e.reason = reason;
    e.detail = detail;
    e.time = monotonic_us();
    link_.send_event(e);
  }

  // ---- BoardLink::Handler: the host's requests over USB.
  link::Refusal start(const link::Hello& hello, link::Caps& caps) override {
    link::DeviceDescription device;
    device.max_payload = static_cast<std::uint16_t>(link::kMinPayload);
    device.table_crc = table_crc_;
    device.table_bytes = table_bytes_;
    device.clock_hz = 1000000;  // CLOCK_MONOTONIC in microseconds, as V4L2's timestamps
    device.max_frame_bytes = 0;  // frames come from the camera, not the link
    device.mode = session_.mode();
    device.device_id = device_id();
    device.kind = "linux-board";
    const std::string name = board_name();
    device.board = name.c_str();
    device.software = "gabarit-board";
    caps = link::make_caps(device);
    if (hello.version != link::kVersion) return link::Refusal::kProtocolVersion;
    if (hello.table_crc != 0 && hello.table_crc != table_crc_) return link::Refusal::kTableMismatch;
    if (!session_.start(hello.initial)) return link::Refusal::kBadPose;
    have_last_crc_ = false;
    progress("run %u started by the host at %.2f,%.2f", hello.run_id, static_cast<double>(hello.initial.x),
             static_cast<double>(hello.initial.y));
    return link::Refusal::kNone;
  }
  void stop() override {
    progress("run %u stopped by the host", link_.run_id());
    if (!gpio_.set_lock(false)) std::fprintf(stderr, "gabarit-board: %s\n", gpio_.error().c_str());
  }
  link::Stats counters() override {
    link::Stats s;
    s.frames_taken = static_cast<std::uint32_t>(delivered_);
    s.frames_tracked = static_cast<std::uint32_t>(tracked_);
    s.frames_dropped = static_cast<std::uint32_t>(dropped_);
    s.frames_skipped = static_cast<std::uint32_t>(error_frames_ + bad_frames_);
    return s;
  }
  std::uint64_t now_us() override { return monotonic_us(); }

  static std::string board_name() {
    // The device tree's model on a real board; the machine otherwise.
    if (std::FILE* f = std::fopen("/proc/device-tree/model", "r")) {
      char text[64] = {};
      const std::size_t n = std::fread(text, 1, sizeof text - 1, f);
      std::fclose(f);
      if (n > 0) return std::string(text, ::strnlen(text, n));
    }
    utsname u{};
    return ::uname(&u) == 0 ? std::string("Linux ") + u.machine : std::string("Linux");
  }
  static std::uint64_t device_id() {
    // Stable per board: the machine id where there is one.
    std::uint64_t id = 0;
    if (std::FILE* f = std::fopen("/etc/machine-id", "r")) {
      char text[40] = {};
      const std::size_t n = std::fread(text, 1, 32, f);
      std::fclose(f);
      id = crc32({reinterpret_cast<const std::byte*>(text), n});
    }
    return id;
  }

  void device_lost(const std::string& why) {
    ++losses_;
    camera_event(link::EventKind::kError, link::EventReason::kCameraLost, static_cast<std::uint32_t>(losses_));
    std::fprintf(stderr, "gabarit-board: lost %s: %s; reopening\n", c_.capture.device.c_str(), why.c_str());
    capture_.close();
    if (!gpio_.set_lock(false)) std::fprintf(stderr, "gabarit-board: %s\n", gpio_.error().c_str());
    wait_for_signal(backoff_ms_);  // a camera going away often takes a moment to be gone for good
  }

  void on_trigger() {
    const int edges = gpio_.read_trigger_rising_edges();
    if (edges < 0) {
      std::fprintf(stderr, "gabarit-board: %s\n", gpio_.error().c_str());
      return;
    }
    if (edges % 2 == 1) {
      running_ = !running_;
      progress("trigger: tracking %s", running_ ? "started" : "stopped");
      if (!running_ && !gpio_.set_lock(false)) std::fprintf(stderr, "gabarit-board: %s\n", gpio_.error().c_str());
    }
  }

  void drain_frames() {
    for (;;) {
      board::CapturedFrame frame;
      switch (capture_.dequeue(frame)) {
        case CaptureEvent::kNoFrame: return;
        case CaptureEvent::kErrorFrame:
          ++error_frames_;
          camera_event(link::EventKind::kError, link::EventReason::kCameraError, frame.sequence);
          count_delivered(frame.sequence);  // keeps the sequence: a flagged frame is not a dropped one
          continue;  // the capture gave its buffer back to the driver
        case CaptureEvent::kDeviceLost: device_lost(capture_.error()); return;
        case CaptureEvent::kFrame: break;
      }
      ++delivered_;
      count_delivered(frame.sequence);
      if (running_ && session_.started() && (!c_.usb || link_.running())) process(frame);
      else if (c_.skip_repeats) note_captured(frame);  // a frame shown before the run: not new when it starts
      if (!capture_.requeue(frame.index)) {
        device_lost(capture_.error());
        return;
      }
      if (c_.max_frames != 0 && tracked_ >= c_.max_frames) {
        stop_ = true;
        return;
      }
    }
  }

  void count_delivered(std::uint32_t sequence) {
    const bool backwards = counter_started_ && sequence < last_sequence_;
    const std::uint32_t gap = counter_.delivered(sequence);
    counter_started_ = true;
    last_sequence_ = sequence;
    dropped_ += gap;
    if (gap > 0) camera_event(link::EventKind::kDropped, link::EventReason::kCameraGap, gap);
    if (backwards) camera_event(link::EventKind::kRestart, link::EventReason::kSequenceWrap, sequence);
  }

  // The frame's luma (its window), false if the buffer is unusable.
  bool frame_luma(const board::CapturedFrame& frame, ImageView& image) {
    if (const auto s = board::luma_view(capture_.layout(), frame.data, frame.bytes_used, luma_, image); s != board::LumaStatus::kOk) {
      ++bad_frames_;
      progress("frame %u skipped: %s", frame.sequence, board::luma_status_name(s));
      return false;
    }
    if (c_.window_width != 0) {  // checked against the frame size when the device opened
      image.width = c_.window_width;
      image.height = c_.window_height;
    }
    return true;
  }

  // --skip-repeats: a frame identical to the one captured before it, or to
  // the last one tracked, is the same picture again (true: skip it).
  bool repeat_of_known(std::uint32_t crc) {
    const bool repeat = (have_captured_crc_ && crc == last_captured_crc_) || (have_last_crc_ && crc == last_crc_);
    last_captured_crc_ = crc;
    have_captured_crc_ = true;
    return repeat;
  }
  void note_captured(const board::CapturedFrame& frame) {
    ImageView image;
    if (frame_luma(frame, image)) (void)repeat_of_known(link::frame_crc(image));
  }

  void process(const board::CapturedFrame& frame) {
    const std::uint64_t dequeued_us = monotonic_us();
    ImageView image;
    if (!frame_luma(frame, image)) return;
    const std::uint32_t crc32c_of_frame = c_.usb || c_.skip_repeats ? link::frame_crc(image) : 0;
    if (c_.skip_repeats && repeat_of_known(crc32c_of_frame)) {
      ++repeats_;
      return;
    }
    app::TrackRow row;
    row.frame = static_cast<std::uint32_t>(tracked_);
    SessionResult result;
    if (const Status s = session_.step(image, result); s != Status::kOk) {
      ++bad_frames_;
      progress("frame %u not tracked: %s", frame.sequence, status_name(s));
      return;
    }
    app::fill_row(row, result);  // the same row as gabarit track writes
    ++tracked_;
    last_crc_ = crc32c_of_frame;
    have_last_crc_ = true;
    bool ok = gpio_.set_lock(row.step.state == TrackState::kTracking);
    if (c_.usb) {
      link::PoseReport report = link::session_report(result);
      report.frame_crc = crc32c_of_frame;
      // V4L2's timestamp is CLOCK_MONOTONIC (vivid, UVC, most drivers): the
      // capture stage on the same clock as the pose. Some drivers stamp the
      // frame's nominal end (vivid), later than it reached us: never later
      // than the dequeue.
      report.received = report.captured = std::min(frame.timestamp_us, dequeued_us);
      report.done = monotonic_us();
      link_.send_pose(report);
    }
    char tail[64];
    int n = std::snprintf(tail, sizeof tail, ",%u,%llu", frame.sequence, ull(frame.timestamp_us));
    if (c_.frame_crc) std::snprintf(tail + n, sizeof tail - static_cast<std::size_t>(n), ",%08x", luma_crc32(image));
    const std::string line = app::pose_csv_row(row) + tail;
    std::printf("%s\n", line.c_str());
    udp_.send(line);
    ok = gpio_.pulse_strobe() && ok;
    if (!ok) std::fprintf(stderr, "gabarit-board: %s\n", gpio_.error().c_str());
  }

  const Config& c_;
  std::uint32_t table_crc_, table_bytes_;
  int signal_fd_;
  app::HostedSession session_;
  board::V4l2Capture capture_;
  board::GpioLines gpio_;
  board::UdpSender udp_;
  board::FrameCounter counter_;
  board::UsbGadget gadget_;
  board::BoardLink link_{gadget_};
  bool counter_started_ = false;
  std::uint32_t last_sequence_ = 0;
  std::uint32_t last_crc_ = 0;  // the last frame tracked
  bool have_last_crc_ = false;
  std::uint32_t last_captured_crc_ = 0;  // the last frame captured (with --skip-repeats)
  bool have_captured_crc_ = false;
  std::uint64_t repeats_ = 0;
  std::vector<std::uint8_t> luma_;
  bool running_;
  bool stop_ = false;
  int backoff_ms_ = 0;  // wait before the next reopen attempt
  std::uint64_t tracked_ = 0, delivered_ = 0, dropped_ = 0, error_frames_ = 0, bad_frames_ = 0, losses_ = 0, stalls_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  // Signals arrive through a descriptor the loop polls, never in the middle
  // of a V4L2 or GPIO call.
  sigset_t mask;
  sigemptyset(&mask);
  sigaddset(&mask, SIGINT);
  sigaddset(&mask, SIGTERM);
  sigaddset(&mask, SIGHUP);
  if (sigprocmask(SIG_BLOCK, &mask, nullptr) < 0) return 1;
  ::signal(SIGPIPE, SIG_IGN);  // a closed stdout ends the run through write errors, not a signal
  const int signal_fd = ::signalfd(-1, &mask, SFD_CLOEXEC | SFD_NONBLOCK);
  if (signal_fd < 0) {
    std::perror("gabarit-board: signalfd");
    return 1;
  }
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // a pose line leaves as soon as it is complete
  try {
    bool help = false;
    const Config config = parse(argc, argv, help);
    if (help) return 0;
    const app::TableFile table(config.table_path);
    Board board(config, table.view(), crc32(table.bytes()), static_cast<std::uint32_t>(table.bytes().size()), signal_fd);
    return board.run();
  } catch (const app::UsageError& e) {
    std::fprintf(stderr, "gabarit-board: %s\n(see gabarit-board --help)\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gabarit-board: error: %s\n", e.what());
    return 1;
  }
}
