// The HIL harness: replay a recorded sequence into a DUT over the link,
// collect every pose, account for every frame, check each pose bit for bit
// against the host's reference (the kernel on the same table and the same
// frames, in the order the DUT took them), inject the planned faults, and
// measure latency. docs/hil-protocol.md describes a run.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "gabarit/hil/dut.hpp"
#include "gabarit/hil/faults.hpp"
#include "gabarit/frame_ledger.hpp"
#include "gabarit/link/protocol.hpp"
#include "gabarit/pose.hpp"

namespace gabarit::hil {

// What became of a frame the harness had to send.
enum class Fate : std::uint8_t {
  kPending,        // not yet known (none is left at the end of a run that completes)
  kPose,           // a POSE came back
  kDroppedByLink,  // it never reached the DUT intact (the DUT's PONG: never taken)
  kDroppedByDut,   // the DUT dropped it (a fragment missing, no free slot)
  kSkippedByDut,   // the DUT skipped it (out of order, too large, not started)
  kDutError,       // the DUT failed on it (tracking failed, the hardware disagreed)
  kLostInRestart,  // in flight when the DUT was restarted (planned, hung or crashed)
  kNotSent,        // --rate: the DUT was busy when its time came (a camera drops it)
};
const char* fate_name(Fate fate);

struct FrameRecord {
  std::uint32_t frame = 0;
  Fate fate = Fate::kPending;
  std::string reason;
  std::optional<link::PoseReport> pose;
  std::uint32_t run = 0;          // which DUT run (0, then one more per restart)
  double sent_us = -1;            // since the run began (first byte handed to the transport)
  double latency_us = -1;         // sent -> POSE received
  double dut_us = -1;             // the DUT's own time for it, received -> done (its clock)
  // A camera DUT's stages on its clock (-1: not reported): the frame shown
  // to the camera -> captured -> pose ready -> strobe edge.
  double camera_us = -1, track_us = -1, strobe_us = -1;
  int reference = -1;             // 1: bit-identical to the host's reference, 0: not, -1: no pose
  std::string mismatch;           // the first field that differs
  // The host reference's frame-cost ledger for it (frame_ledger.hpp). Its
  // work is the DUT's too: work is counted, the same on every target, and
  // the pose matched. Its ticks are the host's, so only work is reported.
  std::optional<FrameLedger> reference_ledger;
  bool frame_crc_ok = true;       // the pixels the DUT tracked are the ones sent
  std::uint32_t repeats = 0;      // duplicate arrivals the DUT reported
  int fault = -1;                 // index into RunResult::faults, if faulted
  std::uint64_t wire_bytes = 0;   // bytes on the wire for it (both ways, framing included)
  std::uint32_t pixel_bytes = 0;  // its pixels (width x height)
};

struct InjectedFault {
  std::uint32_t frame = 0;
  FaultKind kind = FaultKind::kDrop;
  std::string detail;      // what exactly was done (which fragment, byte or bits)
  bool detected = false;   // the frame's fate shows it
  bool recovered = false;  // the next unfaulted frame came back as a pose matching the reference
  std::string evidence;
  // Rig faults: when the rig said the fault was over (since the run began),
  // and how long after that the next matching pose arrived.
  double ended_us = -1;
  double recovery_ms = -1;
  bool answered = false;   // INJECTED came back
};

// A soak's window of frames: memory and latency over the run.
struct SoakSample {
  std::uint32_t frames = 0;      // frames sent so far
  double seconds = 0;            // since the run began
  std::uint64_t host_rss_kib = 0;
  std::uint32_t dut_rss_kib = 0; // 0: the DUT does not report it
  double latency_p50_us = 0, latency_p99_us = 0;  // over the window's poses
};

struct RunResult;

struct RunConfig {
  std::string sequence_dir;            // frames.y4m (and gt.csv)
  std::string table_path;              // the host's copy of the DUT's table
  std::optional<Pose> init;            // else the first ground-truth row
  double rate_fps = 0;                 // 0: as fast as the DUT takes frames
  std::uint32_t max_frames = 0;        // 0: the whole sequence
  FaultPlan faults;
  std::uint64_t seed = 1;              // each fault's bytes and bits
  std::uint32_t max_unplanned_restarts = 10;
  // Soak: the sequence played this many times over (frame k shows frame
  // k mod the sequence's length), with a memory and latency sample every
  // soak_window frames.
  std::uint32_t loops = 1;
  std::uint32_t soak_window = 1000;
  // Called about once a second and at the end: frames resolved, frames to send.
  std::function<void(std::uint32_t, std::uint32_t)> progress;
  // Called as each frame's fate becomes known (results.jsonl).
  std::function<void(const FrameRecord&)> on_resolved;
  // Lines for the DUT's console, each sent as a NOTE (console_verdicts.hpp):
  // the opening one after the first handshake, a frame's as its fate becomes
  // known, the closing ones once the run is judged. Empty or unset: none.
  std::string console_opening;
  std::function<std::string(const FrameRecord&)> console_frame_line;
  std::function<std::vector<std::string>(const RunResult&)> console_closing;
};

struct LatencySummary {
  std::size_t samples = 0;
  double p50 = 0, p99 = 0, max = 0, mean = 0;
};
LatencySummary summarise(std::vector<double> values);

struct RunResult {
  link::Caps caps;                  // the DUT's answer to the first HELLO
  std::string dut_description;
  std::uint32_t frames_total = 0;   // frames the run had to send
  std::vector<FrameRecord> frames;
  std::vector<InjectedFault> faults;
  std::optional<link::Stats> dut_stats;  // the DUT's counters at the end (of its last run)
  std::uint32_t restarts_planned = 0, restarts_hung = 0, restarts_crashed = 0;
  std::uint32_t restarts_reported = 0;   // the DUT's rig restarted the DUT behind it (EVENT restart/boot)
  std::vector<SoakSample> soak;
  std::uint32_t out_of_order = 0;        // answers for a frame older than one already answered
  std::uint32_t double_answers = 0;      // a second fate for one frame
  std::uint32_t unknown_answers = 0;     // answers for frames never sent
  std::uint32_t bad_messages_in = 0;     // messages from the DUT that failed their checks
  std::uint32_t unaccounted = 0;         // frames left pending
  std::uint64_t pixel_bytes_sent = 0, wire_bytes = 0;
  double host_codec_seconds = 0;         // the harness's own encoding, CRCs and framing
  std::string error;                     // why the run stopped early ("" if it ran to the end)
  double seconds = 0;
};

// Runs the sequence into the driver's DUT. Never hangs: every wait has a
// deadline, a silent DUT is restarted. Throws app::Error only for bad input
// (a missing sequence, a table that does not open); a DUT that cannot be
// started or refuses the run ends the run with RunResult::error set.
RunResult run_hil(const RunConfig& config, DutDriver& dut);

}  // namespace gabarit::hil
