#include "gabarit/hil/dut.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <netdb.h>
#include <termios.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <iterator>

#include "gabarit/app/error.hpp"
#include "gabarit/app/files.hpp"
#include "gabarit/app/session_dut.hpp"
#include "gabarit/crc32.hpp"
#include "gabarit/hil/board_map.hpp"

namespace gabarit::hil {
namespace {

// A driver's link, which exists from start() to stop(): asked for outside
// that (a DUT that could not be started again), it is an error, never a
// null dereference.
template <class T>
Transport& started(const std::unique_ptr<T>& link) {
  if (!link) throw app::Error("the DUT is not running (it could not be started)");
  return *link;
}

std::uint64_t steady_micros() {
  return static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::microseconds>(Clock::now().time_since_epoch()).count());
}

// ---- in-process

class LoopbackOutput {
 public:
  explicit LoopbackOutput(Transport& end) : end_(end) {}
  void send(std::span<const std::byte> message) noexcept {
    try {
      end_.send(message, Clock::now() + std::chrono::seconds(1));
    } catch (const std::exception&) {
      closed = true;  // the harness went away: the thread ends
    }
  }
  bool closed = false;

 private:
  Transport& end_;
};

class InprocessDut final : public DutDriver {
 public:
  explicit InprocessDut(const InprocessOptions& o) : options_(o), table_(o.table_path) {}
  ~InprocessDut() override { stop(); }
  std::string kind() const override { return "inprocess"; }
  std::chrono::milliseconds default_hang_timeout() const override { return std::chrono::milliseconds(5000); }
  std::chrono::milliseconds stall_interval() const override { return std::chrono::milliseconds(5); }
  std::string description() const override {
    return std::string("the session profile (app::HostedSession) on a thread, behind ") + (options_.udp ? "UDP on 127.0.0.1" : "a loopback link") +
           (options_.profile.tracker == app::TrackerKind::kParticle ? " (particle tracker)" : options_.profile.plain ? " (plain loop)" : "");
  }

  void start() override {
    stop();
    std::shared_ptr<Transport> device;
    if (options_.udp) {
      auto host = std::make_unique<UdpTransport>("127.0.0.1", 0);
      auto dev = std::make_shared<UdpTransport>("127.0.0.1", host->local_port());
      host->set_peer(dev->local_port());
      host_ = std::move(host);
      device = std::move(dev);
    } else {
      loopback_ = std::make_unique<Loopback>();
      host_ = loopback_->host_end();
      device.reset(loopback_->device_end().release());
    }
    stopping_ = false;
    thread_ = std::thread([this, device] { run(*device); });
  }

  void stop() noexcept override {
    stopping_ = true;
    if (loopback_) loopback_->close();
    if (thread_.joinable()) thread_.join();
    host_.reset();
    loopback_.reset();
  }

  Transport& transport() override { return started(host_); }

 private:
  void run(Transport& end) noexcept {
    try {
      app::SessionDut app(table_.view(), options_.profile, &steady_micros);
      link::DeviceDescription device;
      device.max_payload = options_.max_payload;
      device.table_crc = crc32(table_.bytes());
      device.table_bytes = static_cast<std::uint32_t>(table_.bytes().size());
      device.clock_hz = 1000000;
      device.frame_slots = options_.frame_slots;
      device.max_frame_bytes = 1024u * 1024u;
      device.mode = app.mode();
      device.kind = "inprocess";
      device.board = "host thread";
      device.device_id = crc32(std::as_bytes(std::span("inprocess/host thread")));
      const link::Caps caps = link::make_caps(device);
      std::vector<std::uint8_t> memory(link::dut_frame_memory_bytes(caps.frame_slots, caps.max_frame_bytes));
      LoopbackOutput out(end);
      link::DutEndpoint endpoint(caps, memory);
      while (!out.closed && !stopping_) {
        // Drain what has arrived, then track one frame; wait only when idle.
        bool idle = true;
        while (auto m = end.receive(Clock::now())) {
          link::deliver(endpoint, *m, app, out);
          idle = false;
        }
        if (app.track_next(endpoint)) {
          link::flush(endpoint, out);
          continue;
        }
        if (idle) {
          if (auto m = end.receive(Clock::now() + std::chrono::milliseconds(50))) link::deliver(endpoint, *m, app, out);
        }
      }
    } catch (const std::exception&) {
      // The loopback closed (stop()): the DUT powers off.
    }
  }

