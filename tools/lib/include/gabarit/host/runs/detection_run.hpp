// Detection on the host (gabarit detect, gabarit track without --init, the
// bench): a ModelFinder (model_finder.hpp) with its buffers, re-sized when
// the frame size changes, and the CSV rows gabarit detect writes.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "gabarit/app/args.hpp"
#include "gabarit/app/scratch.hpp"
#include "gabarit/model_finder.hpp"

namespace gabarit::host {

inline constexpr std::string_view kDetectionCsvHeader = "frame,rank,x,y,theta_deg,depth,score,coarse_score,vote_score";
std::string detection_csv_row(std::uint64_t frame, std::size_t rank, const Detection& d);

// --max-count, --min-score, --min-distance, --theta-range, --theta-step,
// --pyramid, --candidates, --position-only (those present in args). Throws
// app::UsageError naming the option.
FinderOptions finder_options_from(const app::Args& args, const TableView& table);

struct FrameDetections {
  std::vector<Detection> detections;  // best first
  double micros = 0;                  // the find, buffers excluded
};

class FrameDetector {
 public:
  // `table` must outlive the detector. Throws app::Error for invalid options.
  // With focus_stack, the table's model images (if it has them) choose each
  // detection's depth and angle by intensity (ModelFinder::use_focus_stack).
  FrameDetector(const TableView& table, const Detector& detector, const FinderOptions& options,
                app::VoterChoice voter = app::VoterChoice::kAuto, bool focus_stack = true);
  // Throws app::Error on a kernel error (an invalid frame).
  FrameDetections detect(const ImageView& frame);
  // Of the last frame size (before the first: of a 1x1 frame).
  const FinderGeometry& geometry() const { return buffers_ ? buffers_->geometry() : fallback_; }
  const FinderOptions& options() const { return options_; }

 private:
  const TableView& table_;
  Detector detector_;
  FinderOptions options_;
  ModelFinder finder_;
  app::TrackerBuffers fine_;
  app::TableFocusStack stack_;
  std::optional<app::FinderBuffers> buffers_;
  FinderGeometry fallback_;
};

}  // namespace gabarit::host
