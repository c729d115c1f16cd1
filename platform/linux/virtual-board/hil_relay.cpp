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
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdarg>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <dirent.h>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "gabarit/app/error.hpp"
#include "gabarit/app/files.hpp"
#include "gabarit/crc32.hpp"
#include "gabarit/link/cobs.hpp"
#include "gabarit/link/dut_endpoint.hpp"
#include "gabarit/link/protocol.hpp"
#include "gabarit/link/rig_faults.hpp"
#include "gabarit/link/usb_host.hpp"
#include "luma.hpp"
#include "v4l2_capture.hpp"
#include "vivid.hpp"

namespace {

using namespace gabarit;
using link::RigFault;

std::uint64_t now_us() {
  timespec t{};
  ::clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<std::uint64_t>(t.tv_sec) * 1000000u + static_cast<std::uint64_t>(t.tv_nsec) / 1000u;
}

std::string text(const char* format, ...) __attribute__((format(printf, 1, 2)));
std::string text(const char* format, ...) {
  char buf[256];
  va_list a;
  va_start(a, format);
  std::vsnprintf(buf, sizeof buf, format, a);
  va_end(a);
  return buf;
}

void sleep_ms(int ms) { std::this_thread::sleep_for(std::chrono::milliseconds(ms)); }

void log(const char* format, ...) __attribute__((format(printf, 1, 2)));
void log(const char* format, ...) {
  std::fprintf(stderr, "gabarit-hil-relay: ");
  va_list a;
  va_start(a, format);
  std::vfprintf(stderr, format, a);
  va_end(a);
  std::fputc('\n', stderr);
}

bool write_file(const std::string& path, const std::string& text) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd < 0) return false;
  const bool ok = ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  ::close(fd);
  return ok;
}

std::string read_file(const std::string& path) {
  std::string s;
  if (std::FILE* f = std::fopen(path.c_str(), "r")) {
    char buf[256];
    const std::size_t n = std::fread(buf, 1, sizeof buf, f);
    s.assign(buf, n);
    std::fclose(f);
  }
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  return s;
}

int run_command(const std::string& command) {
  const int r = std::system(command.c_str());
  return WIFEXITED(r) ? WEXITSTATUS(r) : -1;
}

struct Config {
  std::string port = "auto";  // the virtio-serial port, or the one named gabarit.hil
  std::string capture = "/dev/video0", output = "/dev/video1";
  std::string camera_link = "/tmp/camera";  // what the board opens: made once vivid is set up
  std::string vivid_module = "/modules/vivid.ko";
  std::string vivid_params = "node_types=0x101 n_devs=1";
  std::uint32_t width = 720, height = 480;  // vivid's S-Video frame
  std::string gadget_dir = "/sys/kernel/config/usb_gadget/gabarit";
  link::UsbIdentity usb;
  std::string gpio_dir;  // gpio-sim's sysfs folder of the chip (sim_gpioN inside)
  int lock_line = 0, strobe_line = 1;
  std::string board_log = "/tmp/board.log";
  std::string kind = "virtual-board", board_name = "QEMU virt, Cortex-A72, vivid, USB";  // CAPS: what the harness reports
  std::string table;  // the board's table file: its CRC answers HELLO's check before the board does
  std::vector<std::string> board_argv;
};

