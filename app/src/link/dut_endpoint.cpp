#include "gabarit/link/dut_endpoint.hpp"

#include <cstring>

#include "gabarit/assert.hpp"
#include "gabarit/crc32.hpp"

namespace gabarit::link {

DutEndpoint::DutEndpoint(const Caps& caps, std::span<std::uint8_t> frame_memory) noexcept
    : caps_(caps), memory_(frame_memory) {
  GABARIT_ASSERT(caps.frame_slots >= 1 && caps.frame_slots <= kMaxFrameSlots);
  GABARIT_ASSERT(frame_memory.size() >= dut_frame_memory_bytes(caps.frame_slots, caps.max_frame_bytes));
  if (caps_.frame_slots > kMaxFrameSlots) caps_.frame_slots = kMaxFrameSlots;
  if (caps_.frame_slots == 0) caps_.frame_slots = 1;
}

std::span<std::uint8_t> DutEndpoint::slot_pixels(std::uint32_t slot) noexcept {
  return memory_.subspan(std::size_t{slot} * caps_.max_frame_bytes, caps_.max_frame_bytes);
}

std::uint16_t DutEndpoint::credits() const noexcept {
  std::uint16_t n = 0;
  for (std::uint32_t s = 0; s < caps_.frame_slots; ++s) n = static_cast<std::uint16_t>(n + (slots_[s].state == SlotState::kFree));
  return n;
}

std::uint32_t DutEndpoint::queued() const noexcept {
  std::uint32_t n = 0;
  for (std::uint32_t s = 0; s < caps_.frame_slots; ++s)
    n += slots_[s].state == SlotState::kReady || slots_[s].state == SlotState::kOut;
  return n;
}

std::uint32_t DutEndpoint::oldest_queued() const noexcept {
  std::uint32_t oldest = kNoFrame;
  for (std::uint32_t s = 0; s < caps_.frame_slots; ++s) {
    if (slots_[s].state != SlotState::kReady && slots_[s].state != SlotState::kOut) continue;
    if (oldest == kNoFrame || seq_after(oldest, slots_[s].frame_id)) oldest = slots_[s].frame_id;
  }
  return oldest;
}

void DutEndpoint::send(MessageType type, std::span<const std::byte> payload) noexcept {
  const Header h = sequence_.stamp(type, credits());
  GABARIT_ASSERT(outbox_count_ < kOutboxMessages);
  if (outbox_count_ == kOutboxMessages) {  // the caller did not flush: never overwrite
    ++stats_.bad_message;
    return;
  }
  const std::uint32_t slot = (outbox_head_ + outbox_count_) % kOutboxMessages;
  std::size_t written = 0;
  if (encode_message(h, payload, outbox_[slot], written) != Status::kOk) return;  // payloads here are all < kMinPayload
  outbox_size_[slot] = static_cast<std::uint16_t>(written);
  ++outbox_count_;
  ++stats_.messages_out;
}

std::span<const std::byte> DutEndpoint::front_outgoing() const noexcept {
  if (outbox_count_ == 0) return {};
  return {outbox_[outbox_head_], outbox_size_[outbox_head_]};
}

void DutEndpoint::pop_outgoing() noexcept {
  if (outbox_count_ == 0) return;
  outbox_head_ = (outbox_head_ + 1) % kOutboxMessages;
  --outbox_count_;
}

void DutEndpoint::send_event(EventKind kind, EventReason reason, std::uint32_t frame_id, std::uint32_t detail) noexcept {
  std::byte payload[kEventBytes];
  const Event e{kind, reason, frame_id, detail, now_};
  send(MessageType::kEvent, std::span<const std::byte>(payload, encode(e, payload)));
}

bool DutEndpoint::seen(std::uint32_t frame_id) const noexcept {
  if (newest_ == kNoFrame) return false;
  const std::uint32_t d = newest_ - frame_id;
  return d >= 64 || ((seen_mask_ >> d) & 1u) != 0;  // beyond the window: assume taken (never a second fate)
}

void DutEndpoint::mark_seen(std::uint32_t frame_id) noexcept {
  if (newest_ == kNoFrame) {
    seen_mask_ = 1;
  } else {
    const std::uint32_t shift = frame_id - newest_;
    seen_mask_ = shift >= 64 ? 1 : (seen_mask_ << shift) | 1u;
  }
  newest_ = frame_id;
}

void DutEndpoint::drop_filling(EventReason reason) noexcept {
  if (filling_ >= kMaxFrameSlots) return;
  Slot& s = slots_[filling_];
  send_event(EventKind::kDropped, reason, s.frame_id, s.filled);
  last_refused_ = s.frame_id;
  s.state = SlotState::kFree;
  filling_ = kMaxFrameSlots;
  ++stats_.frames_dropped;
}

void DutEndpoint::on_message(std::span<const std::byte> message, std::uint64_t now) noexcept {
  now_ = now;
  Header h;
  std::span<const std::byte> payload;
  if (const Status s = decode_message(message, h, payload); s != Status::kOk) {
    ++(s == Status::kBadChecksum ? stats_.bad_crc : stats_.bad_message);
    return;
  }
  ++stats_.messages_in;
  if (std::uint32_t skipped = 0; sequence_.accept(h.seq, skipped)) {
    stats_.sequence_gaps += skipped;
  } else {
    ++stats_.stale;  // a duplicate or a late message: frames dedupe by frame id below
  }
  switch (h.type) {
    case MessageType::kHello: on_hello(payload); return;
    case MessageType::kFrame: on_frame(payload); return;
    case MessageType::kPing: {
      Ping ping;
      if (decode(payload, ping) != Status::kOk) {
        ++stats_.bad_message;
        return;
      }
      // The host pings only between frames: a frame still being assembled
      // can no longer complete, and is answered before the PONG.
      drop_filling(EventReason::kIncomplete);
      const Pong pong{ping.token, ping.host_time_us, now_, newest_, queued(), oldest_queued()};
      std::byte out[kPongBytes];
      send(MessageType::kPong, std::span<const std::byte>(out, encode(pong, out)));
      return;
    }
    case MessageType::kStats: {
      std::byte out[kStatsBytes];
      send(MessageType::kStats, std::span<const std::byte>(out, encode(stats_, out)));
      return;
    }
    case MessageType::kBye: {
      const Bye bye{0, newest_};
      std::byte out[kByeBytes];
      send(MessageType::kBye, std::span<const std::byte>(out, encode(bye, out)));
      running_ = false;
      bye_ = true;
      return;
    }
    case MessageType::kInject: {
      Inject inject;
      if (decode(payload, inject) != Status::kOk) {
        ++stats_.bad_message;
        return;
      }
      inject_ = inject;
      inject_pending_ = true;
      return;
    }
    case MessageType::kNote: {
      Note note;
      if (decode(payload, note) != Status::kOk) {
        ++stats_.bad_message;
        return;
      }
      note_ = note;
      note_pending_ = true;
      return;
    }
    case MessageType::kCaps:
    case MessageType::kPose:
    case MessageType::kEvent:
    case MessageType::kPong:
    case MessageType::kInjected:
      break;  // the device's own messages: not for it
  }
  ++stats_.unknown_type;
}

bool DutEndpoint::take_note(Note& note) noexcept {
  if (!note_pending_) return false;
  note = note_;
  note_pending_ = false;
  return true;
}

bool DutEndpoint::take_inject(Inject& inject) noexcept {
  if (!inject_pending_) return false;
  inject = inject_;
  inject_pending_ = false;
  return true;
}

void DutEndpoint::report_injected(const Injected& answer) noexcept {
  std::byte out[kInjectedBytes];
  send(MessageType::kInjected, std::span<const std::byte>(out, encode(answer, out)));
}

void DutEndpoint::report_event(EventKind kind, EventReason reason, std::uint32_t detail, std::uint64_t now) noexcept {
  now_ = now;
  send_event(kind, reason, kNoFrame, detail);
}

void DutEndpoint::on_hello(std::span<const std::byte> payload) noexcept {
  Hello hello;
  if (decode(payload, hello) != Status::kOk) {
    ++stats_.bad_message;
    return;
  }
  if (running_ && hello.run_id == caps_.run_id) {  // a repeated HELLO only gets CAPS again
    std::byte out[kCapsBytes];
    send(MessageType::kCaps, std::span<const std::byte>(out, encode(caps_, out)));
    return;
  }
  for (Slot& s : slots_) s = Slot{};
  filling_ = out_slot_ = kMaxFrameSlots;
  newest_ = last_refused_ = kNoFrame;
  seen_mask_ = 0;
  bye_ = false;
  running_ = false;
  caps_.run_id = hello.run_id;
  if (hello.version != kVersion) return answer_hello(Refusal::kProtocolVersion);
  if (hello.table_crc != 0 && hello.table_crc != caps_.table_crc) return answer_hello(Refusal::kTableMismatch);
  hello_ = hello;
  hello_pending_ = true;  // the application's to accept: answer_hello
}

void DutEndpoint::answer_hello(Refusal refusal) noexcept {
  hello_pending_ = false;
  caps_.refusal = refusal;
  running_ = refusal == Refusal::kNone;
  std::byte out[kCapsBytes];
  send(MessageType::kCaps, std::span<const std::byte>(out, encode(caps_, out)));
}

void DutEndpoint::on_frame(std::span<const std::byte> payload) noexcept {
  FrameFragment f;
  if (decode(payload, f) != Status::kOk) {
    ++stats_.bad_message;
    return;
  }
  const std::uint32_t id = f.frame_id;
  if (filling_ < kMaxFrameSlots && slots_[filling_].frame_id == id) {
    Slot& s = slots_[filling_];
    if (f.offset < s.filled) {  // a fragment again
      ++stats_.stale;
      return;
    }
    if (f.offset > s.filled || f.width != s.width || f.height != s.height) {
      drop_filling(EventReason::kIncomplete);
      return;
    }
    std::memcpy(slot_pixels(filling_).data() + s.filled, f.pixels.data(), f.pixels.size());
    s.filled += static_cast<std::uint32_t>(f.pixels.size());
  } else {
    if (id == last_refused_) return;  // already answered
    if (!running_) {
      send_event(EventKind::kSkipped, EventReason::kNotStarted, id, 0);
      last_refused_ = id;
      return;
    }
    if (newest_ != kNoFrame && !seq_after(id, newest_)) {
      if (!seen(id)) {
        send_event(EventKind::kSkipped, EventReason::kOutOfOrder, id, newest_);
        last_refused_ = id;
        ++stats_.frames_skipped;
      } else if (f.offset == 0) {
        send_event(EventKind::kDuplicate, EventReason::kRepeat, id, 0);
      }
      return;
    }
    drop_filling(EventReason::kIncomplete);  // an older frame that never completed
    mark_seen(id);
    const auto refuse = [&](EventKind kind, EventReason reason) {
      send_event(kind, reason, id, 0);
      last_refused_ = id;
      ++(kind == EventKind::kDropped ? stats_.frames_dropped : stats_.frames_skipped);
    };
    if (f.total_bytes > caps_.max_frame_bytes) return refuse(EventKind::kSkipped, EventReason::kTooLarge);
    if (f.offset != 0) return refuse(EventKind::kDropped, EventReason::kIncomplete);
    std::uint32_t free_slot = kMaxFrameSlots;
    for (std::uint32_t s = 0; s < caps_.frame_slots && free_slot == kMaxFrameSlots; ++s)
      if (slots_[s].state == SlotState::kFree) free_slot = s;
    if (free_slot == kMaxFrameSlots) return refuse(EventKind::kDropped, EventReason::kQueueFull);
    Slot& s = slots_[free_slot];
    s = Slot{SlotState::kFilling, id, f.width, f.height, 0, 0, 0, 0};
    filling_ = free_slot;
    std::memcpy(slot_pixels(free_slot).data(), f.pixels.data(), f.pixels.size());
    s.filled = static_cast<std::uint32_t>(f.pixels.size());
  }
  Slot& s = slots_[filling_];
  if (s.filled == std::uint32_t{s.width} * s.height) {
    const auto pixels = slot_pixels(filling_).first(s.filled);
    s.crc = frame_crc(ImageView{pixels.data(), s.width, s.height, s.width});
    s.received = now_;
    s.order = next_order_++;
    s.state = SlotState::kReady;
    filling_ = kMaxFrameSlots;
    ++stats_.frames_taken;
  }
}

bool DutEndpoint::next_frame(ReadyFrame& frame) noexcept {
  if (out_slot_ < kMaxFrameSlots) return false;
  std::uint32_t best = kMaxFrameSlots;
  for (std::uint32_t s = 0; s < caps_.frame_slots; ++s) {
    if (slots_[s].state == SlotState::kReady &&
        (best == kMaxFrameSlots || static_cast<std::int32_t>(slots_[s].order - slots_[best].order) < 0))
      best = s;
  }
  if (best == kMaxFrameSlots) return false;
  Slot& s = slots_[best];
  s.state = SlotState::kOut;
  out_slot_ = best;
  frame = ReadyFrame{s.frame_id, s.width, s.height, slot_pixels(best).first(s.filled)};
  return true;
}

void DutEndpoint::report_pose(PoseReport pose, std::uint64_t now) noexcept {
  now_ = now;
  GABARIT_ASSERT(out_slot_ < kMaxFrameSlots);
  if (out_slot_ >= kMaxFrameSlots) return;
  Slot& s = slots_[out_slot_];
  pose.frame_id = s.frame_id;
  pose.frame_crc = s.crc;
  pose.received = s.received;
  pose.done = now;
  s.state = SlotState::kFree;
  out_slot_ = kMaxFrameSlots;
  ++stats_.frames_tracked;
  std::byte out[kPoseBytes];
  send(MessageType::kPose, std::span<const std::byte>(out, encode(pose, out)));
}

void DutEndpoint::report_failure(EventKind kind, EventReason reason, std::uint32_t detail, std::uint64_t now) noexcept {
  now_ = now;
  GABARIT_ASSERT(out_slot_ < kMaxFrameSlots);
  if (out_slot_ >= kMaxFrameSlots) return;
  Slot& s = slots_[out_slot_];
  const std::uint32_t id = s.frame_id;
  s.state = SlotState::kFree;
  out_slot_ = kMaxFrameSlots;
  ++stats_.frames_skipped;
  send_event(kind, reason, id, detail);
}

}  // namespace gabarit::link
