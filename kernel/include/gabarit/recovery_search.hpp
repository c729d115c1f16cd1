// Recovery: the search a TrackingSession runs while its target is lost.
//
// Every `interval`-th lost frame searches, alternately around where the
// target would be had it kept the velocity it had at the last confident frame,
// and around that frame's pose (in case it stopped). Candidates go to a
// shortlist of the three best fine votes; each is voted again from its own
// estimate (the target, centred, scores far above clutter), and the best is
// voted once more from its own estimate: that last vote is the search's
// result, which the session accepts only at high confidence.
//
// Without a coarse table the candidates come from the fine table placed on a
// grid: (2 kSearchRings + 1)^2 ROI positions spaced by its x/y extent plus one
// cell (+-36 px for a +-4 px table, plus its own range) at 2 kSearchTurns + 1
// angle offsets, multiples of turn_deg (+-9 deg by default, plus its own
// range). Placements are ordered in shells, nearest first; a search votes the
// kSearchNear nearest and the next `budget` of the others in turn (budget 0:
// all), each search centre keeping its own cursor.
//   With SessionScratch::search_features, features are detected once over the
// whole grid's window and each placement is screened with every
// screen_stride-th of them (map_features), over the last known depth's cells
// only; without, each placement is a full track_step.
//   With a coarse table (larger cells over a wider window, built from the same
// model) the candidates are its coarse_proposals best cells, voted once at
// the centre.
// No heap: scratch comes from the caller; its sizes are constexpr below.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "gabarit/features.hpp"
#include "gabarit/image_view.hpp"
#include "gabarit/motion_filter.hpp"
#include "gabarit/pose.hpp"
#include "gabarit/roi_point.hpp"
#include "gabarit/status.hpp"
#include "gabarit/table_view.hpp"
#include "gabarit/tracker.hpp"

