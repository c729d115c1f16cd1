// The board application's end of the HIL link over USB (the protocol of
// docs/hil-protocol.md, one message per transfer): poses and camera events
// out; HELLO (start a run from a pose, after checking the host's table CRC),
// BYE (stop), STATS and PING in. Frames do not travel on this link: they come
// from the camera.
//
// Nothing is lost to an unplug or a damaged transfer: every message stays
// queued until the host acknowledges it (the header's ack field: the last
// message it took, and it takes them only in sequence), and whatever is
// unacknowledged is sent again each time the host configures the function
// again, or when no acknowledgement has come for a while (go-back-N). The
// host drops what it already has by sequence number.
#pragma once

#include <cstdint>
#include <deque>
#include <span>
#include <string>
#include <vector>

#include "gabarit/link/protocol.hpp"
#include "usb_gadget.hpp"

namespace gabarit::board {

class BoardLink {
 public:
  // What the board does for the host's requests.
  class Handler {
   public:
    virtual ~Handler() = default;
    // A new run from hello.initial; fills `caps` (all but run_id and refusal).
    virtual link::Refusal start(const link::Hello& hello, link::Caps& caps) = 0;
    virtual void stop() = 0;
    // The board's counters for STATS (the link's own are filled in here).
    virtual link::Stats counters() = 0;
    virtual std::uint64_t now_us() = 0;
  };

  BoardLink(UsbGadget& gadget, std::size_t max_unacknowledged = 1024);

  // Takes what the host sent (call when the gadget's event_fd is readable)
  // and sends again what an unplug may have lost.
  void service(Handler& handler);
  // Sends again, in order, what the host has not acknowledged for
  // kResendAfterUs (a message lost on the way: the host takes messages only
  // in sequence). Call whenever the loop wakes.
  void tick(std::uint64_t now_us);
  static constexpr std::uint64_t kResendAfterUs = 300000;
  void send_pose(const link::PoseReport& pose);
  void send_event(const link::Event& event);

  bool running() const { return running_; }
  std::uint32_t run_id() const { return run_id_; }
  std::uint32_t frames_in_run() const { return frames_in_run_; }  // the next pose's frame id
  std::uint64_t resent() const { return resent_; }
  std::uint64_t overflowed() const { return overflowed_; }  // unacknowledged messages given up (a host that never acks)
  const link::Stats& link_stats() const { return stats_; }

 private:
  void send(link::MessageType type, std::span<const std::byte> payload);
  void handle(std::span<const std::byte> message, Handler& handler);

  UsbGadget& gadget_;
  std::size_t max_unacked_;
  struct Sent {
    std::uint32_t seq;
    std::vector<std::byte> bytes;
  };
  std::deque<Sent> unacked_;
  link::Sequencer sequence_{1};  // from 1: 0 is the host's "nothing acknowledged yet"
  std::uint64_t enables_seen_ = 0;
  std::uint64_t last_progress_us_ = 0;  // the last ack that freed a message, or the last resend
  bool running_ = false;
  std::uint32_t run_id_ = 0;
  std::uint32_t frames_in_run_ = 0;
  link::Caps caps_;
  std::uint64_t resent_ = 0, overflowed_ = 0;
  link::Stats stats_;
};

}  // namespace gabarit::board
