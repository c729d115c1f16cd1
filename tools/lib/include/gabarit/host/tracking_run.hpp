// Runs the kernel's tracker over a frame source, one frame at a time, timing
// only the kernel's work per frame (features + voting + pose update; not
// decoding or I/O).
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "gabarit/host/image_io.hpp"
#include "gabarit/table_view.hpp"
#include "gabarit/tracker.hpp"
#include "gabarit/tracking_session.hpp"

namespace gabarit::host {

struct TrackRow {
  std::uint32_t frame = 0;
  StepResult step;
  Confidence confidence = Confidence::kNone;
  bool reacquired = false;
  double micros = 0;  // kernel time for this frame
};

struct TimingSummary {
  std::size_t frames = 0;
  double mean = 0, p50 = 0, p99 = 0, max = 0;  // microseconds
};
TimingSummary summarise_timing(std::vector<double> micros);

// Which voter track_step uses: the CSR lists, word-parallel masks
// (dense_voter.hpp; tables of at most kDenseMaxCells cells), or dense when
// the table allows it. Results are bit-identical; only the time differs.
enum class VoterChoice { kAuto, kCsr, kDense };

// Scratch for track_step on one table, sized by the kernel's formulas.
class TrackerBuffers {
 public:
  TrackerBuffers(const TableView& table, VoterChoice voter);
  TrackerScratch scratch();
  bool dense() const { return !masks_.empty(); }

 private:
  std::vector<RoiPoint> features_;
  std::vector<VoteCounter> counters_;
  std::vector<std::uint8_t> mask_;
  std::vector<std::uint64_t> masks_, dense_scratch_;
};

struct TrackingOptions {
  std::optional<Detector> detector;        // overrides the table's detector
  VoterChoice voter = VoterChoice::kAuto;
  SessionOptions session = kPlainSession;  // motion filter, refinement, recovery
  const TableView* coarse = nullptr;       // the recovery search's table (else the fine one)
  // Threads voting each frame (parallel_voter.hpp, features split). Above 1,
  // only for the plain loop (kPlainSession, no coarse table); the rows are
  // the same bytes as with one thread.
  unsigned threads = 1;
  // The focus stack's images (one per depth, the table's model images): when
  // given, each frame's depth is chosen by intensity at the tracked pose
  // (depth_by_intensity.hpp). Only with a session (not the --threads loop).
  std::vector<GrayImage> focus_stack;
  // The grid search detects features once per lost frame (scratch for it,
  // SessionScratch::search_features); false: a full track_step per placement,
  // as before (kept for the bench's comparison).
  bool shared_search_features = true;
};

// Calls on_row for every frame. row.step is the frame's vote with the
// session's decision in pose, state and score (tracking_session.hpp).
void run_tracking(const TableView& table, FrameSource& frames, const Pose& init, const TrackingOptions& options,
                  const std::function<void(const TrackRow&)>& on_row);
inline void run_tracking(const TableView& table, FrameSource& frames, const Pose& init, const std::optional<Detector>& detector,
                         const std::function<void(const TrackRow&)>& on_row, VoterChoice voter = VoterChoice::kAuto) {
  TrackingOptions options;
  options.detector = detector;
  options.voter = voter;
  run_tracking(table, frames, init, options, on_row);
}

// A session's frame as a row: the vote, with the session's pose, state,
// score and confidence (what `gabarit track` and gabarit-board print).
void fill_row(TrackRow& row, const SessionResult& result);

// One CSV line "frame,x,y,theta_deg,depth,votes,score,status" (no newline).
std::string pose_csv_row(const TrackRow& row);
inline constexpr const char* kPoseCsvHeader = "frame,x,y,theta_deg,depth,votes,score,status";

}  // namespace gabarit::host
