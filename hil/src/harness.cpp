#include "gabarit/hil/harness.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <filesystem>
#include <map>
#include <set>

#include "gabarit/app/error.hpp"
#include "gabarit/app/files.hpp"
#include "gabarit/app/image_io.hpp"
#include "gabarit/app/hosted_session.hpp"
#include "gabarit/app/scratch.hpp"
#include "gabarit/crc32.hpp"
#include "gabarit/app/evaluation.hpp"
#include "gabarit/app/rng.hpp"
#include "gabarit/link/dut_endpoint.hpp"
#include "gabarit/link/session_report.hpp"
#include "gabarit/tracking_session.hpp"

namespace gabarit::hil {

const char* fate_name(Fate fate) {
  switch (fate) {
    case Fate::kPending: return "pending";
    case Fate::kPose: return "pose";
    case Fate::kDroppedByLink: return "dropped-by-link";
    case Fate::kDroppedByDut: return "dropped-by-dut";
    case Fate::kSkippedByDut: return "skipped-by-dut";
    case Fate::kDutError: return "dut-error";
    case Fate::kLostInRestart: return "lost-in-restart";
    case Fate::kNotSent: return "not-sent";
  }
  return "unknown";
}

LatencySummary summarise(std::vector<double> v) {
  LatencySummary s;
  s.samples = v.size();
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  const auto rank = [&](double q) {
    const auto r = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
    return v[std::clamp<std::size_t>(r, 1, v.size()) - 1];
  };
  s.p50 = rank(0.5);
  s.p99 = rank(0.99);
  s.max = v.back();
  double sum = 0;
  for (double x : v) sum += x;
  s.mean = sum / static_cast<double>(v.size());
  return s;
}

namespace {

using link::MessageType;

// The host's reference: the kernel on the same table, in the mode the DUT
// reports, fed the frames the DUT tracked in the order it tracked them.
class Reference {
 public:
  Reference(const TableView& table, std::uint32_t mode) : session_(table, app::profile_from_mode_bits(mode)) {}

  bool start(const Pose& initial) { return session_.start(initial); }

  // "" when the DUT's report is bit-identical to the reference's, else the first field that differs.
  std::string check(const app::GrayImage& frame, const link::PoseReport& dut) {
    SessionResult r;
    if (const Status s = session_.step(frame.view(), r); s != Status::kOk)
      return std::string("the reference failed: ") + status_name(s);
    const link::PoseReport ref = link::session_report(r);
    const auto bits = [](float f) {
      std::uint32_t b;
      std::memcpy(&b, &f, 4);
      return b;
    };
    const auto differ = [](const char* field, double want, double got) {
      char text[160];
      std::snprintf(text, sizeof text, "%s: reference %.9g, DUT %.9g", field, want, got);
      return std::string(text);
    };
    if (bits(ref.pose.x) != bits(dut.pose.x)) return differ("x", ref.pose.x, dut.pose.x);
    if (bits(ref.pose.y) != bits(dut.pose.y)) return differ("y", ref.pose.y, dut.pose.y);
    if (bits(ref.pose.theta_deg) != bits(dut.pose.theta_deg)) return differ("theta_deg", ref.pose.theta_deg, dut.pose.theta_deg);
    if (ref.pose.depth != dut.pose.depth) return differ("depth", ref.pose.depth, dut.pose.depth);
    if (ref.state != dut.state) return differ("state", ref.state, dut.state);
    if (ref.confidence != dut.confidence) return differ("confidence", ref.confidence, dut.confidence);
    if (ref.best_votes != dut.best_votes) return differ("votes", ref.best_votes, dut.best_votes);
    if (bits(ref.score) != bits(dut.score)) return differ("score", ref.score, dut.score);
    if (ref.features != dut.features) return differ("features", ref.features, dut.features);
    if (ref.features_dropped != dut.features_dropped) return differ("features_dropped", ref.features_dropped, dut.features_dropped);
    if (ref.votes != dut.votes) return differ("counter increments", static_cast<double>(ref.votes), static_cast<double>(dut.votes));
    if (ref.flags != dut.flags) return differ("flags", ref.flags, dut.flags);
    return "";
  }

