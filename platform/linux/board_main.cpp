// gabarit-board — the tracker as it runs on an ARM Linux board: frames from a
// V4L2 capture device, the table mapped from a file and validated once, one
// pose line per frame on stdout (and optionally as UDP datagrams), a lock and
// a strobe GPIO output and an optional trigger input. It survives the camera
// going away (reported, then reopened with back-off) and shuts down cleanly
// on SIGINT/SIGTERM with the GPIO outputs low.
#include <poll.h>
#include <signal.h>
#include <sys/signalfd.h>
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
#include "gabarit/app/scratch.hpp"
#include "gabarit/crc32.hpp"
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
  SessionOptions session;  // the robust session by default, as gabarit track
  bool focus_stack = true;  // the table's model images, when it carries them
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
       {"--init", "X,Y[,THETA[,DEPTH]]", "pose before the first frame", false, true},
       {"--format", "auto|GREY|YUYV|NV12", "pixel format to request (default auto: the first of these offered)"},
       {"--size", "WxH", "frame size to request (default: the device's current size)"},
       {"--binary", "", "binary detector on frames whatever the table says"},
       {"--voter", "auto|csr|dense", "voting method; results are identical (default auto)"},
       {"--plain", "", "the thesis's loop instead of the tracking session (as gabarit track --plain)"},
       {"--motion-filter", "", "with --plain: the motion filter (default on, as gabarit track)"},
       {"--refine", "", "with --plain: sub-cell x, y, theta (default on)"},
       {"--recover", "", "with --plain: once lost, search around the last confident pose (default on)"},
       {"--no-focus-stack", "", "ignore the table's model images (depth from the stencils only)"},
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
  c.init_text = args.get("--init");
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
  c.session = app::session_options(args.has("--plain"), args.has("--motion-filter"), args.has("--refine"), args.has("--recover"));
  c.focus_stack = !args.has("--plain") && !args.has("--no-focus-stack");
  c.quiet = args.has("--quiet");
  return c;
}

std::uint32_t luma_crc32(const ImageView& image) {
  std::uint32_t crc = 0;
  for (std::uint32_t y = 0; y < image.height; ++y)
    crc = crc32_update(crc, {reinterpret_cast<const std::byte*>(image.pixels + std::size_t{y} * image.stride), image.width});
  return crc;
}

class Board {
 public:
  Board(const Config& c, const TableView& table, int signal_fd)
      : c_(c),
        signal_fd_(signal_fd),
        // As gabarit track: the recovery search detects features once per search.
        buffers_(table, nullptr, c.voter, c.session.recover),
        session_(table, nullptr, c.binary ? Detector{table_format::DetectorKind::kBinary, 0} : detector_of(table)),
        stack_(table),
        running_(!c.start_stopped) {
    if (session_.start(c.session, app::parse_init_pose(c.init_text, table, "--init")) != Status::kOk)
      throw app::UsageError("--init: not a usable starting pose");
    if (c.focus_stack) session_.use_focus_stack(stack_.get());
  }

