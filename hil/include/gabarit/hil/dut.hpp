// Devices under test: each driver owns its DUT's start, reset and teardown
// (labgrid's strategies), so a hung or crashed DUT is killed and started
// again, never waited on forever. stop() always returns.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "gabarit/app/session_profile.hpp"
#include "gabarit/hil/transport.hpp"

namespace gabarit::hil {

class DutDriver {
 public:
  virtual ~DutDriver() = default;
  virtual std::string kind() const = 0;
  // Powers the DUT on (spawns it); transport() is then valid until stop().
  virtual void start() = 0;
  virtual void stop() noexcept = 0;
  virtual Transport& transport() = 0;
  // How long the DUT may stay silent with a PING outstanding before it is
  // declared hung, and how long a start may take: the driver's default, or
  // what set_hang_timeout gave.
  std::chrono::milliseconds hang_timeout() const { return hang_.count() ? hang_ : default_hang_timeout(); }
  void set_hang_timeout(std::chrono::milliseconds t) { hang_ = t; }
  virtual std::chrono::milliseconds default_hang_timeout() const { return std::chrono::milliseconds(5000); }
  // How long without an answer before the harness asks (PING).
  virtual std::chrono::milliseconds stall_interval() const { return std::chrono::milliseconds(20); }
  // What the driver ran (a command line), for the report.
  virtual std::string description() const { return kind(); }

 private:
  std::chrono::milliseconds hang_{0};
};

struct InprocessOptions {
  std::string table_path;
  app::SessionProfile profile;  // what the device runs (the session's defaults unless told)
  std::uint32_t frame_slots = 4;
  std::uint16_t max_payload = 16384;
  bool udp = false;             // two UDP sockets on 127.0.0.1 instead of the loopback
};
// The session a profile describes (app::HostedSession: the stencil session
// or the particle tracker) on a thread of this process behind a loopback
// link: the protocol is exercised end to end, nothing else is between.
std::unique_ptr<DutDriver> make_inprocess_dut(const InprocessOptions& options);

// A DUT program speaking the protocol COBS-framed on its stdin and stdout (a
// socket pair); its stderr goes to `log_path`. Killed with SIGKILL on stop.
std::unique_ptr<DutDriver> make_process_dut(std::string kind, std::vector<std::string> argv, std::string log_path,
                                            std::chrono::milliseconds hang_timeout);

struct QemuOptions {
  std::string qemu = "qemu-system-arm";
  std::string machine = "mps2-an500";
  std::string firmware;     // the HIL firmware ELF (platform/cortex-m, gabarit-firmware-hil)
  std::string table_path;   // loaded into the firmware's table slot (-device loader)
  int icount_shift = 0;     // -icount shift=N,sleep=off: deterministic guest time
  std::string log_path;     // QEMU's own output
};
// The Cortex-M firmware in qemu-system-arm; its UART0 is a Unix socket the
// harness listens on. The table slot's address and size come from the ELF's
// gabarit_table_slot and gabarit_table_slot_end symbols.
std::unique_ptr<DutDriver> make_qemu_dut(const QemuOptions& options);

struct VirtualBoardOptions {
  std::string qemu = "qemu-system-aarch64";
  std::string cache;       // prepare.sh's: the kernel, busybox, the modules
  std::string scripts;     // platform/linux/virtual-board (hil-initramfs.sh, hil-init.sh)
  std::string board;       // the aarch64 gabarit-board
  std::string relay;       // the aarch64 gabarit-hil-relay
  std::string table_path;
  std::string window;      // WxH: the sequence's frame size (the board tracks that corner of vivid's frame)
  std::string serial = "gabarit-vb-0001";  // the gadget's USB serial number
  std::string log_path;    // the guest's console
  std::string profile_path;  // a session profile for gabarit-board (--profile); empty: its defaults
};
// The virtual board: the board application on Debian's arm64 kernel in
// qemu-system-aarch64, frames through vivid (V4L2), poses over a USB
// FunctionFS gadget (dummy_hcd), both bridged to the harness by a relay in
// the guest on a virtio-serial port (platform/linux/virtual-board/README.md).
std::unique_ptr<DutDriver> make_virtual_board_dut(const VirtualBoardOptions& options);

// A real board (hil/boards/NAME.yaml, board_map.hpp) running the HIL relay
// as the virtual board does: the harness reaches the relay on a serial
// device or TCP. The board cannot be power-cycled from here: a restart
// reconnects.
std::unique_ptr<DutDriver> make_board_dut(const struct BoardMap& board);

// The address and size of an ELF32 symbol (the firmware's table slot).
struct ElfSymbol {
  std::uint32_t address = 0, size = 0;
};
ElfSymbol find_elf_symbol(const std::string& elf_path, const std::string& name);  // throws app::Error

}  // namespace gabarit::hil