 private:
  app::HostedSession session_;
};

enum class RestartCause { kPlanned, kHung, kCrashed };

struct RunAborted {
  std::string why;
};

class Run {
 public:
  Run(const RunConfig& config, DutDriver& dut, RunResult& result)
      : config_(config), dut_(dut), result_(result), table_(config.table_path), rng_(config.seed ^ 0x5EEDull) {
    table_crc_ = crc32(table_.bytes());
  }

  void execute();
  void judge_faults();

 private:
  Transport& wire() { return dut_.transport(); }
  std::vector<std::byte> encode(MessageType type, std::span<const std::byte> payload);
  void send(std::span<const std::byte> message);
  void handle(const std::vector<std::byte>& message);
  // Receives and handles until done() or the deadline; restarts a hung or
  // crashed DUT on the way. false at the deadline.
  template <class Done>
  bool pump(Clock::time_point deadline, Done done);
  void handshake(const Pose& initial, std::uint32_t first_frame);
  void restart(RestartCause cause, const std::string& why);
  void resolve(std::uint32_t frame, Fate fate, const std::string& reason, const link::PoseReport* pose = nullptr);
  void send_frame(std::uint32_t index, const app::GrayImage& image, const PlannedFault* fault);
  void ping();
  void inject(std::uint32_t index, const PlannedFault& fault);
  void restart_reported();
  void sample_soak(std::uint32_t frames_sent);
  double since_start_us() const { return std::chrono::duration<double, std::micro>(Clock::now() - t0_).count(); }

  const RunConfig& config_;
  DutDriver& dut_;
  RunResult& result_;
  app::TableFile table_;
  std::uint32_t table_crc_ = 0;
  app::Rng rng_;
  Clock::time_point t0_ = Clock::now();
  std::optional<Reference> reference_;
  link::Caps caps_;
  bool awaiting_caps_ = false;
  std::uint32_t run_id_ = 0;
  link::Sequencer sequence_;  // the peer forgotten at a restart: a restarted DUT numbers from 0
  std::map<std::uint32_t, app::GrayImage> images_;  // sent, not yet resolved
  std::set<std::uint32_t> outstanding_;
  std::vector<std::vector<std::byte>> held_;  // a reordered frame's messages
  std::uint32_t held_frame_ = link::kNoFrame;
  std::uint32_t next_frame_ = 0;              // the next frame to send
  std::int64_t newest_sent_ = -1;
  std::int64_t last_pose_frame_ = -1;
  Pose last_pose_;
  bool ping_outstanding_ = false;
  std::uint32_t ping_token_ = 0;
  std::int64_t ping_covers_ = -1;
  Clock::time_point ping_sent_at_, last_activity_ = Clock::now();
  bool stats_received_ = false, bye_received_ = false;
  double codec_seconds_ = 0;
  std::uint32_t window_ = 1;
  std::size_t max_payload_ = link::kMinPayload;
  bool dut_restarted_ = false;  // an EVENT restart/boot: the rig restarted the DUT behind it
  std::uint32_t soak_from_ = 0;  // the first frame of the soak window being measured
};

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
        r.mismatch = reference_->check(it->second, *pose);
        r.reference = r.mismatch.empty() ? 1 : 0;
      }
    }
  }
  images_.erase(frame);
  if (config_.on_resolved) config_.on_resolved(r);
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

template <class Done>
bool Run::pump(Clock::time_point deadline, Done done) {
  while (!done()) {
    const auto now = Clock::now();
    if (now >= deadline) return false;
    try {
      if (ping_outstanding_ && !awaiting_caps_ && now - ping_sent_at_ >= dut_.hang_timeout()) {
        restart(RestartCause::kHung, "the DUT hung: no answer to a PING in " + std::to_string(dut_.hang_timeout().count()) + " ms");
        continue;
      }
      // Ask when the DUT has gone quiet, or when a newer frame than one still
      // unanswered has come back (the older one is likely lost).
      const bool overtaken = !outstanding_.empty() && static_cast<std::int64_t>(*outstanding_.begin()) < last_pose_frame_;
      if (!ping_outstanding_ && !awaiting_caps_ && !outstanding_.empty() &&
          (overtaken || now - last_activity_ >= dut_.stall_interval()))
        ping();
      auto m = wire().receive(std::min(deadline, now + dut_.stall_interval()));
      if (m) {
        last_activity_ = Clock::now();
        handle(*m);
      }
      if (dut_restarted_ && !awaiting_caps_) restart_reported();
    } catch (const app::Error& e) {
      if (awaiting_caps_) throw RunAborted{std::string("the DUT did not start: ") + e.what()};
      restart(RestartCause::kCrashed, std::string("the DUT crashed or closed the link: ") + e.what());
    }
  }
  return true;
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

std::uint64_t resident_kib() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::strtoull(line.c_str() + 6, nullptr, 10);
  return 0;
}