  InprocessOptions options_;
  app::TableFile table_;
  std::unique_ptr<Loopback> loopback_;
  std::unique_ptr<Transport> host_;
  std::thread thread_;
  std::atomic<bool> stopping_{false};
};

// ---- a child process

pid_t spawn(const std::vector<std::string>& argv, int stdio_fd, const std::string& log_path) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const int log = log_path.empty() ? ::open("/dev/null", O_WRONLY) : ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  const pid_t pid = ::fork();
  if (pid < 0) throw app::Error(std::string("cannot fork: ") + std::strerror(errno));
  if (pid == 0) {
    if (stdio_fd >= 0) {
      ::dup2(stdio_fd, 0);
      ::dup2(stdio_fd, 1);
    } else {
      const int null = ::open("/dev/null", O_RDWR);
      ::dup2(null, 0);
      ::dup2(log >= 0 ? log : null, 1);
    }
    if (log >= 0) ::dup2(log, 2);
    for (int fd = 3; fd < 1024; ++fd) ::close(fd);
    ::execvp(args[0], args.data());
    std::fprintf(stderr, "cannot run %s: %s\n", args[0], std::strerror(errno));
    ::_exit(127);
  }
  if (log >= 0) ::close(log);
  return pid;
}

void kill_and_reap(pid_t& pid) noexcept {
  if (pid <= 0) return;
  ::kill(pid, SIGKILL);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  pid = -1;
}

std::string quoted(const std::vector<std::string>& argv) {
  std::string s;
  for (const std::string& a : argv) s += (s.empty() ? "" : " ") + a;
  return s;
}

class ProcessDut final : public DutDriver {
 public:
  ProcessDut(std::string kind, std::vector<std::string> argv, std::string log, std::chrono::milliseconds hang)
      : kind_(std::move(kind)), argv_(std::move(argv)), log_(std::move(log)), default_hang_(hang) {}
  ~ProcessDut() override { stop(); }
  std::string kind() const override { return kind_; }
  std::chrono::milliseconds default_hang_timeout() const override { return default_hang_; }
  std::string description() const override { return quoted(argv_); }

  void start() override {
    stop();
    int sv[2];
    if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0)
      throw app::Error(std::string("socketpair: ") + std::strerror(errno));
    const int child_end = ::fcntl(sv[1], F_DUPFD, 3);  // without CLOEXEC for the child
    ::close(sv[1]);
    try {
      pid_ = spawn(argv_, child_end, log_);
    } catch (...) {
      ::close(sv[0]);
      ::close(child_end);
      throw;
    }
    ::close(child_end);
    transport_ = std::make_unique<StreamTransport>(sv[0], sv[0], kind_ + " (" + argv_[0] + ")");
  }

  void stop() noexcept override {
    kill_and_reap(pid_);
    transport_.reset();
  }

  Transport& transport() override { return started(transport_); }

 private:
  std::string kind_;
  std::vector<std::string> argv_;
  std::string log_;
  std::chrono::milliseconds default_hang_;
  pid_t pid_ = -1;
  std::unique_ptr<Transport> transport_;
};

// ---- QEMU

std::string hex(std::uint32_t v) {
  char b[16];
  std::snprintf(b, sizeof b, "0x%08x", v);
  return b;
}

