// The HIL link protocol, version 1 (docs/hil-protocol.md is its reference:
// every byte, the rules, the sequence of a run). Kernel-grade, like the
// kernel: no heap, no exceptions, fixed buffers; built for the host, the
// Linux boards and Cortex-M, and shared by the harness (hil/) and every
// device under test.
//
// A message is a 20-byte little-endian header, a payload and a CRC-32C over
// both:
//   0  u16 magic 0x4C47 ("GL")     10 ..
//   2  u8  version (1)             12  u32 ack: the last sequence number accepted from the peer
//   3  u8  type (MessageType)      16  u16 credits: frames the sender can still queue
//   4  u16 flags (0; ignored)      18  u16 reserved (0)
//   6  u16 payload bytes           20  payload
//   8  u32 sequence number         20+n u32 CRC-32C of bytes [0, 20+n)
// Byte streams carry messages COBS-encoded, each ended by a zero (cobs.hpp);
// message transports (USB bulk, UDP) carry one message per transfer.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "gabarit/image_view.hpp"
#include "gabarit/pose.hpp"
#include "gabarit/status.hpp"

namespace gabarit::link {

inline constexpr std::uint16_t kMagic = 0x4C47;
inline constexpr std::uint8_t kVersion = 1;
inline constexpr std::size_t kHeaderBytes = 20;
inline constexpr std::size_t kTrailerBytes = 4;
// The protocol's ceiling on a payload; each side advertises its own maximum
// (HELLO, CAPS) and both use the smaller.
inline constexpr std::size_t kMaxPayload = 16384;
// The smallest maximum a side may advertise: every message but FRAME fits it.
inline constexpr std::size_t kMinPayload = 256;

constexpr std::size_t message_bytes(std::size_t payload) noexcept { return kHeaderBytes + payload + kTrailerBytes; }

enum class MessageType : std::uint8_t {
  kHello = 1,  // host -> DUT: start (or restart) a run
  kCaps = 2,   // DUT -> host: what the DUT is and holds (the answer to HELLO)
  kFrame = 3,  // host -> DUT: one fragment of a frame
  kPose = 4,   // DUT -> host: a tracked frame's pose
  kEvent = 5,  // DUT -> host: a frame's other fate, or a DUT event
  kPing = 6,   // host -> DUT
  kPong = 7,   // DUT -> host: the answer, with the DUT's view of the run
  kStats = 8,  // host -> DUT (empty: a request); DUT -> host: the counters
  kBye = 9,    // host -> DUT: end of run; DUT -> host: the acknowledgement
  kInject = 10,    // host -> DUT: inject a fault on the DUT's side (a test rig's DUT: the virtual board)
  kInjected = 11,  // DUT -> host: that fault's outcome and evidence
  kNote = 12,      // host -> DUT: a line for the DUT's console (a lab that reads the console sees the host's verdicts)
};
const char* message_type_name(MessageType type) noexcept;  // "hello", ..., "unknown"

struct Header {
  MessageType type = MessageType::kPing;
  std::uint8_t version = kVersion;
  std::uint16_t flags = 0;
  std::uint16_t payload_bytes = 0;  // set by encode_message
  std::uint32_t seq = 0;
  std::uint32_t ack = 0;
  std::uint16_t credits = 0;
};

// a is after b in sequence-number space (RFC 1982 arithmetic on 32 bits):
// true for a = b + 1 .. b + 2^31 - 1, whatever the wrap.
constexpr bool seq_after(std::uint32_t a, std::uint32_t b) noexcept {
  return static_cast<std::int32_t>(a - b) > 0;
}

// One end's sequence numbers, in one place for every sender and receiver
// (the device endpoint, the harness, the board's link, the rig's relay): the
// header of each message it sends (its own next number, and as the ack the
// last number it accepted from the peer), and what it accepts of the peer's.
class Sequencer {
 public:
  explicit constexpr Sequencer(std::uint32_t first = 0) noexcept : next_(first) {}
  // The header of our next message (its number taken).
  Header stamp(MessageType type, std::uint16_t credits = 0) noexcept {
    Header h;
    h.type = type;
    h.seq = next_++;
    h.ack = peer_;
    h.credits = credits;
    return h;
  }
  // A peer's message numbered `seq`: accepted (it becomes our ack) if it is
  // the first or after every one accepted before, `skipped` then counting the
  // numbers between; false for a duplicate or a late one.
  bool accept(std::uint32_t seq, std::uint32_t& skipped) noexcept {
    skipped = 0;
    if (any_ && !seq_after(seq, peer_)) return false;
    if (any_) skipped = seq - peer_ - 1;
    peer_ = seq;
    any_ = true;
    return true;
  }
  // Go-back-N takes only the number right after the last accepted (or the first).
  bool in_order(std::uint32_t seq) const noexcept { return !any_ || seq == peer_ + 1; }
  // A restarted peer numbers its messages from its start again.
  void forget_peer() noexcept { any_ = false; }
  std::uint32_t ack() const noexcept { return peer_; }