// ---- The lock and strobe lines, sampled from gpio-sim's sysfs values on a
// thread: the strobe's rising edges, time-stamped, and whether either line
// was high while the board was down (its safe level is low).
class LineSampler {
 public:
  ~LineSampler() { stop(); }
  bool start(const Config& c) {
    if (c.gpio_dir.empty()) return false;
    lock_fd_ = ::open((c.gpio_dir + "/sim_gpio" + std::to_string(c.lock_line) + "/value").c_str(), O_RDONLY | O_CLOEXEC);
    strobe_fd_ = ::open((c.gpio_dir + "/sim_gpio" + std::to_string(c.strobe_line) + "/value").c_str(), O_RDONLY | O_CLOEXEC);
    if (lock_fd_ < 0 || strobe_fd_ < 0) return false;
    thread_ = std::thread([this] { loop(); });
    return true;
  }
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  // The first rising edge at or after `t` (µs), within `wait_ms`; 0: none.
  std::uint64_t edge_after(std::uint64_t t, int wait_ms) {
    const std::uint64_t end = now_us() + static_cast<std::uint64_t>(wait_ms) * 1000u;
    for (;;) {
      {
        std::lock_guard lock(mutex_);
        for (const std::uint64_t e : edges_)
          if (e + 1000 >= t) return e;  // a sample period's slack: the edge is seen up to one period late
      }
      if (now_us() >= end) return 0;
      sleep_ms(1);
    }
  }
  void forget_edges_before(std::uint64_t t) {
    std::lock_guard lock(mutex_);
    while (!edges_.empty() && edges_.front() + 1000 < t) edges_.pop_front();
  }
  // Watches the lines for "high while down" between begin_down and end_down
  // (samples read from `since`, when the program is gone, on).
  void begin_down(std::uint64_t since) {
    high_while_down_ = false;
    down_since_ = since;
    down_ = true;
  }
  bool end_down() {
    down_ = false;
    return !high_while_down_;
  }
  std::uint64_t samples() const { return samples_; }
  std::uint64_t edges_seen() const { return edges_total_; }

 private:
  static int value(int fd) {
    char c = '0';
    return ::pread(fd, &c, 1, 0) == 1 && c == '1' ? 1 : 0;
  }
  void loop() {
    int last = 0;
    while (!stop_) {
      const std::uint64_t t = now_us();
      const int s = value(strobe_fd_);
      const int l = value(lock_fd_);
      ++samples_;
      if (s == 1 && last == 0) {
        std::lock_guard lock(mutex_);
        edges_.push_back(t);
        if (edges_.size() > 256) edges_.pop_front();
        ++edges_total_;
      }
      last = s;
      if (down_ && t >= down_since_ && (s | l) != 0) high_while_down_ = true;
      std::this_thread::sleep_for(std::chrono::microseconds(250));
    }
  }
  int lock_fd_ = -1, strobe_fd_ = -1;
  std::thread thread_;
  std::atomic<bool> stop_{false}, down_{false}, high_while_down_{false};
  std::atomic<std::uint64_t> samples_{0}, edges_total_{0}, down_since_{0};
  std::mutex mutex_;
  std::deque<std::uint64_t> edges_;
};

// ---- The board's program: started, watched, killed.
class BoardProcess {
 public:
  ~BoardProcess() { kill_now(SIGKILL); }
  bool start(const Config& c) {
    const int log_fd = ::open(c.board_log.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    pid_ = ::fork();
    if (pid_ == 0) {
      const int null_fd = ::open("/dev/null", O_WRONLY);
      ::dup2(null_fd, 1);
      if (log_fd >= 0) ::dup2(log_fd, 2);
      sigset_t none;
      sigemptyset(&none);
      ::sigprocmask(SIG_SETMASK, &none, nullptr);
      std::vector<char*> argv;
      for (const std::string& a : c.board_argv) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      ::execv(argv[0], argv.data());
      _exit(127);
    }
    if (log_fd >= 0) ::close(log_fd);
    ++starts_;
    return pid_ > 0;
  }
  // Still running? Reaps it if not (its status in last_status()).
  bool alive() {
    if (pid_ <= 0) return false;
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == pid_) {
      last_status_ = status;
      pid_ = -1;
      return false;
    }
    return true;
  }
  void kill_now(int signal) {
    if (pid_ <= 0) return;
    ::kill(pid_, signal);
    int status = 0;
    ::waitpid(pid_, &status, 0);
    last_status_ = status;
    pid_ = -1;
  }
  int last_status() const { return last_status_; }
  // VmRSS of the running program, KiB (0: not running).
  std::uint32_t resident_kib() const {
    if (pid_ <= 0) return 0;
    std::FILE* f = std::fopen(("/proc/" + std::to_string(pid_) + "/status").c_str(), "r");
    if (f == nullptr) return 0;
    char line[128];
    unsigned long kib = 0;
    while (std::fgets(line, sizeof line, f) != nullptr)
      if (std::strncmp(line, "VmRSS:", 6) == 0) kib = std::strtoul(line + 6, nullptr, 10);
    std::fclose(f);
    return static_cast<std::uint32_t>(kib);
  }
  std::uint32_t starts() const { return starts_; }

