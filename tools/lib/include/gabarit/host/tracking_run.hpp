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

namespace gabarit::host {

struct TrackRow {
  std::uint32_t frame = 0;
  StepResult step;
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

// Calls on_row for every frame. `detector` overrides the table's detector.
void run_tracking(const TableView& table, FrameSource& frames, const Pose& init, const std::optional<Detector>& detector,
                  const std::function<void(const TrackRow&)>& on_row, VoterChoice voter = VoterChoice::kAuto);

// One CSV line "frame,x,y,theta_deg,depth,votes,score,status" (no newline).
std::string pose_csv_row(const TrackRow& row);
inline constexpr const char* kPoseCsvHeader = "frame,x,y,theta_deg,depth,votes,score,status";

}  // namespace gabarit::host