 private:
  std::uint32_t next_;
  std::uint32_t peer_ = 0;
  bool any_ = false;
};

// Header, payload and CRC into `out` (message_bytes(payload.size()) bytes).
// kInvalidArgument for a payload over kMaxPayload, kBufferTooSmall for a short `out`.
Status encode_message(const Header& header, std::span<const std::byte> payload, std::span<std::byte> out,
                      std::size_t& written) noexcept;

// Checks a received message, in this order, each with its code: shorter than
// a header and trailer (kTruncated), magic (kBadMagic), version
// (kUnsupportedVersion), payload length against the bytes received
// (kSizeMismatch), CRC-32C (kBadChecksum). A message of an unknown type
// decodes (its type is then not a MessageType value): the caller counts it
// and skips it. `payload` views `in`.
Status decode_message(std::span<const std::byte> in, Header& header, std::span<const std::byte>& payload) noexcept;

// ---- Payloads. Each encodes into a caller's buffer (returns the bytes
// written, 0 if the buffer is too short) and decodes with a Status:
// kTruncated when the payload is shorter than the message's fixed part,
// kBadHeaderField for a field the protocol forbids. Longer payloads decode
// (a newer minor version may append fields).

inline constexpr std::uint32_t kNoFrame = 0xFFFFFFFFu;

// Tracker modes a DUT runs (CAPS.mode bits), so the harness's reference
// runs the same loop: the session profile's choices (app/session_profile.hpp,
// mode_bits and profile_from_mode_bits, the one place that writes and reads them).
inline constexpr std::uint32_t kModeSession = 1u << 0;       // TrackingSession defaults; else the thesis's loop
inline constexpr std::uint32_t kModeSharedSearch = 1u << 1;  // the recovery search detects once per frame
inline constexpr std::uint32_t kModeFocusStack = 1u << 2;    // depth by intensity with the table's model images
// Protocol 1.2: the rest of the profile.
inline constexpr std::uint32_t kModeMotionFilter = 1u << 3;        // the thesis's loop with the motion filter added
inline constexpr std::uint32_t kModeRefine = 1u << 4;              // ... with sub-cell refinement added
inline constexpr std::uint32_t kModeRecover = 1u << 5;             // ... with recovery added
inline constexpr std::uint32_t kModeRecoveryDetection = 1u << 6;   // re-acquisition by detection over the frame
inline constexpr std::uint32_t kModeRecoveryParticles = 1u << 7;   // re-acquisition by a particle filter
inline constexpr std::uint32_t kModeSubCellAlignment = 1u << 8;    // sub-cell by feature alignment, not the parabola
inline constexpr std::uint32_t kModeNoVerify = 1u << 9;            // the session without vote-then-verify
// Protocol 1.3: the particle tracker (chapter 3) instead of the session; the
// other bits are then 0 but these and kModeTuned. Its measure, resolved for
// the device's table, in the two bits at kModeParticleMeasureShift
// (app::ParticleMeasureKind: 1 edges, 2 stencil, 3 intensity).
inline constexpr std::uint32_t kModeParticleTracker = 1u << 10;
inline constexpr std::uint32_t kModeParticleMeasureShift = 11;
inline constexpr std::uint32_t kModeParticleMeasureMask = 3u << kModeParticleMeasureShift;
inline constexpr std::uint32_t kModeTuned = 1u << 31;              // numbers other than the defaults: not mirrored

struct Hello {
  std::uint16_t version = kVersion;
  std::uint16_t max_payload = kMaxPayload;
  std::uint32_t table_crc = 0;  // the host's table (CRC-32 of its file); 0: any
  std::uint32_t run_id = 0;     // echoed in CAPS; a new one at each (re)start
  Pose initial;                 // the pose before the first frame
  std::uint32_t first_frame = 0;
};
inline constexpr std::size_t kHelloBytes = 32;

// Why a DUT refuses a run (CAPS.refusal).
enum class Refusal : std::uint16_t { kNone = 0, kProtocolVersion = 1, kTableMismatch = 2, kNoTable = 3, kBadPose = 4 };
const char* refusal_name(Refusal refusal) noexcept;

struct Caps {
  std::uint16_t version = kVersion;
  std::uint16_t max_payload = 0;
  std::uint32_t table_crc = 0;     // CRC-32 of the DUT's table file
  std::uint32_t table_bytes = 0;
  std::uint32_t clock_hz = 0;      // the unit of the DUT's timestamps and cycles
  std::uint32_t frame_slots = 0;   // frames it can queue (the credit window)
  std::uint32_t max_frame_bytes = 0;
  std::uint32_t mode = 0;          // kMode* bits
  std::uint32_t run_id = 0;        // the HELLO's
  Refusal refusal = Refusal::kNone;
  std::uint16_t boot_count = 0;    // starts since power-on (0 after a cold start)
  std::uint64_t device_id = 0;     // stable per device (and per build for simulators)
  char kind[16] = {};              // "inprocess", "verilator", "cortex-m", ...; NUL-padded
  char board[32] = {};             // e.g. "mps2-an500 (Cortex-M7)"
  char firmware[16] = {};          // the DUT's software version
};
inline constexpr std::size_t kCapsBytes = 44 + 16 + 32 + 16;

// One fragment of a frame: pixels [offset, offset + n) of total_bytes
// (width x height, 8-bit luma, row-major).
struct FrameFragment {
  std::uint32_t frame_id = 0;
  std::uint64_t host_time_us = 0;
  std::uint16_t width = 0, height = 0;
  std::uint32_t offset = 0;
  std::uint32_t total_bytes = 0;
  std::span<const std::byte> pixels;  // views the payload
};
inline constexpr std::size_t kFrameFixedBytes = 24;
// Pixels one FRAME message carries with a payload maximum of max_payload.
constexpr std::size_t frame_fragment_pixels(std::size_t max_payload) noexcept { return max_payload - kFrameFixedBytes; }

struct PoseReport {
  std::uint32_t frame_id = 0;
  Pose pose;                        // exact float bits
  std::uint8_t state = 0;           // TrackState
  std::uint8_t confidence = 0;      // Confidence
  std::uint8_t flags = 0;           // kPoseReacquired
  std::uint32_t best_votes = 0;
  float score = 0.0f;
  std::uint32_t features = 0;
  std::uint32_t features_dropped = 0;
  std::uint64_t votes = 0;          // counter increments
  std::uint32_t frame_crc = 0;      // CRC-32C of the pixels the DUT tracked
  std::uint64_t received = 0;       // DUT clock: the frame's last fragment in
  std::uint64_t done = 0;           // DUT clock: the pose ready
  std::uint64_t cycles = 0;         // the voter's clock cycles, where known (0: not)
  // Appended in 1.1 (a 76-byte POSE decodes with both 0): a camera DUT's
  // stages on the same clock as received and done, 0 where not known.
  std::uint64_t captured = 0;       // DUT clock: the camera's timestamp of the frame tracked
  std::uint64_t strobed = 0;        // DUT clock: the strobe line's rising edge for this pose
};
inline constexpr std::uint8_t kPoseReacquired = 1u << 0;
inline constexpr std::size_t kPoseBytes = 92;
inline constexpr std::size_t kPoseBytesV10 = 76;  // the shortest POSE accepted

enum class EventKind : std::uint8_t { kDropped = 1, kSkipped = 2, kError = 3, kRestart = 4, kDuplicate = 5 };
enum class EventReason : std::uint8_t {
  kNone = 0,
  kIncomplete = 1,   // dropped: a fragment never came (the next frame began)
  kQueueFull = 2,    // dropped: no free slot (the host exceeded its credits)
  kOutOfOrder = 3,   // skipped: an older frame than one already taken
  kTooLarge = 4,     // skipped: larger than CAPS.max_frame_bytes or inconsistent fragments
  kNotStarted = 5,   // skipped: a frame before HELLO
  kTracking = 6,     // error: the tracker failed (detail: the Status)
  kHardware = 7,     // error: the hardware's result disagrees with the kernel's on its counters
  kBoot = 8,         // restart: the DUT (re)started
  kRepeat = 9,       // duplicate: a frame already taken came again (no fate: informational)
  // A camera DUT (the Linux board behind V4L2; detail: the driver's sequence number or count):
  kCameraTimeout = 10,  // error: the camera path did not deliver the frame in time
  kSameAsPrevious = 11, // skipped: identical to the previous frame, which a camera cannot tell apart
  kCameraError = 12,    // error (informational, frame kNoFrame): a buffer the driver flagged V4L2_BUF_FLAG_ERROR
  kCameraGap = 13,      // dropped (informational): the driver's sequence skipped `detail` frames
  kCameraLost = 14,     // error (informational): the capture device went away
  kCameraBack = 15,     // restart (informational): the capture device is open again
  kSequenceWrap = 16,   // restart (informational): the driver's sequence number went back (wrapped)
};
inline constexpr std::uint8_t kLastEventReason = 16;
const char* event_kind_name(EventKind kind) noexcept;
const char* event_reason_name(EventReason reason) noexcept;

struct Event {
  EventKind kind = EventKind::kError;
  EventReason reason = EventReason::kNone;
  std::uint32_t frame_id = kNoFrame;
  std::uint32_t detail = 0;
  std::uint64_t time = 0;  // DUT clock
};
inline constexpr std::size_t kEventBytes = 20;

struct Ping {
  std::uint32_t token = 0;
  std::uint64_t host_time_us = 0;
};
inline constexpr std::size_t kPingBytes = 12;

struct Pong {
  std::uint32_t token = 0;
  std::uint64_t host_time_us = 0;  // the PING's
  std::uint64_t dut_time = 0;
  std::uint32_t last_frame = kNoFrame;  // the newest frame id taken (complete) this run
  std::uint32_t queued = 0;             // frames taken and not yet answered
  std::uint32_t oldest_queued = kNoFrame;  // the oldest of them: every older frame taken is answered
};
inline constexpr std::size_t kPongBytes = 32;

// The DUT's counters since its start (a request is an empty STATS).
struct Stats {
  std::uint32_t messages_in = 0, bad_crc = 0, bad_message = 0, unknown_type = 0;
  std::uint32_t framing_errors = 0;   // COBS runs discarded (stream links)
  std::uint32_t sequence_gaps = 0;    // messages missing by sequence number
  std::uint32_t stale = 0;            // messages not after the last accepted
  std::uint32_t frames_taken = 0, frames_tracked = 0, frames_dropped = 0, frames_skipped = 0;
  std::uint32_t messages_out = 0;
  // Appended in 1.1 (0 when absent or not known): the DUT program's resident
  // memory, for soaks.
  std::uint32_t resident_kib = 0;
};
inline constexpr std::size_t kStatsBytes = 52;

struct Bye {
  std::uint32_t reason = 0;       // 0: the run is complete
  std::uint32_t last_frame = kNoFrame;  // host: the last frame sent; DUT: the last taken
};
inline constexpr std::size_t kByeBytes = 8;

// INJECT: a fault the DUT's rig injects on its side of the link (a camera
// error, a USB unplug, a killed process, ...). `kind` is the rig's fault
// number (hil/faults.hpp: FaultKind); an unknown one is answered unsupported.
struct Inject {
  std::uint32_t token = 0;
  std::uint8_t kind = 0;
};
inline constexpr std::size_t kInjectBytes = 8;

enum class InjectOutcome : std::uint8_t { kDetected = 0, kUnsupported = 1, kFailed = 2, kUndetected = 3 };
const char* inject_outcome_name(InjectOutcome outcome) noexcept;

// INJECTED: the fault is over (its effect detected by the DUT's own
// checks, or not), with what showed it.
struct Injected {
  std::uint32_t token = 0;
  std::uint8_t kind = 0;
  InjectOutcome outcome = InjectOutcome::kFailed;
  std::uint16_t attempts = 0;   // injections needed (vivid loses some error injections)
  std::uint64_t started = 0;    // DUT clock
  std::uint64_t ended = 0;      // DUT clock: the fault over (the device back, the halt cleared, ...)
  char evidence[80] = {};       // what detected it, NUL-padded
};
inline constexpr std::size_t kInjectedBytes = 24 + 80;

// NOTE: a line of text from the host for the DUT's own console, where it has
// one (the Cortex-M firmware prints it on UART1). A board farm that reads only
// the console (LAVA's monitors) learns the harness's verdicts this way
// (docs/hil-farm.md). Printable ASCII, NUL-padded; no answer. A DUT without a
// console ignores it.
struct Note {
  std::uint32_t frame_id = kNoFrame;  // the frame it is about (kNoFrame: the run)
  char text[96] = {};
};
inline constexpr std::size_t kNoteBytes = 4 + 96;

std::size_t encode(const Hello& m, std::span<std::byte> out) noexcept;
std::size_t encode(const Caps& m, std::span<std::byte> out) noexcept;
std::size_t encode(const FrameFragment& m, std::span<std::byte> out) noexcept;  // header fields and pixels
std::size_t encode(const PoseReport& m, std::span<std::byte> out) noexcept;
std::size_t encode(const Event& m, std::span<std::byte> out) noexcept;
std::size_t encode(const Ping& m, std::span<std::byte> out) noexcept;
std::size_t encode(const Pong& m, std::span<std::byte> out) noexcept;
std::size_t encode(const Stats& m, std::span<std::byte> out) noexcept;
std::size_t encode(const Bye& m, std::span<std::byte> out) noexcept;
std::size_t encode(const Inject& m, std::span<std::byte> out) noexcept;
std::size_t encode(const Injected& m, std::span<std::byte> out) noexcept;
std::size_t encode(const Note& m, std::span<std::byte> out) noexcept;

Status decode(std::span<const std::byte> payload, Hello& m) noexcept;
Status decode(std::span<const std::byte> payload, Caps& m) noexcept;
Status decode(std::span<const std::byte> payload, FrameFragment& m) noexcept;  // pixels view `payload`
Status decode(std::span<const std::byte> payload, PoseReport& m) noexcept;
Status decode(std::span<const std::byte> payload, Event& m) noexcept;
Status decode(std::span<const std::byte> payload, Ping& m) noexcept;
Status decode(std::span<const std::byte> payload, Pong& m) noexcept;
Status decode(std::span<const std::byte> payload, Stats& m) noexcept;
Status decode(std::span<const std::byte> payload, Bye& m) noexcept;
Status decode(std::span<const std::byte> payload, Inject& m) noexcept;
Status decode(std::span<const std::byte> payload, Injected& m) noexcept;
Status decode(std::span<const std::byte> payload, Note& m) noexcept;  // kBadHeaderField: not printable ASCII

// Copies a NUL-terminated string into a fixed field, truncating, NUL-padding.
template <std::size_t N>
void set_text(char (&field)[N], const char* text) noexcept {
  std::size_t i = 0;
  for (; text != nullptr && text[i] != '\0' && i + 1 < N; ++i) field[i] = text[i];
  for (; i < N; ++i) field[i] = '\0';
}

// The POSE's frame CRC: CRC-32C of the frame's luma row by row, `width`
// bytes of each row (no row padding). Every device and the harness compute
// it here, so that a frame is named the same way on every target.
std::uint32_t frame_crc(const ImageView& frame) noexcept;

// What every device under test reports about itself in CAPS, filled in one
// place (make_caps): its table, its limits, its mode, who it is.
inline constexpr const char* kSoftwareVersion = "gabarit 0.1.0";
struct DeviceDescription {
  std::uint32_t table_crc = 0;        // CRC-32 of the DUT's table file (0 and 0 bytes: none)
  std::uint32_t table_bytes = 0;
  std::uint32_t clock_hz = 0;         // the unit of its timestamps
  std::uint32_t frame_slots = 1;
  std::uint32_t max_frame_bytes = 0;  // 0: frames come from a camera, not the link
  std::uint16_t max_payload = kMaxPayload;
  std::uint32_t mode = 0;             // the session profile's mode bits (app/session_profile.hpp)
  const char* kind = "";              // "inprocess", "verilator", "cortex-m", "linux-board", ...
  const char* board = "";
  const char* software = kSoftwareVersion;
  std::uint64_t device_id = 0;        // 0: the CRC-32 of `board` (stable per board name)
};
Caps make_caps(const DeviceDescription& device) noexcept;

}  // namespace gabarit::link
