// A tracking session: the per-frame loop a camera application runs, on top of
// track_step. It keeps the pose between frames and adds, each optional:
//   - the motion filter (motion_filter.hpp): the ROI at the predicted pose,
//     candidates gated by the motion model, confidence, velocity;
//   - sub-cell refinement (refinement.hpp) of the chosen cell;
//   - recovery: once lost, every search_interval-th frame searches,
//     alternately around where the target would be had it kept the velocity
//     it had at the last confident frame, and around that frame's pose (in
//     case it stopped). Candidates go to a shortlist of the three best fine
//     votes; each is voted again from its own estimate (the target, centred,
//     scores far above clutter), and the best must reach high confidence to
//     return the session to tracking.
//       Without a coarse table the candidates come from the fine table placed
//     on a grid: 9 x 9 ROI positions spaced by its x/y extent (+-36 px for a
//     +-4 px table, plus its own range) at 7 angle offsets, multiples of
//     search_turn_deg (+-9 deg by default, plus its own range). With
//     SessionScratch::search_features, features are detected once over the
//     whole grid and each placement is screened with every screen_stride-th
//     of them (map_features); without, each is a full track_step. A search
//     votes the 9 placements nearest the centre and the next search_budget
//     of the other 558 in turn, nearest shells first (search_budget 0: all).
//       With a coarse table (larger cells over a wider window, built from
//     the same model) the candidates are its coarse_proposals best cells,
//     voted once at the centre.
// With everything off (kPlainSession) a session is exactly track_step frame
// after frame, a lost frame keeping the previous pose.
// No heap: scratch comes from the caller, as for track_step.
#pragma once

#include <cstdint>
#include <span>

#include "gabarit/depth_by_intensity.hpp"
#include "gabarit/motion_filter.hpp"
#include "gabarit/tracker.hpp"

namespace gabarit {

inline constexpr std::uint32_t kMaxCoarseProposals = 16;

struct SessionOptions {
  bool motion_filter = true;
  bool refine = true;
  bool recover = true;  // search for the target once lost (else keep predicting)
  float search_turn_deg = 3.0f;  // the grid search's angle offsets
  std::uint32_t search_budget = 0;  // grid placements beyond the nearest 9 per search; 0 = all 558
  std::uint32_t search_interval = 1;  // search every n-th lost frame (1: every one)
  std::uint32_t screen_stride = 2;  // grid search with shared features: every n-th feature scores a placement
  std::uint32_t coarse_proposals = 8;  // with a coarse table: its best cells checked by the fine table, 1..kMaxCoarseProposals
  MotionFilterParams filter;
};
// track_step frame after frame, nothing added: the thesis's tracker.
inline constexpr SessionOptions kPlainSession{false, false, false, 3.0f, 0, 1, 2, 8, {}};

// The recovery grid (tracking_session.cpp): (2 kSearchRings + 1)^2 ROI
// positions spaced by the fine table's x/y extent, at 2 kSearchTurns + 1
// angle offsets spaced by search_turn_deg.
inline constexpr int kSearchRings = 4;
inline constexpr int kSearchTurns = 3;
inline constexpr std::uint32_t kSearchPlacementCount = (2 * kSearchRings + 1) * (2 * kSearchRings + 1) * (2 * kSearchTurns + 1);
inline constexpr std::uint32_t kSearchNear = 9;  // ring <= 1 at turn 0: voted at every search

// The grid spacing: a table's x (or y) extent plus one cell.
inline float search_step(const Axis& a) noexcept {
  return a.max - a.min + (a.cells > 1 ? (a.max - a.min) / static_cast<float>(a.cells - 1) : 1.0f);
}
// The recovery grid's placements reach this far from the search centre:
// kSearchRings grid steps, then the half-side of the window a rotated ROI
// needs, plus a pixel for rounding.
inline std::uint32_t search_reach(const TableView& fine) noexcept {
  const float sx = search_step(fine.axis_x()), sy = search_step(fine.axis_y());
  const auto grid = static_cast<std::uint32_t>(static_cast<float>(kSearchRings) * (sx > sy ? sx : sy)) + 1u;
  return grid + tracker_window_side(fine.roi_width(), fine.roi_height(), fine.roi_origin_x(), fine.roi_origin_y()) / 2 + 1u;
}
inline std::size_t search_feature_capacity(const TableView& fine) noexcept {
  const std::size_t side = 2 * std::size_t{search_reach(fine)} + 1;
  return side * side;
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

struct SessionResult {
  Pose pose;                 // the session's estimate after this frame
  StepResult step;           // the raw vote of the table searched this frame
  Confidence confidence = Confidence::kNone;
  TrackState state = TrackState::kLost;
  float score = 0.0f;        // normalised score of the chosen cell
  bool searched_coarse = false;
  bool reacquired = false;   // this frame ended a lost period
};

class TrackingSession {
 public:
  // `fine` (and `coarse`, if not null) must outlive the session. Errors from
  // start(): kInvalidArgument for bad options or a non-finite pose.
  TrackingSession(const TableView& fine, const TableView* coarse, const Detector& detector) noexcept
      : fine_(fine), coarse_(coarse), detector_(detector) {}
  [[nodiscard]] Status start(const SessionOptions& options, const Pose& initial) noexcept;
  [[nodiscard]] Status step(const ImageView& image, SessionScratch scratch, SessionResult& out) noexcept;
  // With a focus stack (which must outlive the session; nullptr to stop),
  // each frame's depth is then chosen by intensity at the tracked pose
  // (depth_by_intensity.hpp) instead of by the winning stencils' stack index.
  void use_focus_stack(const FocusStack* stack) noexcept { stack_ = stack; }

  const Pose& pose() const noexcept { return pose_; }
  float reference_score() const noexcept { return reference_; }
  const MotionFilterState& motion() const noexcept { return motion_; }
  bool lost() const noexcept { return lost_; }

 private:
  Status track_fine(const ImageView& image, SessionScratch scratch, SessionResult& out) noexcept;
  Status search(const ImageView& image, SessionScratch scratch, SessionResult& out) noexcept;
  Confidence grade(float score, float next_score) noexcept;
  void begin_lost() noexcept;

  const TableView& fine_;
  const TableView* coarse_;
  Detector detector_;
  SessionOptions options_;
  Pose pose_;
  Pose last_confident_;
  MotionFilterState confident_motion_;      // the velocity at last_confident_
  std::uint32_t frames_since_confident_ = 0;
  MotionFilterState motion_;
  float reference_ = 0.0f;  // running score of high-confidence frames (motion_filter.hpp)
  bool lost_ = false;
  const FocusStack* stack_ = nullptr;
  std::uint32_t lost_frames_ = 0;  // frames since the session became lost
  std::uint32_t searches_ = 0;     // searches since then
  std::uint32_t search_cursor_[2] = {0, 0};  // per search centre: the next of the outer placements to vote
};

}  // namespace gabarit