 private:
  pid_t pid_ = -1;
  int last_status_ = 0;
  std::uint32_t starts_ = 0;
};

// ---- The harness's side: the virtio-serial port, COBS-framed.
class HarnessPort {
 public:
  // A serial line (a real board's UART or USB-serial gadget) goes raw; a
  // virtio-serial port has no line settings.
  bool open(const std::string& path) {
    fd_ = ::open(path.c_str(), O_RDWR | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
    if (fd_ < 0) return false;
    termios t{};
    if (::isatty(fd_) && ::tcgetattr(fd_, &t) == 0) {
      ::cfmakeraw(&t);
      t.c_cflag |= CLOCAL | CREAD;
      if (::tcsetattr(fd_, TCSANOW, &t) != 0) return false;
    }
    return true;
  }
  int fd() const { return fd_; }
  // Reads what is there; each whole message to `on_message`.
  template <class F>
  void read_available(F&& on_message, link::DutEndpoint& endpoint) {
    std::byte buf[16384];
    for (;;) {
      const ssize_t n = ::read(fd_, buf, sizeof buf);
      if (n <= 0) return;
      for (ssize_t i = 0; i < n; ++i) {
        switch (decoder_.push(buf[i])) {
          case link::CobsStreamDecoder::Event::kMessage: on_message(decoder_.message()); break;
          case link::CobsStreamDecoder::Event::kDiscarded: endpoint.on_framing_error(); break;
          case link::CobsStreamDecoder::Event::kNone: break;
        }
      }
    }
  }
  void send(std::span<const std::byte> message) {
    std::vector<std::byte> wire(link::cobs_encoded_capacity(message.size()));
    std::size_t n = 0;
    if (link::cobs_encode(message, wire, n) != Status::kOk) return;
    std::size_t at = 0;
    while (at < n) {
      const ssize_t w = ::write(fd_, wire.data() + at, n - at);
      if (w > 0) {
        at += static_cast<std::size_t>(w);
      } else if (w < 0 && (errno == EAGAIN || errno == EINTR)) {
        pollfd p{fd_, POLLOUT, 0};
        (void)::poll(&p, 1, 100);
      } else {
        return;  // the host went away: the harness restarts the board
      }
    }
  }

 private:
  int fd_ = -1;
  std::vector<std::byte> storage_ = std::vector<std::byte>(link::message_bytes(link::kMaxPayload) + 64);
  link::CobsStreamDecoder decoder_{storage_};
};

std::string find_virtio_port(const std::string& name) {
  const std::string base = "/sys/class/virtio-ports";
  std::string found;
  if (DIR* d = ::opendir(base.c_str())) {
    while (const dirent* e = ::readdir(d))
      if (e->d_name[0] != '.' && read_file(base + "/" + e->d_name + "/name") == name) found = std::string("/dev/") + e->d_name;
    ::closedir(d);
  }
  return found;
}

// ---- The relay.
class Relay {
 public:
  explicit Relay(Config c) : c_(std::move(c)), usb_(c_.usb, link::message_bytes(link::kMinPayload)) {}

  int run();

 private:
  struct Current {
    link::ReadyFrame frame;
    std::uint32_t crc = 0;
    std::uint64_t shown = 0, deadline = 0, reshow = 0;
  };

