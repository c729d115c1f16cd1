// The device side of the HIL link: what every DUT runs between its transport
// and its tracker (the in-process DUT, the Verilated voter's, the Cortex-M
// firmware, the Linux board). Kernel-grade: no heap, the frame slots are the
// caller's memory, every message is checked before anything in it is used.
//
// The endpoint answers HELLO (after asking the application to start a run),
// PING, STATS and BYE itself; it reassembles FRAME fragments into slots, in
// frame order, and hands complete frames to the application one at a time
// (next_frame). Each frame it takes gets exactly one answer: a POSE
// (report_pose) or an EVENT (report_failure, or its own: dropped incomplete,
// queue full). Frames it never takes whole are answered with an EVENT when it
// learns of them: a gap in a frame's fragments, a frame older than one taken,
// a PING while a frame is still incomplete (the host pings only between frames).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "gabarit/link/protocol.hpp"

namespace gabarit::link {

// Where the endpoint's messages go: a stream transport COBS-encodes them, a
// message transport sends each as one transfer.
class MessageOutput {
 public:
  virtual void send(std::span<const std::byte> message) noexcept = 0;

 protected:
  ~MessageOutput() = default;
};

// The tracker behind the endpoint.
class DutApplication {
 public:
  // Start (or restart) a run at hello.initial; kNone accepts it.
  virtual Refusal start(const Hello& hello) noexcept = 0;
  // The DUT's clock (CAPS.clock_hz ticks), for timestamps.
  virtual std::uint64_t now() noexcept = 0;

 protected:
  ~DutApplication() = default;
};

struct ReadyFrame {
  std::uint32_t frame_id = kNoFrame;
  std::uint16_t width = 0, height = 0;
  std::span<const std::uint8_t> pixels;  // width * height, row-major; valid until it is reported
};

inline constexpr std::uint32_t kMaxFrameSlots = 8;

// Bytes of frame memory an endpoint needs.
constexpr std::size_t dut_frame_memory_bytes(std::uint32_t slots, std::uint32_t max_frame_bytes) noexcept {
  return std::size_t{slots} * max_frame_bytes;
}

class DutEndpoint {
 public:
  // `caps` describes the DUT (its frame_slots, 1..kMaxFrameSlots, and
  // max_frame_bytes size `frame_memory`; its max_payload is what it can
  // receive). The endpoint fills run_id and refusal per HELLO.
  // Precondition (GABARIT_ASSERT): frame_memory.size() >= dut_frame_memory_bytes(...).
  DutEndpoint(const Caps& caps, std::span<std::uint8_t> frame_memory, DutApplication& app, MessageOutput& out) noexcept;

  // One received message (de-framed). Never trusts it: a bad one is counted.
  void on_message(std::span<const std::byte> message) noexcept;
  // The stream decoder discarded a run (counted in STATS.framing_errors).
  void on_framing_error() noexcept { ++stats_.framing_errors; }

  // The oldest complete frame, which the application then owns until it
  // reports it. false: none (or one is already out).
  bool next_frame(ReadyFrame& frame) noexcept;
  // The frame from next_frame tracked: `pose` with everything but frame_id,
  // frame_crc, received and done, which the endpoint fills in; sends POSE.
  void report_pose(PoseReport pose) noexcept;
  // The frame from next_frame not tracked: sends EVENT.
  void report_failure(EventKind kind, EventReason reason, std::uint32_t detail) noexcept;

  bool running() const noexcept { return running_; }    // a HELLO accepted, no BYE since
  bool bye_received() const noexcept { return bye_; }
  const Stats& stats() const noexcept { return stats_; }
  std::uint32_t queued() const noexcept;  // frames taken, not yet reported
  std::uint32_t oldest_queued() const noexcept;  // the oldest of them (kNoFrame: none)

 private:
  enum class SlotState : std::uint8_t { kFree, kFilling, kReady, kOut };
  struct Slot {
    SlotState state = SlotState::kFree;
    std::uint32_t frame_id = kNoFrame;
    std::uint16_t width = 0, height = 0;
    std::uint32_t filled = 0;
    std::uint32_t crc = 0;
    std::uint64_t received = 0;
    std::uint32_t order = 0;  // completion order, for oldest-first
  };

  void on_hello(std::span<const std::byte> payload) noexcept;
  void on_frame(std::span<const std::byte> payload) noexcept;
  void send(MessageType type, std::span<const std::byte> payload) noexcept;
  void send_event(EventKind kind, EventReason reason, std::uint32_t frame_id, std::uint32_t detail) noexcept;
  void drop_filling(EventReason reason) noexcept;
  bool seen(std::uint32_t frame_id) const noexcept;
  void mark_seen(std::uint32_t frame_id) noexcept;
  std::span<std::uint8_t> slot_pixels(std::uint32_t slot) noexcept;
  std::uint16_t credits() const noexcept;

  Caps caps_;
  std::span<std::uint8_t> memory_;
  DutApplication& app_;
  MessageOutput& out_;
  Slot slots_[kMaxFrameSlots];
  std::uint32_t filling_ = kMaxFrameSlots;  // the slot being filled, or none
  std::uint32_t out_slot_ = kMaxFrameSlots; // the slot the application holds, or none
  std::uint32_t next_order_ = 0;
  // Frame ids taken this run: the newest, and which of the 64 before it.
  std::uint32_t newest_ = kNoFrame;
  std::uint64_t seen_mask_ = 0;
  std::uint32_t last_refused_ = kNoFrame;  // a late frame already answered (its other fragments stay quiet)
  bool running_ = false, bye_ = false;
  bool any_seq_ = false;
  std::uint32_t peer_seq_ = 0;  // the last sequence number accepted (our ack)
  std::uint32_t seq_ = 0;       // ours
  Stats stats_;
  std::byte tx_[message_bytes(kMinPayload)] = {};
};

}  // namespace gabarit::link