namespace gabarit {

inline constexpr std::uint32_t kMaxCoarseProposals = 16;

struct RecoveryOptions {
  float turn_deg = 3.0f;               // the grid's angle offsets
  std::uint32_t budget = 0;            // grid placements beyond the nearest kSearchNear per search; 0 = all
  std::uint32_t interval = 1;          // search every n-th lost frame (1: every one)
  std::uint32_t screen_stride = 2;     // with shared features: every n-th feature scores a placement
  std::uint32_t coarse_proposals = 8;  // with a coarse table: its best cells checked by the fine table, 1..kMaxCoarseProposals
  // With a detection stage (TrackingSession::use_detection_recovery): the
  // first detect_after lost frames search locally (the grid, or the coarse
  // table), the later ones by detection over where the target can be. 0:
  // detection from the first lost frame: with the search bounded by the
  // reach it costs less than the grid, and the scene suite tracks the same
  // with 0 and 2 (docs/detection.md).
  std::uint32_t detect_after = 0;
};
// True if the options are usable (strides and interval >= 1, proposals in range, a finite turn).
bool valid(const RecoveryOptions& options) noexcept;

// The grid: (2 kSearchRings + 1)^2 ROI positions at 2 kSearchTurns + 1 angle offsets.
inline constexpr int kSearchRings = 4;
inline constexpr int kSearchTurns = 3;
inline constexpr std::uint32_t kSearchPlacementCount = (2 * kSearchRings + 1) * (2 * kSearchRings + 1) * (2 * kSearchTurns + 1);
inline constexpr std::uint32_t kSearchNear = 9;  // ring <= 1 at turn 0: voted at every search

// The grid spacing along an axis: its extent plus one cell.
constexpr float search_step(const Axis& a) noexcept {
  return a.max - a.min + (a.cells > 1 ? (a.max - a.min) / static_cast<float>(a.cells - 1) : 1.0f);
}
// How far the grid's placements reach from the search centre, in pixels:
// kSearchRings grid steps, then the half-side of the window a rotated ROI
// needs, plus a pixel for rounding. A grid wider than 2^16 px saturates (its
// window is then too large to share features, and each placement votes alone).
constexpr std::uint32_t search_reach(const Axis& x, const Axis& y, std::uint16_t roi_width, std::uint16_t roi_height,
                                     std::int16_t roi_origin_x, std::int16_t roi_origin_y) noexcept {
  const float sx = search_step(x), sy = search_step(y);
  const float grid = static_cast<float>(kSearchRings) * (sx > sy ? sx : sy);
  const std::uint32_t grid_px = grid < 65536.0f ? static_cast<std::uint32_t>(grid) + 1u : 65537u;
  return grid_px + tracker_window_side(roi_width, roi_height, roi_origin_x, roi_origin_y) / 2 + 1u;
}
// Entries of SessionScratch::search_features: the grid's whole window.
constexpr std::size_t search_feature_capacity(const Axis& x, const Axis& y, std::uint16_t roi_width,
                                              std::uint16_t roi_height, std::int16_t roi_origin_x,
                                              std::int16_t roi_origin_y) noexcept {
  const std::size_t side = 2 * std::size_t{search_reach(x, y, roi_width, roi_height, roi_origin_x, roi_origin_y)} + 1;
  return side * side;
}
// The most shared features a hosted program allocates for the search (64
// MiB, app::SessionBuffers); a table whose grid window needs more (x/y ranges
// of hundreds of pixels) is searched with a full track_step per placement.
inline constexpr std::size_t kMaxSearchFeatures = std::size_t{1} << 24;

inline std::uint32_t search_reach(const TableView& fine) noexcept {
  return search_reach(fine.axis_x(), fine.axis_y(), fine.roi_width(), fine.roi_height(), fine.roi_origin_x(),
                      fine.roi_origin_y());
}
inline std::size_t search_feature_capacity(const TableView& fine) noexcept {
  return search_feature_capacity(fine.axis_x(), fine.axis_y(), fine.roi_width(), fine.roi_height(), fine.roi_origin_x(),
                                 fine.roi_origin_y());
}

struct SessionScratch {
  TrackerScratch fine;
  TrackerScratch coarse;  // for the coarse table; unused without one
  // Optional, search_feature_capacity(fine) entries: the grid search then
  // detects features once per search and screens each placement with every
  // screen_stride-th of them, over the last known depth's cells, instead of
  // a full track_step per placement. Empty: track_step per placement (for a
  // part short of RAM: about 4 bytes per pixel of the search window).
  std::span<RoiPoint> search_features = {};
};

// Where the target was last seen with confidence, and how it was moving.
struct LastSighting {
  Pose pose;
  MotionFilterState motion;
  std::uint32_t frames_since = 0;  // frames since that sighting
};

// The outcome of one lost frame.
struct SearchResult {
  bool searched = false;        // false: a frame between searches (interval > 1)
  bool searched_coarse = false;
  StepResult vote;              // the final vote of the best candidate (its counters stay in the fine scratch)
  Pose from;                    // the pose that vote was measured from
  // The search's work units (finder_search.hpp): its feature extraction and
  // its votes (a particle search's own measures are not counted).
  std::uint64_t work = 0;
};

class RecoverySearch {
 public:
  // `fine` (and `coarse`, if not null) must outlive the search.
  RecoverySearch(const TableView& fine, const TableView* coarse, const Detector& detector) noexcept
      : fine_(fine), coarse_(coarse), detector_(detector) {}
  // Starts a lost period: nearest placements first, the extrapolated centre first.
  void reset() noexcept {
    lost_frames_ = searches_ = 0;
    cursor_[0] = cursor_[1] = 0;
  }
  // One lost frame; screen_depth is the last known depth. Precondition:
  // valid(options). Errors: the tracker's (short scratch, an invalid image).
  [[nodiscard]] Status run(const ImageView& image, const RecoveryOptions& options, const LastSighting& last,
                           std::uint16_t screen_depth, SessionScratch scratch, SearchResult& out) noexcept;

 private:
  const TableView& fine_;
  const TableView* coarse_;
  Detector detector_;
  std::uint32_t lost_frames_ = 0;  // frames since the lost period began
  std::uint32_t searches_ = 0;     // searches since then
  std::uint32_t cursor_[2] = {0, 0};  // per search centre: the next of the outer placements to vote
};

}  // namespace gabarit
