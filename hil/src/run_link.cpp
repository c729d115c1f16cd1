// The harness's run, its messages: encoding, the DUT's answers, the
// handshake, pings and restarts (run.hpp).
#include "run.hpp"

namespace gabarit::hil::detail {

std::vector<std::byte> Run::encode(MessageType type, std::span<const std::byte> payload) {
  const link::Header h = sequence_.stamp(type);
  std::vector<std::byte> m(link::message_bytes(payload.size()));
  std::size_t n = 0;
  if (link::encode_message(h, payload, m, n) != Status::kOk) throw app::Error("hil: cannot encode a message");
  return m;
}

void Run::send(std::span<const std::byte> message) { wire().send(message, Clock::now() + dut_.hang_timeout()); }

void Run::resolve(std::uint32_t frame, Fate fate, const std::string& reason, const link::PoseReport* pose) {
  if (frame >= result_.frames.size() || result_.frames[frame].sent_us < 0) {
    ++result_.unknown_answers;
    return;
  }
  FrameRecord& r = result_.frames[frame];
  if (r.fate != Fate::kPending) {
    ++result_.double_answers;
    return;
  }
  r.fate = fate;
  r.reason = reason;
  outstanding_.erase(frame);
  if (pose != nullptr) {
    r.pose = *pose;
    r.latency_us = since_start_us() - r.sent_us;
    if (caps_.clock_hz != 0 && pose->done >= pose->received)
      r.dut_us = static_cast<double>(pose->done - pose->received) * 1e6 / caps_.clock_hz;
    const double tick_us = caps_.clock_hz != 0 ? 1e6 / caps_.clock_hz : 0;
    if (pose->captured != 0 && tick_us > 0) {
      if (pose->captured >= pose->received) r.camera_us = static_cast<double>(pose->captured - pose->received) * tick_us;
      if (pose->done >= pose->captured) r.track_us = static_cast<double>(pose->done - pose->captured) * tick_us;
    }
    if (pose->strobed != 0 && pose->strobed >= pose->done && tick_us > 0)
      r.strobe_us = static_cast<double>(pose->strobed - pose->done) * tick_us;
    if (static_cast<std::int64_t>(frame) <= last_pose_frame_) ++result_.out_of_order;
    last_pose_frame_ = std::max<std::int64_t>(last_pose_frame_, frame);
    last_pose_ = pose->pose;
    const auto it = images_.find(frame);
    if (it != images_.end()) {
      r.frame_crc_ok = link::frame_crc(it->second.view()) == pose->frame_crc;
      if (reference_) {
        r.mismatch = reference_->check(it->second, *pose, r.reference_ledger);
        r.reference = r.mismatch.empty() ? 1 : 0;
      }
    }
  }
  images_.erase(frame);
  if (config_.on_resolved) config_.on_resolved(r);
  if (config_.console_frame_line) notes_.emplace_back(frame, config_.console_frame_line(r));
}

void Run::send_notes() {
  for (const auto& [frame, text] : notes_) {
    link::Note note;
    note.frame_id = frame;
    link::set_text(note.text, text.c_str());
    std::byte b[link::kNoteBytes];
    send(encode(MessageType::kNote, std::span(b, link::encode(note, b))));
  }
  notes_.clear();
}

void Run::send_closing_notes(const std::vector<std::string>& lines) {
  // The opening line first if the run never got as far (a DUT that refused
  // the run): a farm then reads a complete verdict, its checks failed.
  if (!opened_ && !config_.console_opening.empty()) notes_.emplace_back(link::kNoFrame, config_.console_opening);
  for (const std::string& line : lines) notes_.emplace_back(link::kNoFrame, line);
  try {
    send_notes();
  } catch (const std::exception&) {
    // No link left (a DUT that could not be started again): its console
    // shows no end, and a farm watching for one times out, as it must for a
    // board that stopped answering. The report has the verdicts.
    notes_.clear();
  }
}

void Run::handle(const std::vector<std::byte>& message) {
  const auto start = Clock::now();
  link::Header h;
  std::span<const std::byte> payload;
  if (link::decode_message(message, h, payload) != Status::kOk) {
    ++result_.bad_messages_in;
    return;
  }
  std::uint32_t skipped = 0;
  (void)sequence_.accept(h.seq, skipped);  // our ack; the harness counts gaps by frame, not by message
  const auto decoded = [&](auto& m) {
    if (link::decode(payload, m) == Status::kOk) return true;
    ++result_.bad_messages_in;
    return false;
  };
  switch (h.type) {
    case MessageType::kCaps: {
      link::Caps c;
      if (decoded(c) && awaiting_caps_ && c.run_id == run_id_) {
        caps_ = c;
        awaiting_caps_ = false;
      }
      break;
    }
    case MessageType::kPose: {
      link::PoseReport p;
      if (!decoded(p)) break;
      codec_seconds_ += std::chrono::duration<double>(Clock::now() - start).count();
      if (p.frame_id < result_.frames.size()) result_.frames[p.frame_id].wire_bytes += wire().wire_size(message);
      resolve(p.frame_id, Fate::kPose, "", &p);
      return;
    }
    case MessageType::kEvent: {
      link::Event e;
      if (!decoded(e)) break;
      const std::string why = std::string(link::event_kind_name(e.kind)) + ": " + link::event_reason_name(e.reason);
      switch (e.kind) {
        case link::EventKind::kDropped: resolve(e.frame_id, Fate::kDroppedByDut, why); break;
        case link::EventKind::kSkipped: resolve(e.frame_id, Fate::kSkippedByDut, why); break;
        case link::EventKind::kError:
          resolve(e.frame_id, Fate::kDutError, why + " (" + std::to_string(e.detail) + ")");
          break;
        case link::EventKind::kDuplicate:
          if (e.frame_id < result_.frames.size()) ++result_.frames[e.frame_id].repeats;
          break;
        case link::EventKind::kRestart:
          // The rig restarted the DUT's program behind it: its tracker starts
          // over, so the run does (a new HELLO, the reference too).
          if (e.reason == link::EventReason::kBoot) dut_restarted_ = true;
          break;
      }
      break;
    }
    case MessageType::kInjected: {
      link::Injected in;
      if (!decoded(in)) break;
      if (in.token >= result_.faults.size() || result_.faults[in.token].answered) {
        ++result_.unknown_answers;
        break;
      }
      InjectedFault& f = result_.faults[in.token];
      f.answered = true;
      f.ended_us = since_start_us();
      f.detected = in.outcome == link::InjectOutcome::kDetected;
      f.evidence = std::string(link::inject_outcome_name(in.outcome)) + ": " + in.evidence +
                   (in.attempts > 1 ? " (" + std::to_string(in.attempts) + " injections)" : "");
      if (caps_.clock_hz != 0 && in.ended >= in.started)
        f.detail += "; lasted " + std::to_string(static_cast<long long>((in.ended - in.started) * 1000 / caps_.clock_hz)) + " ms on the DUT";
      break;
    }
    case MessageType::kPong: {
      link::Pong p;
      if (!decoded(p) || !ping_outstanding_ || p.token != ping_token_) break;
      ping_outstanding_ = false;
      // The link is in order: everything sent before the PING reached the
      // DUT before it, and the DUT answers in frame order, so every frame it
      // took that is older than its oldest queued one has been answered. A
      // frame sent before the PING, older than that, with no answer, never
      // arrived.
      {
        const std::string why = "never reached the DUT intact (its newest frame: " +
                                (p.last_frame == link::kNoFrame ? std::string("none") : std::to_string(p.last_frame)) + ")";
        std::vector<std::uint32_t> lost;
        for (const std::uint32_t f : outstanding_)
          if (static_cast<std::int64_t>(f) <= ping_covers_ && f != held_frame_ &&
              (p.queued == 0 || p.oldest_queued == link::kNoFrame || f < p.oldest_queued))
            lost.push_back(f);
        for (const std::uint32_t f : lost) resolve(f, Fate::kDroppedByLink, why);
      }
      break;
    }
    case MessageType::kStats: {
      link::Stats s;
      if (decoded(s)) result_.dut_stats = s, stats_received_ = true;
      break;
    }
    case MessageType::kBye: bye_received_ = true; break;
    default: ++result_.bad_messages_in; break;
  }
}

void Run::ping() {
  std::byte b[link::kPingBytes];
  const link::Ping p{++ping_token_, static_cast<std::uint64_t>(since_start_us())};
  send(encode(MessageType::kPing, std::span(b, link::encode(p, b))));
  ping_outstanding_ = true;
  ping_covers_ = newest_sent_;
  ping_sent_at_ = Clock::now();
}

void Run::handshake(const Pose& initial, std::uint32_t first_frame) {
  link::Hello hello;
  hello.max_payload = static_cast<std::uint16_t>(link::kMaxPayload);
  hello.table_crc = table_crc_;
  hello.run_id = ++run_id_;
  hello.initial = initial;
  hello.first_frame = first_frame;
  std::byte b[link::kHelloBytes];
  const auto message = encode(MessageType::kHello, std::span(b, link::encode(hello, b)));
  awaiting_caps_ = true;
  const auto deadline = Clock::now() + dut_.hang_timeout();
  try {
    while (awaiting_caps_) {
      send(message);  // again every second: a DUT still booting may not read it
      if (Clock::now() > deadline) break;
      pump(std::min(deadline, Clock::now() + std::chrono::seconds(1)), [&] { return !awaiting_caps_; });
    }
  } catch (const app::Error& e) {
    throw RunAborted{std::string("the DUT did not start: ") + e.what()};
  }
  if (awaiting_caps_) throw RunAborted{"the DUT did not answer HELLO within " + std::to_string(dut_.hang_timeout().count()) + " ms"};
  if (caps_.refusal == link::Refusal::kTableMismatch)
    throw RunAborted{"the DUT holds another table: CRC-32 " + std::to_string(caps_.table_crc) + " (" + std::to_string(caps_.table_bytes) +
                     " bytes), the host's " + std::to_string(table_crc_) + " (" + std::to_string(table_.bytes().size()) + " bytes)"};
  if (caps_.refusal == link::Refusal::kNoTable)
    throw RunAborted{"the DUT has no valid table it can use (too large for it, or none loaded; see its log)"};
  if (caps_.refusal != link::Refusal::kNone)
    throw RunAborted{std::string("the DUT refused the run: ") + link::refusal_name(caps_.refusal)};
  if (run_id_ == 1) {
    result_.caps = caps_;
    if ((caps_.mode & link::kModeTuned) != 0)
      throw RunAborted{"the DUT runs a session profile with tuned numbers, which CAPS does not carry: the reference cannot mirror it"};
    try {
      reference_.emplace(table_.view(), caps_.mode);
    } catch (const app::Error& e) {
      throw RunAborted{std::string("the reference cannot run the DUT's mode: ") + e.what()};
    }
    window_ = std::clamp<std::uint32_t>(caps_.frame_slots, 1, link::kMaxFrameSlots);
    max_payload_ = std::clamp<std::size_t>(caps_.max_payload, link::kMinPayload, link::kMaxPayload);
  }
  if (!reference_->start(initial)) throw RunAborted{"the reference rejected the initial pose"};
  ping_outstanding_ = false;
  last_activity_ = Clock::now();
}

void Run::restart(RestartCause cause, const std::string& why) {
  switch (cause) {
    case RestartCause::kPlanned: ++result_.restarts_planned; break;
    case RestartCause::kHung: ++result_.restarts_hung; break;
    case RestartCause::kCrashed: ++result_.restarts_crashed; break;
  }
  if (result_.restarts_hung + result_.restarts_crashed > config_.max_unplanned_restarts)
    throw RunAborted{"more than " + std::to_string(config_.max_unplanned_restarts) + " unplanned restarts; the last: " + why};
  const std::vector<std::uint32_t> lost(outstanding_.begin(), outstanding_.end());
  for (const std::uint32_t f : lost) resolve(f, Fate::kLostInRestart, why);
  held_.clear();
  held_frame_ = link::kNoFrame;
  ping_outstanding_ = false;
  sequence_.forget_peer();  // a restarted DUT numbers its messages from 0
  dut_.stop();
  try {
    dut_.start();
  } catch (const app::Error& e) {
    throw RunAborted{std::string("the DUT did not restart: ") + e.what()};
  }
  handshake(last_pose_, next_frame_);
  for (auto& r : result_.frames)
    if (r.frame >= next_frame_) r.run = run_id_ - 1;
}

void Run::restart_reported() {
  dut_restarted_ = false;
  ++result_.restarts_reported;
  const std::vector<std::uint32_t> lost(outstanding_.begin(), outstanding_.end());
  for (const std::uint32_t f : lost) resolve(f, Fate::kLostInRestart, "the DUT's rig restarted it (its program ended or was killed)");
  ping_outstanding_ = false;
  handshake(last_pose_, next_frame_);
  for (auto& r : result_.frames)
    if (r.frame >= next_frame_) r.run = run_id_ - 1;
}

// A rig fault: the DUT's rig does it before the frame is sent, and answers
// when it is over (a sequence wrap ends later, while frames go on).
void Run::inject(std::uint32_t index, const PlannedFault& fault) {
  const auto token = static_cast<std::uint32_t>(result_.frames[index].fault);
  InjectedFault& f = result_.faults[token];
  f.detail = "injected by the DUT's rig before frame " + std::to_string(index);
  const link::Inject request{token, rig_fault_number(fault.kind)};
  std::byte b[link::kInjectBytes];
  send(encode(MessageType::kInject, std::span(b, link::encode(request, b))));
  if (fault.kind == FaultKind::kSequenceWrap) return;
  if (!pump(Clock::now() + dut_.hang_timeout(), [&] { return result_.faults[token].answered; }))
    result_.faults[token].evidence = "no answer from the rig in " + std::to_string(dut_.hang_timeout().count()) + " ms";
}

}  // namespace gabarit::hil::detail
