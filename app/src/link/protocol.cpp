#include "gabarit/link/protocol.hpp"

#include <cstring>

#include "gabarit/crc32.hpp"

namespace gabarit::link {
namespace {

// Little-endian field writer and reader over a fixed span. Writes past the
// end set `ok` false (encode then returns 0); reads past the end read zeros
// and set `ok` false (decode returns kTruncated).
class Writer {
 public:
  explicit Writer(std::span<std::byte> out) noexcept : out_(out) {}
  void u8(std::uint8_t v) noexcept { put(v, 1); }
  void u16(std::uint16_t v) noexcept { put(v, 2); }
  void u32(std::uint32_t v) noexcept { put(v, 4); }
  void u64(std::uint64_t v) noexcept { put(v, 8); }
  void f32(float v) noexcept {
    std::uint32_t bits;
    std::memcpy(&bits, &v, 4);
    u32(bits);
  }
  void bytes(const void* data, std::size_t n) noexcept {
    if (!ok_ || n > out_.size() - at_) {
      ok_ = false;
      return;
    }
    if (n != 0) std::memcpy(out_.data() + at_, data, n);
    at_ += n;
  }
  std::size_t done() const noexcept { return ok_ ? at_ : 0; }

 private:
  void put(std::uint64_t v, std::size_t n) noexcept {
    if (!ok_ || n > out_.size() - at_) {
      ok_ = false;
      return;
    }
    for (std::size_t i = 0; i < n; ++i) out_[at_ + i] = static_cast<std::byte>((v >> (8 * i)) & 0xFFu);
    at_ += n;
  }
  std::span<std::byte> out_;
  std::size_t at_ = 0;
  bool ok_ = true;
};

class Reader {
 public:
  explicit Reader(std::span<const std::byte> in) noexcept : in_(in) {}
  std::uint8_t u8() noexcept { return static_cast<std::uint8_t>(get(1)); }
  std::uint16_t u16() noexcept { return static_cast<std::uint16_t>(get(2)); }
  std::uint32_t u32() noexcept { return static_cast<std::uint32_t>(get(4)); }
  std::uint64_t u64() noexcept { return get(8); }
  float f32() noexcept {
    const std::uint32_t bits = u32();
    float v;
    std::memcpy(&v, &bits, 4);
    return v;
  }
  template <std::size_t N>
  void text(char (&field)[N]) noexcept {
    for (std::size_t i = 0; i < N; ++i) field[i] = static_cast<char>(u8());
    field[N - 1] = '\0';  // whatever was sent, the field ends
  }
  std::span<const std::byte> rest() const noexcept { return in_.subspan(at_ < in_.size() ? at_ : in_.size()); }
  Status status() const noexcept { return ok_ ? Status::kOk : Status::kTruncated; }

