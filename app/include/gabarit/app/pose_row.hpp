// The pose row: one line per frame, what `gabarit track` writes to its CSV and
// gabarit-board to stdout and UDP (docs/file-formats.md, "Poses").
#pragma once

#include <cstdint>
#include <string>

#include "gabarit/motion_filter.hpp"
#include "gabarit/tracker.hpp"
#include "gabarit/tracking_session.hpp"

namespace gabarit::app {

struct TrackRow {
  std::uint32_t frame = 0;
  StepResult step;  // the frame's vote, with the session's pose, state and score
  Confidence confidence = Confidence::kNone;
  bool reacquired = false;
  double micros = 0;  // kernel time for this frame
  std::uint64_t work = 0;  // the session's work units for it (SessionResult::work)
  // The session's (or the particle filter's) frame-cost ledger
  // (frame_ledger.hpp; ticks in nanoseconds, steady_nanoseconds), and the time spent reading the frame before it, in
  // microseconds (decoding, the camera). No session (the plain loop on
  // several threads): has_ledger is false.
  bool has_ledger = false;
  FrameLedger ledger;
  double io_micros = 0;
};

// The ledger's clock in the host's programs (frame_ledger.hpp's TickSource):
// nanoseconds of the host's monotonic clock.
std::uint64_t steady_nanoseconds() noexcept;

// A session's frame as a row: the vote, with the session's pose, state,
// score and confidence.
void fill_row(TrackRow& row, const SessionResult& result);

// One CSV line "frame,x,y,theta_deg,depth,votes,score,status" (no newline).
std::string pose_csv_row(const TrackRow& row);
inline constexpr const char* kPoseCsvHeader = "frame,x,y,theta_deg,depth,votes,score,status";

}  // namespace gabarit::app
