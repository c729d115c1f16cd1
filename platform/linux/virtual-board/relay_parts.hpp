// The virtual board's relay (hil_relay.cpp), its parts: the guest's clock,
// logging and small file helpers, the relay's configuration, the sampler of
// the board's GPIO lines, the board's process, and the harness's port.
#pragma once

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

namespace gabarit::relay {

using link::RigFault;

inline std::uint64_t now_us() {
  timespec t{};
  ::clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<std::uint64_t>(t.tv_sec) * 1000000u + static_cast<std::uint64_t>(t.tv_nsec) / 1000u;
}

inline std::string text(const char* format, ...) __attribute__((format(printf, 1, 2)));
inline std::string text(const char* format, ...) {
  char buf[256];
  va_list a;
  va_start(a, format);
  std::vsnprintf(buf, sizeof buf, format, a);
  va_end(a);
  return buf;
}

inline void sleep_ms(int ms) { std::this_thread::sleep_for(std::chrono::milliseconds(ms)); }

inline void log(const char* format, ...) __attribute__((format(printf, 1, 2)));
inline void log(const char* format, ...) {
  std::fprintf(stderr, "gabarit-hil-relay: ");
  va_list a;
  va_start(a, format);
  std::vfprintf(stderr, format, a);
  va_end(a);
  std::fputc('\n', stderr);
}

inline bool write_file(const std::string& path, const std::string& text) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd < 0) return false;
  const bool ok = ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  ::close(fd);
  return ok;
}

inline std::string read_file(const std::string& path) {
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

inline int run_command(const std::string& command) {
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

inline std::string find_virtio_port(const std::string& name) {
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
}  // namespace gabarit::relay