 private:
  std::uint64_t get(std::size_t n) noexcept {
    if (!ok_ || n > in_.size() - at_) {
      ok_ = false;
      return 0;
    }
    std::uint64_t v = 0;
    for (std::size_t i = 0; i < n; ++i) v |= std::uint64_t{static_cast<std::uint8_t>(in_[at_ + i])} << (8 * i);
    at_ += n;
    return v;
  }
  std::span<const std::byte> in_;
  std::size_t at_ = 0;
  bool ok_ = true;
};

void put_pose(Writer& w, const Pose& p) noexcept {
  w.f32(p.x);
  w.f32(p.y);
  w.f32(p.theta_deg);
  w.u16(p.depth);
}

Pose get_pose(Reader& r) noexcept {
  Pose p;
  p.x = r.f32();
  p.y = r.f32();
  p.theta_deg = r.f32();
  p.depth = r.u16();
  return p;
}

}  // namespace

const char* message_type_name(MessageType type) noexcept {
  switch (type) {
    case MessageType::kHello: return "hello";
    case MessageType::kCaps: return "caps";
    case MessageType::kFrame: return "frame";
    case MessageType::kPose: return "pose";
    case MessageType::kEvent: return "event";
    case MessageType::kPing: return "ping";
    case MessageType::kPong: return "pong";
    case MessageType::kStats: return "stats";
    case MessageType::kBye: return "bye";
    case MessageType::kInject: return "inject";
    case MessageType::kInjected: return "injected";
    case MessageType::kNote: return "note";
  }
  return "unknown";
}

std::uint32_t frame_crc(const ImageView& frame) noexcept {
  std::uint32_t crc = 0;
  for (std::uint32_t y = 0; y < frame.height; ++y)
    crc = crc32c_update(crc, std::as_bytes(std::span(frame.pixels + std::size_t{y} * frame.stride, frame.width)));
  return crc;
}

Caps make_caps(const DeviceDescription& d) noexcept {
  Caps caps;
  caps.max_payload = d.max_payload;
  caps.table_crc = d.table_crc;
  caps.table_bytes = d.table_bytes;
  caps.clock_hz = d.clock_hz;
  caps.frame_slots = d.frame_slots;
  caps.max_frame_bytes = d.max_frame_bytes;
  caps.mode = d.mode;
  set_text(caps.kind, d.kind);
  set_text(caps.board, d.board);
  set_text(caps.firmware, d.software);
  caps.device_id = d.device_id != 0 ? d.device_id : crc32(std::as_bytes(std::span(d.board, std::strlen(d.board))));
  return caps;
}

const char* refusal_name(Refusal refusal) noexcept {
  switch (refusal) {
    case Refusal::kNone: return "none";
    case Refusal::kProtocolVersion: return "protocol-version";
    case Refusal::kTableMismatch: return "table-mismatch";
    case Refusal::kNoTable: return "no-valid-table";
    case Refusal::kBadPose: return "initial-pose-rejected";
  }
  return "unknown";
}

const char* event_kind_name(EventKind kind) noexcept {
  switch (kind) {
    case EventKind::kDropped: return "dropped";
    case EventKind::kSkipped: return "skipped";
    case EventKind::kError: return "error";
    case EventKind::kRestart: return "restart";
    case EventKind::kDuplicate: return "duplicate";
  }
  return "unknown";
}

const char* event_reason_name(EventReason reason) noexcept {
  switch (reason) {
    case EventReason::kNone: return "none";
    case EventReason::kIncomplete: return "incomplete";
    case EventReason::kQueueFull: return "queue-full";
    case EventReason::kOutOfOrder: return "out-of-order";
    case EventReason::kTooLarge: return "too-large";
    case EventReason::kNotStarted: return "not-started";
    case EventReason::kTracking: return "tracking-failed";
    case EventReason::kHardware: return "hardware-mismatch";
    case EventReason::kBoot: return "boot";
    case EventReason::kRepeat: return "repeat";
    case EventReason::kCameraTimeout: return "camera-timeout";
    case EventReason::kSameAsPrevious: return "same-as-previous-frame";
    case EventReason::kCameraError: return "camera-error-buffer";
    case EventReason::kCameraGap: return "camera-sequence-gap";
    case EventReason::kCameraLost: return "camera-lost";
    case EventReason::kCameraBack: return "camera-reopened";
    case EventReason::kSequenceWrap: return "camera-sequence-wrap";
  }
  return "unknown";
}

const char* inject_outcome_name(InjectOutcome outcome) noexcept {
  switch (outcome) {
    case InjectOutcome::kDetected: return "detected";
    case InjectOutcome::kUnsupported: return "unsupported";
    case InjectOutcome::kFailed: return "failed";
    case InjectOutcome::kUndetected: return "undetected";
  }
  return "unknown";
}

Status encode_message(const Header& header, std::span<const std::byte> payload, std::span<std::byte> out,
                      std::size_t& written) noexcept {
  written = 0;
  if (payload.size() > kMaxPayload) return Status::kInvalidArgument;
  if (out.size() < message_bytes(payload.size())) return Status::kBufferTooSmall;
  Writer w(out);
  w.u16(kMagic);
  w.u8(header.version);
  w.u8(static_cast<std::uint8_t>(header.type));
  w.u16(header.flags);
  w.u16(static_cast<std::uint16_t>(payload.size()));
  w.u32(header.seq);
  w.u32(header.ack);
  w.u16(header.credits);
  w.u16(0);
  w.bytes(payload.data(), payload.size());
  const std::size_t body = kHeaderBytes + payload.size();
  w.u32(crc32c(out.first(body)));
  written = w.done();
  return written == message_bytes(payload.size()) ? Status::kOk : Status::kBufferTooSmall;
}

Status decode_message(std::span<const std::byte> in, Header& header, std::span<const std::byte>& payload) noexcept {
  payload = {};
  if (in.size() < kHeaderBytes + kTrailerBytes) return Status::kTruncated;
  Reader r(in);
  if (r.u16() != kMagic) return Status::kBadMagic;
  header.version = r.u8();
  if (header.version != kVersion) return Status::kUnsupportedVersion;
  header.type = static_cast<MessageType>(r.u8());
  header.flags = r.u16();
  header.payload_bytes = r.u16();
  header.seq = r.u32();
  header.ack = r.u32();
  header.credits = r.u16();
  (void)r.u16();
  if (message_bytes(header.payload_bytes) != in.size()) return Status::kSizeMismatch;
  const std::size_t body = kHeaderBytes + header.payload_bytes;
  Reader trailer(in.subspan(body));
  if (trailer.u32() != crc32c(in.first(body))) return Status::kBadChecksum;
  payload = in.subspan(kHeaderBytes, header.payload_bytes);
  return Status::kOk;
}

std::size_t encode(const Hello& m, std::span<std::byte> out) noexcept {
  Writer w(out);
  w.u16(m.version);
  w.u16(m.max_payload);
  w.u32(m.table_crc);
  w.u32(m.run_id);
  put_pose(w, m.initial);
  w.u16(0);
  w.u32(m.first_frame);
  return w.done();
}

Status decode(std::span<const std::byte> payload, Hello& m) noexcept {
  Reader r(payload);
  m.version = r.u16();
  m.max_payload = r.u16();
  m.table_crc = r.u32();
  m.run_id = r.u32();
  m.initial = get_pose(r);
  (void)r.u16();
  m.first_frame = r.u32();
  GABARIT_TRY(r.status());
  if (m.max_payload < kMinPayload) return Status::kBadHeaderField;
  return Status::kOk;
}

std::size_t encode(const Caps& m, std::span<std::byte> out) noexcept {
  Writer w(out);
  w.u16(m.version);
  w.u16(m.max_payload);
  w.u32(m.table_crc);
  w.u32(m.table_bytes);
  w.u32(m.clock_hz);
  w.u32(m.frame_slots);
  w.u32(m.max_frame_bytes);
  w.u32(m.mode);
  w.u32(m.run_id);
  w.u16(static_cast<std::uint16_t>(m.refusal));
  w.u16(m.boot_count);
  w.u64(m.device_id);
  w.bytes(m.kind, sizeof m.kind);
  w.bytes(m.board, sizeof m.board);
  w.bytes(m.firmware, sizeof m.firmware);
  return w.done();
}

Status decode(std::span<const std::byte> payload, Caps& m) noexcept {
  Reader r(payload);
  m.version = r.u16();
  m.max_payload = r.u16();
  m.table_crc = r.u32();
  m.table_bytes = r.u32();
  m.clock_hz = r.u32();
  m.frame_slots = r.u32();
  m.max_frame_bytes = r.u32();
  m.mode = r.u32();
  m.run_id = r.u32();
  m.refusal = static_cast<Refusal>(r.u16());
  m.boot_count = r.u16();
  m.device_id = r.u64();
  r.text(m.kind);
  r.text(m.board);
  r.text(m.firmware);
  GABARIT_TRY(r.status());
  if (m.refusal == Refusal::kNone && (m.max_payload < kMinPayload || m.frame_slots == 0 || m.clock_hz == 0))
    return Status::kBadHeaderField;
  return Status::kOk;
}

std::size_t encode(const FrameFragment& m, std::span<std::byte> out) noexcept {
  Writer w(out);
  w.u32(m.frame_id);
  w.u64(m.host_time_us);
  w.u16(m.width);
  w.u16(m.height);
  w.u32(m.offset);
  w.u32(m.total_bytes);
  w.bytes(m.pixels.data(), m.pixels.size());
  return w.done();
}

Status decode(std::span<const std::byte> payload, FrameFragment& m) noexcept {
  Reader r(payload);
  m.frame_id = r.u32();
  m.host_time_us = r.u64();
  m.width = r.u16();
  m.height = r.u16();
  m.offset = r.u32();
  m.total_bytes = r.u32();
  GABARIT_TRY(r.status());
  m.pixels = r.rest();
  // The fragment lies within a frame of width x height pixels.
  const std::uint64_t total = std::uint64_t{m.width} * m.height;
  if (total == 0 || m.total_bytes != total || m.frame_id == kNoFrame) return Status::kBadHeaderField;
  if (m.offset > total || m.pixels.size() > total - m.offset || m.pixels.empty()) return Status::kBadHeaderField;
  return Status::kOk;
}

std::size_t encode(const PoseReport& m, std::span<std::byte> out) noexcept {
  Writer w(out);
  w.u32(m.frame_id);
  put_pose(w, m.pose);
  w.u8(m.state);
  w.u8(m.confidence);
  w.u8(m.flags);
  w.u8(0);
  w.u32(m.best_votes);
  w.f32(m.score);
  w.u32(m.features);
  w.u32(m.features_dropped);
  w.u64(m.votes);
  w.u32(m.frame_crc);
  w.u64(m.received);
  w.u64(m.done);
  w.u64(m.cycles);
  w.u16(0);
  w.u64(m.captured);
  w.u64(m.strobed);
  return w.done();
}

Status decode(std::span<const std::byte> payload, PoseReport& m) noexcept {
  Reader r(payload);
  m.frame_id = r.u32();
  m.pose = get_pose(r);
  m.state = r.u8();
  m.confidence = r.u8();
  m.flags = r.u8();
  (void)r.u8();
  m.best_votes = r.u32();
  m.score = r.f32();
  m.features = r.u32();
  m.features_dropped = r.u32();
  m.votes = r.u64();
  m.frame_crc = r.u32();
  m.received = r.u64();
  m.done = r.u64();
  m.cycles = r.u64();
  (void)r.u16();
  GABARIT_TRY(r.status());
  m.captured = m.strobed = 0;
  if (payload.size() >= kPoseBytes) {  // 1.1's stages
    m.captured = r.u64();
    m.strobed = r.u64();
  }
  if (m.state > 3 || m.frame_id == kNoFrame) return Status::kBadHeaderField;  // TrackState, kAmbiguous the last
  return Status::kOk;
}

std::size_t encode(const Event& m, std::span<std::byte> out) noexcept {
  Writer w(out);
  w.u8(static_cast<std::uint8_t>(m.kind));
  w.u8(static_cast<std::uint8_t>(m.reason));
  w.u16(0);
  w.u32(m.frame_id);
  w.u32(m.detail);
  w.u64(m.time);
  return w.done();
}

Status decode(std::span<const std::byte> payload, Event& m) noexcept {
  Reader r(payload);
  const std::uint8_t kind = r.u8();
  const std::uint8_t reason = r.u8();
  (void)r.u16();
  m.frame_id = r.u32();
  m.detail = r.u32();
  m.time = r.u64();
  GABARIT_TRY(r.status());
  if (kind < 1 || kind > 5 || reason > kLastEventReason) return Status::kBadHeaderField;
  m.kind = static_cast<EventKind>(kind);
  m.reason = static_cast<EventReason>(reason);
  return Status::kOk;
}

std::size_t encode(const Ping& m, std::span<std::byte> out) noexcept {
  Writer w(out);
  w.u32(m.token);
  w.u64(m.host_time_us);
  return w.done();
}

Status decode(std::span<const std::byte> payload, Ping& m) noexcept {
  Reader r(payload);
  m.token = r.u32();
  m.host_time_us = r.u64();
  return r.status();
}

std::size_t encode(const Pong& m, std::span<std::byte> out) noexcept {
  Writer w(out);
  w.u32(m.token);
  w.u64(m.host_time_us);
  w.u64(m.dut_time);
  w.u32(m.last_frame);
  w.u32(m.queued);
  w.u32(m.oldest_queued);
  return w.done();
}

Status decode(std::span<const std::byte> payload, Pong& m) noexcept {
  Reader r(payload);
  m.token = r.u32();
  m.host_time_us = r.u64();
  m.dut_time = r.u64();
  m.last_frame = r.u32();
  m.queued = r.u32();
  m.oldest_queued = r.u32();
  return r.status();
}

std::size_t encode(const Stats& m, std::span<std::byte> out) noexcept {
  Writer w(out);
  for (const std::uint32_t v : {m.messages_in, m.bad_crc, m.bad_message, m.unknown_type, m.framing_errors, m.sequence_gaps,
                                m.stale, m.frames_taken, m.frames_tracked, m.frames_dropped, m.frames_skipped, m.messages_out,
                                m.resident_kib})
    w.u32(v);
  return w.done();
}

Status decode(std::span<const std::byte> payload, Stats& m) noexcept {
  Reader r(payload);
  for (std::uint32_t* v : {&m.messages_in, &m.bad_crc, &m.bad_message, &m.unknown_type, &m.framing_errors, &m.sequence_gaps,
                           &m.stale, &m.frames_taken, &m.frames_tracked, &m.frames_dropped, &m.frames_skipped, &m.messages_out})
    *v = r.u32();
  GABARIT_TRY(r.status());
  m.resident_kib = payload.size() >= kStatsBytes ? r.u32() : 0;  // 1.1
  return Status::kOk;
}

std::size_t encode(const Bye& m, std::span<std::byte> out) noexcept {
  Writer w(out);
  w.u32(m.reason);
  w.u32(m.last_frame);
  return w.done();
}

Status decode(std::span<const std::byte> payload, Bye& m) noexcept {
  Reader r(payload);
  m.reason = r.u32();
  m.last_frame = r.u32();
  return r.status();
}


std::size_t encode(const Inject& m, std::span<std::byte> out) noexcept {
  Writer w(out);
  w.u32(m.token);
  w.u8(m.kind);
  w.u8(0);
  w.u16(0);
  return w.done();
}

Status decode(std::span<const std::byte> payload, Inject& m) noexcept {
  Reader r(payload);
  m.token = r.u32();
  m.kind = r.u8();
  return r.status();
}

std::size_t encode(const Injected& m, std::span<std::byte> out) noexcept {
  Writer w(out);
  w.u32(m.token);
  w.u8(m.kind);
  w.u8(static_cast<std::uint8_t>(m.outcome));
  w.u16(m.attempts);
  w.u64(m.started);
  w.u64(m.ended);
  for (const char c : m.evidence) w.u8(static_cast<std::uint8_t>(c));
  return w.done();
}

Status decode(std::span<const std::byte> payload, Injected& m) noexcept {
  Reader r(payload);
  m.token = r.u32();
  m.kind = r.u8();
  const std::uint8_t outcome = r.u8();
  m.attempts = r.u16();
  m.started = r.u64();
  m.ended = r.u64();
  r.text(m.evidence);
  GABARIT_TRY(r.status());
  if (outcome > 3) return Status::kBadHeaderField;
  m.outcome = static_cast<InjectOutcome>(outcome);
  return Status::kOk;
}

std::size_t encode(const Note& m, std::span<std::byte> out) noexcept {
  Writer w(out);
  w.u32(m.frame_id);
  for (const char c : m.text) w.u8(static_cast<std::uint8_t>(c));
  return w.done();
}

Status decode(std::span<const std::byte> payload, Note& m) noexcept {
  Reader r(payload);
  m.frame_id = r.u32();
  r.text(m.text);
  GABARIT_TRY(r.status());
  // Text, then only padding: a console must never be sent control bytes.
  bool padding = false;
  for (const char c : m.text) {
    if (c == '\0') padding = true;
    else if (padding || c < ' ' || c > '~') return Status::kBadHeaderField;
  }
  return Status::kOk;
}

}  // namespace gabarit::link