void Run::sample_soak(std::uint32_t frames_sent) {
  stats_received_ = false;
  send(encode(MessageType::kStats, {}));
  pump(Clock::now() + std::chrono::seconds(5), [&] { return stats_received_; });
  std::vector<double> latency;
  for (std::uint32_t i = soak_from_; i < frames_sent && i < result_.frames.size(); ++i)
    if (result_.frames[i].latency_us >= 0) latency.push_back(result_.frames[i].latency_us);
  const LatencySummary l = summarise(latency);
  SoakSample s;
  s.frames = frames_sent;
  s.seconds = since_start_us() / 1e6;
  s.host_rss_kib = resident_kib();
  s.dut_rss_kib = result_.dut_stats ? result_.dut_stats->resident_kib : 0;
  s.latency_p50_us = l.p50;
  s.latency_p99_us = l.p99;
  result_.soak.push_back(s);
  soak_from_ = frames_sent;
}

void Run::send_frame(std::uint32_t index, const app::GrayImage& image, const PlannedFault* fault) {
  const auto start = Clock::now();
  FrameRecord& record = result_.frames[index];
  const std::size_t total = image.pixels.size();
  const std::size_t per_message = link::frame_fragment_pixels(max_payload_);
  std::vector<std::vector<std::byte>> messages;
  std::vector<std::byte> payload(max_payload_);
  const auto host_time = static_cast<std::uint64_t>(since_start_us());
  for (std::size_t at = 0; at < total; at += per_message) {
    const std::size_t n = std::min(per_message, total - at);
    const link::FrameFragment f{index, host_time, static_cast<std::uint16_t>(image.width), static_cast<std::uint16_t>(image.height),
                                static_cast<std::uint32_t>(at), static_cast<std::uint32_t>(total),
                                std::as_bytes(std::span(image.pixels).subspan(at, n))};
    messages.push_back(encode(MessageType::kFrame, std::span(payload.data(), link::encode(f, payload))));
  }
  codec_seconds_ += std::chrono::duration<double>(Clock::now() - start).count();
  record.sent_us = since_start_us();
  record.run = run_id_ - 1;
  outstanding_.insert(index);
  newest_sent_ = index;
  result_.pixel_bytes_sent += total;
  record.pixel_bytes = static_cast<std::uint32_t>(total);
  const std::uint64_t before = wire().bytes_sent();
  std::size_t flip_message = messages.size();
  std::vector<std::uint64_t> flip_positions;
  if (fault != nullptr) {
    InjectedFault& injected = result_.faults[static_cast<std::size_t>(record.fault)];
    const auto pick = static_cast<std::size_t>(rng_.next_u64() % messages.size());
    switch (fault->kind) {
      case FaultKind::kDrop: injected.detail = "none of its " + std::to_string(messages.size()) + " messages sent"; break;
      case FaultKind::kDuplicate: injected.detail = "its " + std::to_string(messages.size()) + " messages sent twice"; break;
      case FaultKind::kReorder: injected.detail = "sent after frame " + std::to_string(index + 1); break;
      case FaultKind::kCorrupt: {
        auto& m = messages[pick];
        const std::size_t at = link::kHeaderBytes + rng_.next_u64() % (m.size() - link::kHeaderBytes - link::kTrailerBytes);
        const auto x = static_cast<std::uint8_t>(1 + rng_.next_u64() % 255);
        m[at] ^= std::byte{x};
        injected.detail = "message " + std::to_string(pick) + " of " + std::to_string(messages.size()) + ": byte " +
                          std::to_string(at) + " xor " + std::to_string(x);
        break;
      }
      case FaultKind::kBitflip: {
        flip_message = pick;
        const std::size_t bits = 1 + rng_.next_u64() % 3;
        std::vector<std::uint64_t> positions;
        const std::uint64_t span = wire().wire_size(messages[pick]) * 8;
        injected.detail = "message " + std::to_string(pick) + " of " + std::to_string(messages.size()) + ": wire bits";
        for (std::size_t i = 0; i < bits; ++i) {
          positions.push_back(rng_.next_u64() % span);
          injected.detail += " " + std::to_string(positions.back());
        }
        flip_positions = positions;  // armed just before that message goes, below
        break;
      }
      case FaultKind::kRestart: injected.detail = "the DUT stopped and started again before the frame"; break;
      default: break;  // a rig fault: done before the frame (inject)
    }
  }
  const bool drop = fault != nullptr && fault->kind == FaultKind::kDrop;
  const bool reorder = fault != nullptr && fault->kind == FaultKind::kReorder;
  std::vector<std::vector<std::byte>> held_before = std::move(held_);
  held_.clear();
  const std::uint32_t held_before_frame = held_frame_;
  held_frame_ = link::kNoFrame;
  if (reorder) {
    held_ = std::move(messages);
    held_frame_ = index;
  } else if (!drop) {
    const int copies = fault != nullptr && fault->kind == FaultKind::kDuplicate ? 2 : 1;
    for (int c = 0; c < copies; ++c) {
      for (std::size_t i = 0; i < messages.size(); ++i) {
        if (i == flip_message && c == 0) wire().flip_bits_on_next_send(flip_positions);
        send(messages[i]);
      }
    }
  }
  record.wire_bytes += wire().bytes_sent() - before;
  // A frame held back by a reorder goes after this one.
  if (!held_before.empty()) {
    const std::uint64_t held_start = wire().bytes_sent();
    for (const auto& m : held_before) send(m);
    result_.frames[held_before_frame].wire_bytes += wire().bytes_sent() - held_start;
  }
}

