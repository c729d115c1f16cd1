// The device side of the HIL link: what every DUT runs between its transport
// and its tracker (the in-process DUT, the Verilated voter's, the Cortex-M
// firmware, the virtual board's relay). Kernel-grade: no heap, the frame slots are the
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

// The endpoint does no I/O and calls nothing of its caller's (no virtual
// calls: the firmware's stack report follows every call): it takes a received
// message and the time, and queues the messages to send in its outbox, which
// the caller empties after each call (flush). A HELLO waits for the
// application's answer (pending_hello, answer_hello). deliver() does the
// three for a message, for any Application with
//   link::Refusal start(const link::Hello&) noexcept   // kNone accepts the run
//   std::uint64_t now() noexcept                       // its clock, CAPS.clock_hz ticks
// and any Output with
//   void send(std::span<const std::byte> message) noexcept
// (a stream transport COBS-encodes each message; a message transport sends
// each as one transfer).

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
  DutEndpoint(const Caps& caps, std::span<std::uint8_t> frame_memory) noexcept;

  // One received message (de-framed), at time `now`. Never trusts it: a bad
  // one is counted.
  void on_message(std::span<const std::byte> message, std::uint64_t now) noexcept;
  // The stream decoder discarded a run (counted in STATS.framing_errors).
  void on_framing_error() noexcept { ++stats_.framing_errors; }

  // The oldest complete frame, which the application then owns until it
  // reports it. false: none (or one is already out).
  bool next_frame(ReadyFrame& frame) noexcept;
  // The frame from next_frame tracked, done at `now`: `pose` with everything
  // but frame_id, frame_crc, received and done, which the endpoint fills in;
  // queues POSE.
  void report_pose(PoseReport pose, std::uint64_t now) noexcept;
  // The frame from next_frame not tracked: queues EVENT.
  void report_failure(EventKind kind, EventReason reason, std::uint32_t detail, std::uint64_t now) noexcept;

  // A HELLO that waits for the application's answer (null: none); the
  // answer queues CAPS.
  const Hello* pending_hello() const noexcept { return hello_pending_ ? &hello_ : nullptr; }
  void answer_hello(Refusal refusal) noexcept;

  // An INJECT waiting for the application's answer (null: none): a DUT whose
  // rig can inject faults on its side (the virtual board's relay) does it and
  // answers INJECTED; deliver() answers unsupported for any other.
  // The rig may answer later (a fault that ends on its own time) and may
  // take another INJECT meanwhile: take_inject() hands the request over,
  // report_injected() queues its answer (the caller's token and kind).
  const Inject* pending_inject() const noexcept { return inject_pending_ ? &inject_ : nullptr; }
  bool take_inject(Inject& inject) noexcept;
  void report_injected(const Injected& answer) noexcept;
  // A NOTE for the DUT's console (its text is printable ASCII): a DUT with a
  // console prints it (deliver() calls app.note where the application has
  // one); the rest ignore it.
  bool take_note(Note& note) noexcept;
  // A DUT event with no frame (kNoFrame): a rig's DUT restarted behind it
  // (kRestart, kBoot), which the host answers with a new HELLO.
  void report_event(EventKind kind, EventReason reason, std::uint32_t detail, std::uint64_t now) noexcept;
  // The tracker mode CAPS reports, where the rig learns it from its DUT.
  void set_mode(std::uint32_t mode) noexcept { caps_.mode = mode; }
  // STATS.resident_kib, where the DUT knows it.
  void set_resident_kib(std::uint32_t kib) noexcept { stats_.resident_kib = kib; }

  // The oldest queued message to send (empty: none), and its removal. The
  // outbox holds kOutboxMessages; a call queues at most two, so emptying it
  // after every call never loses one (STATS.messages_out counts what was
  // queued; an overflow would be counted in bad_message, and asserted).
  std::span<const std::byte> front_outgoing() const noexcept;
  void pop_outgoing() noexcept;
  static constexpr std::uint32_t kOutboxMessages = 4;

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
  std::uint64_t now_ = 0;  // the time of the call being handled
  Slot slots_[kMaxFrameSlots];
  std::uint32_t filling_ = kMaxFrameSlots;  // the slot being filled, or none
  std::uint32_t out_slot_ = kMaxFrameSlots; // the slot the application holds, or none
  std::uint32_t next_order_ = 0;
  // Frame ids taken this run: the newest, and which of the 64 before it.
  std::uint32_t newest_ = kNoFrame;
  std::uint64_t seen_mask_ = 0;
  std::uint32_t last_refused_ = kNoFrame;  // a late frame already answered (its other fragments stay quiet)
  bool running_ = false, bye_ = false;
  Sequencer sequence_;  // ours, and the last of the peer's accepted (our ack)
  Stats stats_;
  Hello hello_;
  bool hello_pending_ = false;
  Inject inject_;
  bool inject_pending_ = false;
  Note note_;
  bool note_pending_ = false;
  std::byte outbox_[kOutboxMessages][message_bytes(kMinPayload)] = {};
  std::uint16_t outbox_size_[kOutboxMessages] = {};
  std::uint32_t outbox_head_ = 0, outbox_count_ = 0;
};

// One received message through the endpoint: handled, a HELLO answered by
// the application, the outbox sent.
template <class Output>
void flush(DutEndpoint& endpoint, Output& out) noexcept {
  for (auto m = endpoint.front_outgoing(); !m.empty(); m = endpoint.front_outgoing()) {
    out.send(m);
    endpoint.pop_outgoing();
  }
}

template <class Application, class Output>
void deliver(DutEndpoint& endpoint, std::span<const std::byte> message, Application& app, Output& out) noexcept {
  endpoint.on_message(message, app.now());
  if (const Hello* hello = endpoint.pending_hello()) endpoint.answer_hello(app.start(*hello));
  if (Inject inject; endpoint.take_inject(inject)) {
    Injected answer;
    answer.outcome = InjectOutcome::kUnsupported;
    if constexpr (requires { app.inject(inject); }) answer = app.inject(inject);
    answer.token = inject.token;
    answer.kind = inject.kind;
    endpoint.report_injected(answer);
  }
  if (Note note; endpoint.take_note(note)) {
    if constexpr (requires { app.note(note); }) app.note(note);
  }
  flush(endpoint, out);
}

}  // namespace gabarit::link