// Spawns QEMU (`argv`), whose chardev connects to a Unix socket at
// `socket_path` that this listens on, and returns the connection as a stream
// transport. QEMU may also fail to start (a bad option): then its log says why.
std::unique_ptr<Transport> start_qemu_with_socket(const std::vector<std::string>& argv, const std::string& socket_path,
                                                  const std::string& log_path, const std::string& what, pid_t& pid) {
  const int listener = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (listener < 0) throw app::Error(std::string("socket: ") + std::strerror(errno));
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  std::snprintf(a.sun_path, sizeof a.sun_path, "%s", socket_path.c_str());
  ::unlink(socket_path.c_str());
  if (::bind(listener, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || ::listen(listener, 1) != 0) {
    const int e = errno;
    ::close(listener);
    throw app::Error(socket_path + ": cannot listen: " + std::strerror(e));
  }
  pid = spawn(argv, -1, log_path);
  const auto deadline = Clock::now() + std::chrono::seconds(20);
  int fd = -1;
  while (fd < 0) {
    pollfd p{listener, POLLIN, 0};
    if (::poll(&p, 1, 100) > 0) fd = ::accept4(listener, nullptr, nullptr, SOCK_CLOEXEC);
    int status = 0;
    if (fd < 0 && ::waitpid(pid, &status, WNOHANG) == pid) {
      pid = -1;
      ::close(listener);
      throw app::Error("qemu exited before connecting its " + what + " (see " + log_path + ")");
    }
    if (fd < 0 && Clock::now() > deadline) {
      ::close(listener);
      kill_and_reap(pid);
      throw app::Error("qemu did not connect its " + what + " within 20 s");
    }
  }
  ::close(listener);
  ::unlink(socket_path.c_str());
  return std::make_unique<StreamTransport>(fd, fd, what);
}

std::string make_temp_dir() {
  char dir[] = "/tmp/gabarit-hil-XXXXXX";
  if (::mkdtemp(dir) == nullptr) throw app::Error(std::string("mkdtemp: ") + std::strerror(errno));
  return dir;
}

class QemuDut final : public DutDriver {
 public:
  explicit QemuDut(QemuOptions o) : options_(std::move(o)) {
    ElfSymbol slot = find_elf_symbol(options_.firmware, "gabarit_table_slot");
    const ElfSymbol end = find_elf_symbol(options_.firmware, "gabarit_table_slot_end");
    if (end.address < slot.address) throw app::Error(options_.firmware + ": the table slot ends before it begins");
    slot.size = end.address - slot.address;
    const auto bytes = static_cast<std::uint64_t>(app::read_file(options_.table_path).size());
    if (bytes > slot.size)
      throw app::Error(options_.table_path + ": " + std::to_string(bytes) + " bytes; the firmware's table slot holds " +
                       std::to_string(slot.size));
    slot_ = slot.address;
    dir_ = make_temp_dir();
    socket_path_ = dir_ + "/uart0.sock";
  }
  ~QemuDut() override {
    stop();
    ::rmdir(dir_.c_str());
  }
  std::string kind() const override { return "cortex-m"; }
  std::chrono::milliseconds default_hang_timeout() const override { return std::chrono::milliseconds(60000); }
  std::chrono::milliseconds stall_interval() const override { return std::chrono::milliseconds(200); }
  std::string description() const override { return quoted(argv()); }

  std::vector<std::string> argv() const {
    std::vector<std::string> icount = {"-icount", "shift=" + std::to_string(options_.icount_shift) + ",sleep=off"};
    if (options_.icount_shift < 0) icount.clear();
    std::vector<std::string> a = {options_.qemu, "-M", options_.machine, "-nographic", "-monitor", "none"};
    a.insert(a.end(), icount.begin(), icount.end());
    const std::vector<std::string> rest = {
            "-semihosting-config", "enable=on,target=native",  // a fault ends QEMU (the harness sees a crash)
            "-kernel", options_.firmware,
            "-device", "loader,file=" + options_.table_path + ",addr=" + hex(slot_) + ",force-raw=on",
            "-chardev", "socket,id=link,path=" + socket_path_, "-serial", "chardev:link"};
    a.insert(a.end(), rest.begin(), rest.end());
    return a;
  }

  void start() override {
    stop();
    transport_ = start_qemu_with_socket(argv(), socket_path_, options_.log_path, "cortex-m UART0", pid_);
  }

  void stop() noexcept override {
    kill_and_reap(pid_);
    transport_.reset();
    ::unlink(socket_path_.c_str());
  }

  Transport& transport() override { return started(transport_); }

 private:
  QemuOptions options_;
  std::uint32_t slot_ = 0;
  std::string dir_, socket_path_;
  pid_t pid_ = -1;
  std::unique_ptr<Transport> transport_;
};

// ---- the virtual board (platform/linux/virtual-board): Debian's arm64
// kernel in qemu-system-aarch64, the board application behind vivid and USB,
// the relay on the virtio-serial port gabarit.hil.

class VirtualBoardDut final : public DutDriver {
 public:
  explicit VirtualBoardDut(VirtualBoardOptions o) : options_(std::move(o)) {
    for (const std::string* f : {&options_.board, &options_.relay, &options_.table_path})
      if (::access(f->c_str(), R_OK) != 0) throw app::Error(*f + ": not found (build the aarch64 preset's gabarit-board and gabarit-hil-relay)");
    for (const char* f : {"vmlinuz", "busybox", "modules/order"})
      if (::access((options_.cache + "/" + f).c_str(), R_OK) != 0)
        throw app::Error(options_.cache + ": no " + f + " (run platform/linux/virtual-board/prepare.sh " + options_.cache + ")");
    dir_ = make_temp_dir();
    socket_path_ = dir_ + "/hil.sock";
    initramfs_ = dir_ + "/initramfs.cpio.gz";
  }
  ~VirtualBoardDut() override {
    stop();
    ::unlink(initramfs_.c_str());
    ::rmdir(dir_.c_str());
  }
  std::string kind() const override { return "virtual-board"; }
  // Booting under emulation, then a fault that reloads a module or restarts
  // the board's program: long silences are normal.
  std::chrono::milliseconds default_hang_timeout() const override { return std::chrono::milliseconds(90000); }
  std::chrono::milliseconds stall_interval() const override { return std::chrono::milliseconds(500); }
  std::string description() const override { return quoted(argv()); }

  std::vector<std::string> argv() const {
    return {options_.qemu, "-M", "virt", "-cpu", "cortex-a72", "-smp", "2", "-m", "1024", "-nographic", "-no-reboot",
            "-nic", "none", "-kernel", options_.cache + "/vmlinuz", "-initrd", initramfs_,
            "-append", "console=ttyAMA0 panic=-1 quiet",
            "-device", "virtio-serial-device",
            "-chardev", "socket,id=hil,path=" + socket_path_,
            "-device", "virtserialport,chardev=hil,name=gabarit.hil"};
  }

  void start() override {
    stop();
    if (!built_) {
      std::vector<std::string> build = {"bash", options_.scripts + "/hil-initramfs.sh", "--cache", options_.cache,
                                        "--board", options_.board, "--relay", options_.relay,
                                        "--table", options_.table_path, "--window", options_.window,
                                        "--serial", options_.serial, "--out", initramfs_};
      if (!options_.profile_path.empty()) build.insert(build.end(), {"--profile", options_.profile_path});
      const pid_t p = spawn(build, -1, options_.log_path);
      int status = 0;
      ::waitpid(p, &status, 0);
      if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
        throw app::Error("building the virtual board's initramfs failed (see " + options_.log_path + ")");
      built_ = true;
    }
    transport_ = start_qemu_with_socket(argv(), socket_path_, options_.log_path, "virtio-serial port", pid_);
  }

  void stop() noexcept override {
    // After a BYE the guest prints its logs and powers off: give it a moment.
    for (int i = 0; i < 50 && pid_ > 0; ++i) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) pid_ = -1;
      else ::usleep(100000);
    }
    kill_and_reap(pid_);
    transport_.reset();
    ::unlink(socket_path_.c_str());
  }

  Transport& transport() override { return started(transport_); }

 private:
  VirtualBoardOptions options_;
  std::string dir_, socket_path_, initramfs_;
  bool built_ = false;
  pid_t pid_ = -1;
  std::unique_ptr<Transport> transport_;
};