  // Board link.
  bool board_send(link::MessageType type, std::span<const std::byte> payload, std::span<const std::byte> mangle = {});
  // Services USB for up to `ms`; handles one board message if one came.
  void pump_usb(int ms);
  void on_board_message(const std::vector<std::byte>& m);
  bool wait_usb_open(int ms);
  bool board_hello(const link::Hello& hello, link::Caps& caps);
  void board_restart(const char* why);
  // Camera.
  bool camera_up(bool wrap_sequence, std::string& error);
  void camera_down();
  bool reload_camera(int absent_ms, bool wrap_sequence, std::string& error);
  bool loop_shows(const std::uint8_t* pixels, std::uint32_t w, std::uint32_t h, std::string& error);
  // Faults.
  // nullopt: the fault ends later (a sequence wrap), answered by check_wraps().
  std::optional<link::Injected> inject(RigFault fault, const link::Inject& request);
  template <class Pred>
  bool pump_until(Pred done, int ms) {
    const std::uint64_t end = now_us() + static_cast<std::uint64_t>(ms) * 1000u;
    while (!done()) {
      if (now_us() >= end) return false;
      pump_usb(5);
      keep_board_alive();
      reshow_current();
    }
    return true;
  }
  void keep_board_alive();
  void reshow_current();
  // Harness side.
  void on_harness_message(std::span<const std::byte> m);
  void flush();
  void take_frames();
  void check_wraps();