void Run::judge_faults() {
  const auto clean_pose_after = [&](std::uint32_t after) -> std::string {
    for (std::uint32_t j = after + 1; j < result_.frames.size(); ++j) {
      const FrameRecord& r = result_.frames[j];
      // Frames of other faults, frames never sent, and frames a planned
      // restart took are not evidence either way.
      const bool planned_loss = r.fate == Fate::kLostInRestart && r.reason.rfind("a planned restart", 0) == 0;
      if (r.fault >= 0 || r.fate == Fate::kNotSent || r.sent_us < 0 || planned_loss) continue;
      if (r.fate == Fate::kPose && r.reference == 1) return "";
      return "frame " + std::to_string(j) + ", the next unfaulted one: " + fate_name(r.fate) +
             (r.fate == Fate::kPose ? " not matching the reference" : "");
    }
    return "";  // no later frame to judge by
  };
  for (InjectedFault& f : result_.faults) {
    const FrameRecord& r = result_.frames[f.frame];
    const std::string fate = std::string(fate_name(r.fate)) + (r.reason.empty() ? "" : " (" + r.reason + ")");
    std::uint32_t last_affected = f.frame;
    switch (f.kind) {
      case FaultKind::kDrop:
      case FaultKind::kCorrupt:
      case FaultKind::kBitflip:
        f.detected = r.fate == Fate::kDroppedByLink || r.fate == Fate::kDroppedByDut || r.fate == Fate::kLostInRestart;
        f.evidence = "frame " + std::to_string(f.frame) + ": " + fate;
        // Bits flipped on a delimiter can take the next message with them.
        if (f.kind == FaultKind::kBitflip) last_affected = f.frame + 1;
        break;
      case FaultKind::kDuplicate:
        // A restart that took the frame before it was answered leaves nothing to tell.
        f.detected = (r.repeats >= 1 && r.fate == Fate::kPose) || r.fate == Fate::kLostInRestart;
        f.evidence = "frame " + std::to_string(f.frame) + ": " + fate + ", the DUT reported " + std::to_string(r.repeats) +
                     " repeat(s) and answered it once";
        break;
      case FaultKind::kReorder: {
        const FrameRecord& next = result_.frames[f.frame + 1];
        f.detected = r.fate == Fate::kSkippedByDut && next.fate == Fate::kPose;
        f.evidence = "frame " + std::to_string(f.frame) + ": " + fate + "; frame " + std::to_string(f.frame + 1) + ": " + fate_name(next.fate);
        last_affected = f.frame + 1;
        break;
      }
      case FaultKind::kCameraError:
      case FaultKind::kCameraDrop:
      case FaultKind::kSequenceWrap:
      case FaultKind::kCameraDisconnect:
      case FaultKind::kModuleReload:
      case FaultKind::kUsbStall:
      case FaultKind::kUsbUnplug:
      case FaultKind::kUsbTimeout:
      case FaultKind::kBoardKill:
      case FaultKind::kUsbCorrupt: {
        // The rig's own checks detected it (INJECTED); tracking again means a
        // pose matching the reference after the fault's end, within 1 s.
        if (!f.answered) f.evidence = f.evidence.empty() ? "the rig never answered" : f.evidence;
        last_affected = f.frame > 0 ? f.frame - 1 : 0;
        const std::string problem = clean_pose_after(last_affected);
        double first = -1;
        for (const FrameRecord& p : result_.frames)
          if (p.fate == Fate::kPose && p.reference == 1 && f.ended_us >= 0 && p.sent_us + p.latency_us >= f.ended_us) {
            const double at = p.sent_us + p.latency_us;
            if (first < 0 || at < first) first = at;
          }
        if (first >= 0) f.recovery_ms = (first - f.ended_us) / 1000.0;
        f.recovered = problem.empty() && f.answered && f.recovery_ms >= 0 && f.recovery_ms <= 1000.0;
        if (!problem.empty()) f.evidence += "; not recovered: " + problem;
        else if (f.recovery_ms > 1000.0) f.evidence += "; tracking again only after " + std::to_string(f.recovery_ms) + " ms";
        else if (f.recovery_ms >= 0) f.evidence += "; tracking again " + std::to_string(static_cast<int>(f.recovery_ms)) + " ms after";
        continue;
      }
      case FaultKind::kRestart:
        f.detected = r.run > 0;  // the DUT came back with a new run
        f.evidence = "the DUT restarted before frame " + std::to_string(f.frame) + " (run " + std::to_string(r.run) + "); frame " +
                     std::to_string(f.frame) + ": " + fate;
        last_affected = f.frame > 0 ? f.frame - 1 : 0;
        if (f.frame == 0) {
          f.recovered = r.fate == Fate::kPose && r.reference == 1;
          continue;
        }
        break;
    }
    const std::string problem = clean_pose_after(last_affected);
    f.recovered = problem.empty();
    if (!problem.empty()) f.evidence += "; not recovered: " + problem;
  }
}