// ---- a real board's relay, on a serial device or TCP

speed_t baud_constant(std::uint32_t baud) {
  switch (baud) {
    case 9600: return B9600;
    case 19200: return B19200;
    case 38400: return B38400;
    case 57600: return B57600;
    case 115200: return B115200;
    case 230400: return B230400;
    case 460800: return B460800;
    case 921600: return B921600;
    case 1000000: return B1000000;
    case 2000000: return B2000000;
    case 3000000: return B3000000;
    case 4000000: return B4000000;
    default: throw app::Error("baud " + std::to_string(baud) + ": not a standard rate");
  }
}

class BoardDut final : public DutDriver {
 public:
  explicit BoardDut(BoardMap b) : board_(std::move(b)) {}
  ~BoardDut() override { stop(); }
  std::string kind() const override { return "board"; }
  std::chrono::milliseconds default_hang_timeout() const override { return std::chrono::milliseconds(board_.hang_timeout_ms); }
  std::chrono::milliseconds stall_interval() const override { return std::chrono::milliseconds(500); }
  std::string description() const override {
    return board_.name + " (" + board_.source + "): the relay on " + board_.relay + ", gadget " + board_.usb + ", camera " +
           board_.camera + " by " + board_.frame_path;
  }

  void start() override {
    stop();
    const int fd = board_.relay.rfind("tcp:", 0) == 0 ? connect_tcp(board_.relay.substr(4)) : open_serial();
    transport_ = std::make_unique<StreamTransport>(fd, fd, board_.name + " relay");
  }
  void stop() noexcept override { transport_.reset(); }
  Transport& transport() override { return started(transport_); }