  Config c_;
  link::UsbHostLink usb_;
  LineSampler lines_;
  BoardProcess board_;
  HarnessPort harness_;
  vivid::Output output_;
  std::optional<link::DutEndpoint> endpoint_;
  std::vector<std::uint8_t> frame_memory_;
  std::optional<Current> current_;
  std::vector<std::uint8_t> shown_;  // the last frame shown
  std::uint32_t shown_width_ = 0, shown_height_ = 0;
  std::uint32_t screen_crc_ = 0;  // what vivid shows now (the board skips a frame equal to it)
  bool have_screen_ = false;
  bool expecting_kill_ = false;
  // The board link's numbering.
  link::Sequencer sequence_{1};  // from 1: 0 is the board's "nothing acknowledged yet"
  std::uint64_t last_ping_ = 0, last_rss_ = 0;
  std::uint32_t ping_token_ = 0;
  // What the board said.
  std::optional<link::Caps> board_caps_;
  std::optional<link::Stats> board_stats_;
  std::uint64_t camera_errors_ = 0, camera_gaps_ = 0, camera_lost_ = 0, camera_back_ = 0, wraps_ = 0;
  std::uint64_t board_duplicates_ = 0, board_out_of_sequence_ = 0, stale_poses_ = 0, strobes_missed_ = 0, board_restarts_ = 0;
  // Sequence-wrap faults wait for the wrap while frames go on.
  struct PendingWrap {
    link::Injected answer;
    std::uint64_t wraps_before = 0, deadline = 0;
  };
  std::vector<PendingWrap> pending_wraps_;
};

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
  camera_down();
  std::string ignored;
  (void)vivid::set_control(c_.capture, vivid::kDisconnect, 1, ignored);
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
  std::string error;
  char evidence[160] = {};
  const auto done = [&](bool detected, const std::string& text) {
    std::snprintf(evidence, sizeof evidence, "%s", text.c_str());
    a.outcome = detected ? link::InjectOutcome::kDetected : link::InjectOutcome::kUndetected;
  };
  switch (fault) {
    case RigFault::kCameraError: {
      // vivid loses some injections (no capture buffer queued at its tick): up to five tries.
      const std::uint64_t before = camera_errors_;
      for (a.attempts = 1; a.attempts <= 5; ++a.attempts) {
        if (!vivid::set_control(c_.capture, vivid::kDqbufError, 1, error)) break;
        if (pump_until([&] { return camera_errors_ > before; }, 300)) break;
      }
      if (!error.empty()) break;
      if (a.attempts > 5) a.attempts = 5;
      done(camera_errors_ > before, text("board: %llu error-flagged buffer(s) skipped", static_cast<unsigned long long>(camera_errors_ - before)));
      break;
    }
    case RigFault::kCameraDrop: {
      const std::uint64_t before = camera_gaps_;
      if (!vivid::set_control(c_.capture, vivid::kDroppedPercent, 50, error)) break;
      pump_until([&] { return camera_gaps_ > before; }, 1000);
      std::string ignored;
      (void)vivid::set_control(c_.capture, vivid::kDroppedPercent, 0, ignored);
      done(camera_gaps_ > before, text("board: %llu sequence gap(s) reported", static_cast<unsigned long long>(camera_gaps_ - before)));
      break;
    }
    case RigFault::kSequenceWrap: {
      // vivid starts a stream at 2^32 - 128 with its wrap control on: the
      // camera is restarted with it armed, and the fault ends when the board
      // has seen the sequence go back, 128 frames later, while tracking goes on.
      if (!reload_camera(0, true, error)) break;
      a.ended = now_us();
      pending_wraps_.push_back({a, wraps_, now_us() + 15000000u});
      return std::nullopt;
    }
    case RigFault::kCameraDisconnect:
    case RigFault::kModuleReload: {
      const std::uint64_t lost = camera_lost_, back = camera_back_;
      if (!reload_camera(fault == RigFault::kModuleReload ? 1000 : 0, false, error)) break;
      pump_until([&] { return camera_back_ > back; }, 5000);
      done(camera_lost_ > lost && camera_back_ > back, text("board: camera lost (%llu) and reopened (%llu)",
           static_cast<unsigned long long>(camera_lost_ - lost), static_cast<unsigned long long>(camera_back_ - back)));
      break;
    }
    case RigFault::kUsbStall: {
      const std::uint64_t cleared = usb_.stats().halts_cleared;
      if (!usb_.halt_in_endpoint()) {
        error = usb_.error();
        break;
      }
      pump_until([&] { return usb_.stats().halts_cleared > cleared; }, 2000);
      done(usb_.stats().halts_cleared > cleared, text("host: LIBUSB_ERROR_PIPE on IN, halt cleared"));
      break;
    }
    case RigFault::kUsbUnplug: {
      const std::string udc = read_file(c_.gadget_dir + "/UDC");
      const std::uint64_t losses = usb_.stats().losses, opens = usb_.stats().opens;
      if (udc.empty() || !write_file(c_.gadget_dir + "/UDC", "\n")) {
        error = "unbinding " + c_.gadget_dir + "/UDC";
        break;
      }
      pump_until([&] { return usb_.stats().losses > losses || !usb_.is_open(); }, 1000);
      sleep_ms(100);
      if (!write_file(c_.gadget_dir + "/UDC", udc + "\n")) {
        error = "binding the gadget again";
        break;
      }
      pump_until([&] { return usb_.stats().opens > opens; }, 5000);
      done(usb_.stats().opens > opens, text("host: device gone and reopened by polling (%llu loss(es))",
           static_cast<unsigned long long>(usb_.stats().losses - losses)));
      break;
    }
    case RigFault::kUsbTimeout: {
      // Transfers given 1 ms: they expire, some with part of a message moved.
      const std::uint64_t timeouts = usb_.stats().timeouts;
      const std::uint64_t end = now_us() + 200000u;
      std::vector<std::byte> m;
      while (now_us() < end && usb_.is_open()) {
        if (usb_.receive(m, 1) == link::UsbResult::kOk) on_board_message(m);
      }
      done(usb_.stats().timeouts > timeouts, text("host: %llu transfer timeout(s), %llu with a partial message kept",
           static_cast<unsigned long long>(usb_.stats().timeouts - timeouts),
           static_cast<unsigned long long>(usb_.stats().partial_timeouts)));
      break;
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
      done(back && safe, text("board: killed (SIGKILL), lines low while down: %s, USB back: %s", safe ? "yes" : "NO",
           back ? "yes" : "NO"));
      break;
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
      done(bad_after == bad_before + 1, text("board: bad CRC count %u -> %u", bad_before, bad_after));
      break;
    }
  }
  if (!error.empty()) std::snprintf(evidence, sizeof evidence, "%s", error.c_str());
  a.ended = now_us();
  link::set_text(a.evidence, evidence);
  return a;
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

}  // namespace

int main(int argc, char** argv) {
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