void Run::execute() {
  const std::filesystem::path dir(config_.sequence_dir);
  const std::string frames_path = (dir / "frames.y4m").string();
  auto frames = app::open_frames(frames_path);
  Pose initial;
  if (config_.init) {
    initial = *config_.init;
  } else {
    const std::string gt = (dir / "gt.csv").string();
    if (!std::filesystem::exists(gt)) throw app::Error(config_.sequence_dir + ": no gt.csv to start from; give --init");
    const auto truth = app::read_pose_csv(gt);
    if (truth.empty()) throw app::Error(gt + ": no ground-truth rows to start from; give --init");
    initial = Pose{static_cast<float>(truth[0].x), static_cast<float>(truth[0].y), static_cast<float>(truth[0].theta_deg),
                   static_cast<std::uint16_t>(truth[0].depth)};
  }
  last_pose_ = initial;
  const std::uint32_t per_loop = config_.max_frames;
  const std::uint64_t total64 = std::uint64_t{per_loop} * std::max<std::uint32_t>(config_.loops, 1);
  if (total64 > 0xFFFFFFFEull) throw app::Error("--soak: too many frames in all");
  const auto total = static_cast<std::uint32_t>(total64);
  result_.frames_total = total;
  result_.frames.resize(total);
  for (std::uint32_t i = 0; i < total; ++i) result_.frames[i].frame = i;
  for (const PlannedFault& f : config_.faults.faults) {
    if (f.frame >= total) continue;
    result_.frames[f.frame].fault = static_cast<int>(result_.faults.size());
    result_.faults.push_back({f.frame, f.kind, "", false, false, ""});
  }
  try {
    dut_.start();
  } catch (const app::Error& e) {
    throw RunAborted{std::string("the DUT did not start: ") + e.what()};
  }
  result_.dut_description = dut_.description();
  t0_ = Clock::now();
  handshake(initial, 0);
  auto last_progress = Clock::now();
  app::GrayImage image;
  const bool soak = config_.loops > 1;
  for (std::uint32_t k = 0; k < total; ++k) {
    if (k > 0 && k % per_loop == 0) frames = app::open_frames(frames_path);  // the next loop of a soak
    if (!frames->next(image)) throw RunAborted{frames_path + ": ended at frame " + std::to_string(k % per_loop)};
    if (soak && k > 0 && k % config_.soak_window == 0) sample_soak(k);
    if (image.width > 0xFFFF || image.height > 0xFFFF || image.pixels.size() > caps_.max_frame_bytes)
      throw RunAborted{"frame " + std::to_string(k) + " is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                       "; the DUT takes frames of at most " + std::to_string(caps_.max_frame_bytes) + " pixels"};
    const PlannedFault* fault = config_.faults.at(k);
    if (fault != nullptr && fault->kind == FaultKind::kRestart) {
      next_frame_ = k;
      restart(RestartCause::kPlanned, "a planned restart before frame " + std::to_string(k));
    }
    next_frame_ = k;
    const auto room = [&] { return outstanding_.size() - (held_.empty() ? 0 : 1) < window_; };
    if (config_.rate_fps > 0) {
      const auto due = t0_ + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(k / config_.rate_fps));
      pump(due, [] { return false; });
      if (!room()) {
        result_.frames[k].fate = Fate::kNotSent;
        result_.frames[k].reason = "the DUT was busy at the frame's time";
        if (config_.on_resolved) config_.on_resolved(result_.frames[k]);
        continue;
      }
    } else {
      pump(Clock::time_point::max(), room);
    }
    next_frame_ = k;
    if (fault != nullptr && is_rig_fault(fault->kind)) inject(k, *fault);
    next_frame_ = k;
    send_frame(k, image, fault);
    images_[k] = std::move(image);
    image = app::GrayImage{};
    pump(Clock::now(), [] { return false; });
    if (config_.progress && Clock::now() - last_progress >= std::chrono::seconds(1)) {
      config_.progress(k + 1 - static_cast<std::uint32_t>(outstanding_.size()), total);
      last_progress = Clock::now();
    }
  }
  next_frame_ = total;
  if (!held_.empty()) {  // cannot happen (no reorder on the last frame), but never leave one unsent
    for (const auto& m : held_) send(m);
    held_.clear();
    held_frame_ = link::kNoFrame;
  }
  pump(Clock::time_point::max(), [&] { return outstanding_.empty(); });
  // Rig faults that end on their own time (a sequence wrap) answer by now.
  pump(Clock::now() + dut_.hang_timeout(), [&] {
    for (const InjectedFault& f : result_.faults)
      if (is_rig_fault(f.kind) && !f.answered && result_.frames[f.frame].sent_us >= 0) return false;
    return true;
  });
  if (soak) sample_soak(total);
  // The DUT's counters, then goodbye; neither is worth waiting long for.
  send(encode(MessageType::kStats, {}));
  pump(Clock::now() + std::chrono::seconds(5), [&] { return stats_received_; });
  std::byte b[link::kByeBytes];
  send(encode(MessageType::kBye, std::span(b, link::encode(link::Bye{0, total - 1}, b))));
  pump(Clock::now() + std::chrono::seconds(5), [&] { return bye_received_; });
  if (config_.progress) config_.progress(total, total);
  result_.host_codec_seconds = codec_seconds_ + wire().framing_seconds();
}

}  // namespace

RunResult run_hil(const RunConfig& config, DutDriver& dut) {
  RunResult result;
  const auto start = Clock::now();
  Run run(config, dut, result);
  try {
    run.execute();
  } catch (const RunAborted& a) {
    result.error = a.why;
  }
  run.judge_faults();
  dut.stop();
  for (const FrameRecord& r : result.frames)
    if (r.fate == Fate::kPending && r.sent_us >= 0) ++result.unaccounted;
  for (const FrameRecord& r : result.frames) result.wire_bytes += r.wire_bytes;
  result.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return result;
}

}  // namespace gabarit::hil
