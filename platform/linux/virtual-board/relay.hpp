// The virtual board's relay (hil_relay.cpp): the class, its board and
// harness sides in hil_relay.cpp, its camera and the rig's faults in
// relay_faults.cpp.
#pragma once

#include <array>

#include "relay_parts.hpp"

namespace gabarit::relay {

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
  // Faults (relay_faults.cpp).
  // nullopt: the fault ends later (a sequence wrap), answered by check_wraps().
  std::optional<link::Injected> inject(RigFault fault, const link::Inject& request);
  // A camera fault (vivid) or a link or board fault: whether the board or the
  // host saw it (nullopt: it could not be injected, `error` says why), with
  // what showed it in `evidence`; `attempts` the injections it took.
  std::optional<bool> inject_camera(RigFault fault, std::uint16_t& attempts, std::string& evidence, std::string& error);
  std::optional<bool> inject_link(RigFault fault, std::string& evidence, std::string& error);
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
  // The frames shown most recently (harness frame, CRC-32C), to name the
  // pixels of a stale pose in the log.
  struct ShownFrame {
    std::uint32_t frame_id = 0, crc = 0;
  };
  std::array<ShownFrame, 16> recent_{};
  std::size_t recent_count_ = 0;
};

}  // namespace gabarit::relay