 private:
  int open_serial() const {
    const int fd = ::open(board_.relay.c_str(), O_RDWR | O_NOCTTY | O_CLOEXEC);
    if (fd < 0) throw app::Error(board_.relay + ": " + std::strerror(errno));
    termios t{};
    if (::tcgetattr(fd, &t) == 0) {  // a pty or a pipe has no line settings: fine
      ::cfmakeraw(&t);
      const speed_t speed = baud_constant(board_.baud);
      ::cfsetispeed(&t, speed);
      ::cfsetospeed(&t, speed);
      t.c_cflag |= CLOCAL | CREAD;
      if (::tcsetattr(fd, TCSANOW, &t) != 0) {
        const int e = errno;
        ::close(fd);
        throw app::Error(board_.relay + ": setting raw mode: " + std::strerror(e));
      }
    }
    return fd;
  }
  int connect_tcp(const std::string& address) const {
    const auto colon = address.rfind(':');
    if (colon == std::string::npos) throw app::Error("relay tcp:" + address + ": want tcp:HOST:PORT");
    addrinfo hints{};
    hints.ai_socktype = SOCK_STREAM;
    addrinfo* found = nullptr;
    if (::getaddrinfo(address.substr(0, colon).c_str(), address.substr(colon + 1).c_str(), &hints, &found) != 0 || found == nullptr)
      throw app::Error("relay tcp:" + address + ": cannot resolve it");
    // The board may still be booting: try for up to 20 s.
    const auto deadline = Clock::now() + std::chrono::seconds(20);
    int fd = -1;
    while (fd < 0) {
      fd = ::socket(found->ai_family, found->ai_socktype | SOCK_CLOEXEC, found->ai_protocol);
      if (fd >= 0 && ::connect(fd, found->ai_addr, found->ai_addrlen) != 0) {
        ::close(fd);
        fd = -1;
      }
      if (fd < 0 && Clock::now() > deadline) {
        ::freeaddrinfo(found);
        throw app::Error("relay tcp:" + address + ": no connection in 20 s");
      }
      if (fd < 0) ::usleep(200000);
    }
    ::freeaddrinfo(found);
    return fd;
  }

