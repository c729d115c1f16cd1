// A tracking session: the per-frame loop a camera application runs, on top of
// track_step. It keeps the pose between frames and adds, each optional:
//   - the motion filter (motion_filter.hpp): the ROI at the predicted pose,
//     candidates gated by the motion model, confidence, velocity;
//   - sub-cell refinement (refinement.hpp) of the chosen cell;
//   - recovery: once lost, each frame searches a coarse table (larger cells
//     over a wider motion window, built from the same model), alternately
//     around where the target would be had it kept the velocity it had at the
//     last confident frame, and around that frame's pose (in case it
//     stopped); the fine table then votes again from the coarse hit, and a
//     high-confidence fine vote returns the session to tracking. Without a
//     coarse table the fine table itself is placed on a grid around those
//     places (7 x 7 ROI positions spaced by the table's x/y extent, at the
//     angle offsets 0 and +-search_turn_deg), and the three best placements
//     are voted again from their own estimates (the target, centred, scores
//     far above clutter); the best must reach high confidence. A lost frame
//     votes the 9 placements nearest the centre (no turn) and the next
//     search_budget of the other 138 in turn, nearest rings first, so a
//     lost frame costs about search_budget + 13 fine votes and the whole
//     grid is covered every ceil(138 / search_budget) lost frames
//     (search_budget 0: all 147 every frame).
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

struct SessionOptions {
  bool motion_filter = true;
  bool refine = true;
  bool recover = true;  // search for the target once lost (else keep predicting)
  float search_turn_deg = 3.0f;  // the grid search's angle offsets
  std::uint32_t search_budget = 0;  // grid placements beyond the nearest 9 per lost frame; 0 = all 138
  MotionFilterParams filter;
};
// track_step frame after frame, nothing added: the thesis's tracker.
inline constexpr SessionOptions kPlainSession{false, false, false, 3.0f, 0, {}};

struct SessionScratch {
  TrackerScratch fine;
  TrackerScratch coarse;  // for the coarse table; unused without one
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
  std::uint32_t search_cursor_ = 0;  // the next of the outer placements to vote
};

}  // namespace gabarit
