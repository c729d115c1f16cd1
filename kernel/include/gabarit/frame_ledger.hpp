// The frame-cost ledger: what a tracking session's frame spent, phase by
// phase, in two currencies.
//   - work, counted: the detection search's units (finder_search.hpp: about
//     one counter increment each), so the same on every target and usable
//     as a budget. Their sum is SessionResult::work.
//   - ticks, timed: read from a clock the caller gives the session
//     (TrackingSession::use_clock), in that clock's unit (the host's
//     programs use nanoseconds). Without a clock, and on bare-metal
//     Cortex-M (kLedgerTimed), every tick count is 0 and nothing is timed.
// Timing never changes what the session computes: the same frames give the
// same poses with a clock or without.
#pragma once

#include <cstdint>

namespace gabarit {

enum class FramePhase : std::uint8_t {
  kFeatures,  // the ROI's features: gradients, thresholds, thinning, mapping into the table frame
  kVote,      // clearing the counters, voting, the best cells and the pose update of the vote
  kVerify,    // vote, then verify: the proposals' correlations with the model and their refinement
  kDepth,     // depth (and angle) by intensity at the chosen pose, with a focus stack
  kRecovery,  // a lost frame's search (grid, particles or detection), all of it
  kSurvey,    // verifying: the survey of the frame for look-alikes, a piece after a tracked frame
  kOther,     // the rest of the step: gating, the motion filter, sub-cell refinement
};
inline constexpr std::uint32_t kFramePhaseCount = 7;

// A short stable name such as "features" (for --stats and reports).
constexpr const char* frame_phase_name(FramePhase phase) noexcept {
  switch (phase) {
    case FramePhase::kFeatures: return "features";
    case FramePhase::kVote: return "vote";
    case FramePhase::kVerify: return "verify";
    case FramePhase::kDepth: return "depth";
    case FramePhase::kRecovery: return "recovery";
    case FramePhase::kSurvey: return "survey";
    case FramePhase::kOther: return "other";
  }
  return "?";
}

// A monotonic clock: a free function, so the kernel needs no <chrono> and an
// MCU can pass a cycle counter.
using TickSource = std::uint64_t (*)() noexcept;

struct FrameLedger {
  std::uint64_t work[kFramePhaseCount] = {};
  std::uint64_t ticks[kFramePhaseCount] = {};
  // The raw counts behind the work (this frame, every vote of it included:
  // at the prediction, at the last pose, in a recovery's grid search).
  std::uint64_t pixels_scanned = 0;  // pixels the detector ran over (PreparedFrame::pixels_scanned)
  std::uint64_t features = 0;        // feature pixels that voted
  std::uint64_t votes = 0;           // counter increments
  std::uint32_t correlations = 0;    // model-to-frame correlations (verified candidates, depths)

  void add(FramePhase phase, std::uint64_t phase_work, std::uint64_t phase_ticks) noexcept {
    work[static_cast<std::uint32_t>(phase)] += phase_work;
    ticks[static_cast<std::uint32_t>(phase)] += phase_ticks;
  }
  std::uint64_t total_work() const noexcept {
    std::uint64_t sum = 0;
    for (std::uint64_t w : work) sum += w;
    return sum;
  }
  std::uint64_t total_ticks() const noexcept {
    std::uint64_t sum = 0;
    for (std::uint64_t t : ticks) sum += t;
    return sum;
  }
};

// Whether the ledger can be timed on this target. Not on bare-metal
// Cortex-M: the firmware's stack analysis (platform/cortex-m/firmware_report.py)
// admits no indirect call, so there the ledger counts work only and every
// tick is 0 (a cycle counter read directly would be the way to time it).
#if defined(__ARM_ARCH_PROFILE) && __ARM_ARCH_PROFILE == 'M'
inline constexpr bool kLedgerTimed = false;
#else
inline constexpr bool kLedgerTimed = true;
#endif

// The clock's reading, 0 without one.
inline std::uint64_t read_ticks(TickSource clock) noexcept {
  if constexpr (kLedgerTimed) {
    return clock != nullptr ? clock() : 0;
  } else {
    static_cast<void>(clock);
    return 0;
  }
}

}  // namespace gabarit