  BoardMap board_;
  std::unique_ptr<Transport> transport_;
};

template <class T>
T read_le(const std::vector<unsigned char>& b, std::size_t at) {
  if (at + sizeof(T) > b.size()) throw app::Error("truncated ELF");
  T v = 0;
  for (std::size_t i = 0; i < sizeof(T); ++i) v = static_cast<T>(v | (static_cast<T>(b[at + i]) << (8 * i)));
  return v;
}

}  // namespace

ElfSymbol find_elf_symbol(const std::string& elf_path, const std::string& name) {
  const std::vector<std::byte> file = app::read_file(elf_path);
  const std::vector<unsigned char> b(reinterpret_cast<const unsigned char*>(file.data()),
                                     reinterpret_cast<const unsigned char*>(file.data()) + file.size());
  try {
    if (b.size() < 52 || std::memcmp(b.data(), "\x7f" "ELF", 4) != 0 || b[4] != 1 || b[5] != 1)
      throw app::Error("not a little-endian ELF32 file");
    const auto shoff = read_le<std::uint32_t>(b, 32);
    const auto shentsize = read_le<std::uint16_t>(b, 46);
    const auto shnum = read_le<std::uint16_t>(b, 48);
    for (std::uint32_t s = 0; s < shnum; ++s) {
      const std::size_t sh = shoff + std::size_t{s} * shentsize;
      if (read_le<std::uint32_t>(b, sh + 4) != 2) continue;  // SHT_SYMTAB
      const auto off = read_le<std::uint32_t>(b, sh + 16), size = read_le<std::uint32_t>(b, sh + 20);
      const auto link = read_le<std::uint32_t>(b, sh + 24), entsize = read_le<std::uint32_t>(b, sh + 36);
      const std::size_t strsh = shoff + std::size_t{link} * shentsize;
      const auto stroff = read_le<std::uint32_t>(b, strsh + 16), strsize = read_le<std::uint32_t>(b, strsh + 20);
      if (entsize < 16) break;
      for (std::uint32_t at = 0; at + entsize <= size; at += entsize) {
        const auto n = read_le<std::uint32_t>(b, off + at);
        if (n >= strsize || stroff + n >= b.size()) continue;
        const char* sym = reinterpret_cast<const char*>(b.data() + stroff + n);
        const std::size_t max = std::min<std::size_t>(strsize - n, b.size() - stroff - n);
        if (::strnlen(sym, max) == name.size() && name.compare(0, name.size(), sym, name.size()) == 0)
          return {read_le<std::uint32_t>(b, off + at + 4), read_le<std::uint32_t>(b, off + at + 8)};
      }
    }
  } catch (const app::Error& e) {
    throw app::Error(elf_path + ": " + e.what());
  }
  throw app::Error(elf_path + ": no symbol " + name + " (is this the HIL firmware, gabarit-firmware-hil.elf?)");
}

std::unique_ptr<DutDriver> make_inprocess_dut(const InprocessOptions& options) { return std::make_unique<InprocessDut>(options); }

std::unique_ptr<DutDriver> make_process_dut(std::string kind, std::vector<std::string> argv, std::string log_path,
                                            std::chrono::milliseconds hang_timeout) {
  return std::make_unique<ProcessDut>(std::move(kind), std::move(argv), std::move(log_path), hang_timeout);
}

std::unique_ptr<DutDriver> make_qemu_dut(const QemuOptions& options) { return std::make_unique<QemuDut>(options); }

std::unique_ptr<DutDriver> make_board_dut(const BoardMap& board) { return std::make_unique<BoardDut>(board); }

std::unique_ptr<DutDriver> make_virtual_board_dut(const VirtualBoardOptions& options) {
  return std::make_unique<VirtualBoardDut>(options);
}

}  // namespace gabarit::hil