  int run() {
    if (!gpio_.open(c_.gpio, "gabarit-board")) return fail("GPIO: " + gpio_.error());
    if (!c_.udp.empty() && !udp_.open(c_.udp)) return fail(udp_.error());
    std::printf("%s%s\n", kPoseHeader, c_.frame_crc ? ",luma_crc32" : "");
    bool reported_open_failure = false;
    while (!stop_) {
      if (!capture_.is_open()) {
        if (capture_.open(c_.capture)) {
          const auto& l = capture_.layout();
          progress("capturing %ux%u %s from %s", l.width, l.height, board::fourcc_text(l.pixel_format).text, c_.capture.device.c_str());
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
      pollfd fds[3] = {{capture_.fd(), POLLIN, 0}, {signal_fd_, POLLIN, 0}, {gpio_.trigger_fd(), POLLIN, 0}};
      const int n = ::poll(fds, gpio_.trigger_fd() >= 0 ? 3 : 2, c_.frame_timeout_ms);
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
      if (fds[2].revents != 0) on_trigger();
      if ((fds[0].revents & (POLLERR | POLLHUP | POLLNVAL)) != 0) {
        device_lost("the device reported an error (unplugged?)");
        continue;
      }
      if ((fds[0].revents & POLLIN) != 0) drain_frames();
    }
    if (!gpio_.set_lock(false)) std::fprintf(stderr, "gabarit-board: %s\n", gpio_.error().c_str());
    gpio_.release();
    capture_.close();
    std::fflush(stdout);
    std::fprintf(stderr,
                 "gabarit-board: %llu frames tracked, %llu delivered, %llu dropped by the driver, %llu flagged bad, "
                 "%llu unusable, %llu device losses, %llu stalls, %llu UDP sends failed\n",
                 ull(tracked_), ull(counter_total_delivered()), ull(dropped_), ull(error_frames_), ull(bad_frames_),
                 ull(losses_), ull(stalls_), ull(udp_.failed()));
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

  void wait_for_signal(int ms) {
    pollfd p{signal_fd_, POLLIN, 0};
    if (::poll(&p, 1, ms) > 0) {
      signalfd_siginfo info{};
      if (::read(signal_fd_, &info, sizeof info) == static_cast<ssize_t>(sizeof info)) progress("signal %u: stopping", info.ssi_signo);
      stop_ = true;
    }
  }

  void device_lost(const std::string& why) {
    ++losses_;
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
          dropped_ += counter_.delivered(frame.sequence);  // keeps the sequence: a flagged frame is not a dropped one
          continue;
        case CaptureEvent::kDeviceLost: device_lost(capture_.error()); return;
        case CaptureEvent::kFrame: break;
      }
      ++delivered_;
      dropped_ += counter_.delivered(frame.sequence);
      if (running_) process(frame);
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

  void process(const board::CapturedFrame& frame) {
    ImageView image;
    if (const auto s = board::luma_view(capture_.layout(), frame.data, frame.bytes_used, luma_, image); s != board::LumaStatus::kOk) {
      ++bad_frames_;
      progress("frame %u skipped: %s", frame.sequence, board::luma_status_name(s));
      return;
    }
    app::TrackRow row;
    row.frame = static_cast<std::uint32_t>(tracked_);
    SessionResult result;
    if (const Status s = session_.step(image, buffers_.scratch(), result); s != Status::kOk) {
      ++bad_frames_;
      progress("frame %u not tracked: %s", frame.sequence, status_name(s));
      return;
    }
    app::fill_row(row, result);  // the same row as gabarit track writes
    ++tracked_;
    char tail[64];
    int n = std::snprintf(tail, sizeof tail, ",%u,%llu", frame.sequence, ull(frame.timestamp_us));
    if (c_.frame_crc) std::snprintf(tail + n, sizeof tail - static_cast<std::size_t>(n), ",%08x", luma_crc32(image));
    const std::string line = app::pose_csv_row(row) + tail;
    std::printf("%s\n", line.c_str());
    udp_.send(line);
    bool ok = gpio_.set_lock(row.step.state == TrackState::kTracking);
    ok = gpio_.pulse_strobe() && ok;
    if (!ok) std::fprintf(stderr, "gabarit-board: %s\n", gpio_.error().c_str());
  }

  const Config& c_;
  int signal_fd_;
  app::SessionBuffers buffers_;
  TrackingSession session_;
  app::TableFocusStack stack_;
  board::V4l2Capture capture_;
  board::GpioLines gpio_;
  board::UdpSender udp_;
  board::FrameCounter counter_;
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
    Board board(config, table.view(), signal_fd);
    return board.run();
  } catch (const app::UsageError& e) {
    std::fprintf(stderr, "gabarit-board: %s\n(see gabarit-board --help)\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gabarit-board: error: %s\n", e.what());
    return 1;
  }
}
