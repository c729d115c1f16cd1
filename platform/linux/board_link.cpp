// See board_link.hpp.
#include "board_link.hpp"

namespace gabarit::board {

BoardLink::BoardLink(UsbGadget& gadget, std::size_t max_unacknowledged) : gadget_(gadget), max_unacked_(max_unacknowledged) {}

void BoardLink::send(link::MessageType type, std::span<const std::byte> payload) {
  const link::Header h = sequence_.stamp(type);
  Sent s{h.seq, std::vector<std::byte>(link::message_bytes(payload.size()))};
  std::size_t n = 0;
  if (link::encode_message(h, payload, s.bytes, n) != Status::kOk) return;  // payloads here are all small
  ++stats_.messages_out;
  if (gadget_.enabled()) (void)gadget_.send(s.bytes);  // a full queue: the resend after the next enable carries it
  if (unacked_.size() >= max_unacked_) {
    unacked_.pop_front();
    ++overflowed_;
  }
  unacked_.push_back(std::move(s));
}

void BoardLink::send_pose(const link::PoseReport& pose) {
  link::PoseReport p = pose;
  p.frame_id = frames_in_run_++;
  std::byte out[link::kPoseBytes];
  send(link::MessageType::kPose, std::span<const std::byte>(out, link::encode(p, out)));
}

void BoardLink::send_event(const link::Event& event) {
  std::byte out[link::kEventBytes];
  send(link::MessageType::kEvent, std::span<const std::byte>(out, link::encode(event, out)));
}

void BoardLink::tick(std::uint64_t now_us) {
  if (unacked_.empty()) {
    last_progress_us_ = now_us;
    return;
  }
  if (!gadget_.enabled() || now_us - last_progress_us_ < kResendAfterUs) return;
  for (const Sent& s : unacked_) {
    (void)gadget_.send(s.bytes);
    ++resent_;
  }
  last_progress_us_ = now_us;
}

void BoardLink::service(Handler& handler) {
  gadget_.clear_event();
  if (const std::uint64_t enables = gadget_.enable_count(); enables != enables_seen_) {
    // The host configured us (again): whatever it has not acknowledged may
    // have been lost with the cable.
    enables_seen_ = enables;
    for (const Sent& s : unacked_) {
      (void)gadget_.send(s.bytes);
      ++resent_;
    }
  }
  std::vector<std::byte> message;
  while (gadget_.receive(message)) handle(message, handler);
}

void BoardLink::handle(std::span<const std::byte> message, Handler& handler) {
  link::Header h;
  std::span<const std::byte> payload;
  if (const Status s = link::decode_message(message, h, payload); s != Status::kOk) {
    ++(s == Status::kBadChecksum ? stats_.bad_crc : stats_.bad_message);
    return;
  }
  ++stats_.messages_in;
  if (std::uint32_t skipped = 0; sequence_.accept(h.seq, skipped)) {
    stats_.sequence_gaps += skipped;
  } else {
    ++stats_.stale;
  }
  // Everything up to the host's ack has arrived.
  bool freed = false;
  while (!unacked_.empty() && !link::seq_after(unacked_.front().seq, h.ack)) unacked_.pop_front(), freed = true;
  if (freed) last_progress_us_ = handler.now_us();
  switch (h.type) {
    case link::MessageType::kHello: {
      link::Hello hello;
      if (link::decode(payload, hello) != Status::kOk) {
        ++stats_.bad_message;
        return;
      }
      if (!(running_ && hello.run_id == run_id_)) {  // a repeated HELLO gets its CAPS again
        caps_ = link::Caps{};
        caps_.refusal = handler.start(hello, caps_);
        caps_.run_id = hello.run_id;
        running_ = caps_.refusal == link::Refusal::kNone;
        run_id_ = hello.run_id;
        frames_in_run_ = 0;
      }
      std::byte out[link::kCapsBytes];
      send(link::MessageType::kCaps, std::span<const std::byte>(out, link::encode(caps_, out)));
      return;
    }
    case link::MessageType::kPing: {
      link::Ping ping;
      if (link::decode(payload, ping) != Status::kOk) {
        ++stats_.bad_message;
        return;
      }
      const link::Pong pong{ping.token, ping.host_time_us, handler.now_us(),
                            frames_in_run_ == 0 ? link::kNoFrame : frames_in_run_ - 1, 0, link::kNoFrame};
      std::byte out[link::kPongBytes];
      send(link::MessageType::kPong, std::span<const std::byte>(out, link::encode(pong, out)));
      return;
    }
    case link::MessageType::kStats: {
      link::Stats s = handler.counters();
      s.messages_in = stats_.messages_in;
      s.bad_crc = stats_.bad_crc;
      s.bad_message = stats_.bad_message;
      s.unknown_type = stats_.unknown_type;
      s.sequence_gaps = stats_.sequence_gaps;
      s.stale = stats_.stale;
      s.messages_out = stats_.messages_out + 1;
      std::byte out[link::kStatsBytes];
      send(link::MessageType::kStats, std::span<const std::byte>(out, link::encode(s, out)));
      return;
    }
    case link::MessageType::kBye: {
      if (running_) handler.stop();
      running_ = false;
      const link::Bye bye{0, frames_in_run_ == 0 ? link::kNoFrame : frames_in_run_ - 1};
      std::byte out[link::kByeBytes];
      send(link::MessageType::kBye, std::span<const std::byte>(out, link::encode(bye, out)));
      return;
    }
    default: ++stats_.unknown_type; return;
  }
}

}  // namespace gabarit::board
