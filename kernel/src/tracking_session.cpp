#include "gabarit/tracking_session.hpp"

#include "gabarit/refinement.hpp"

namespace gabarit {
namespace {

TrackState state_of(Confidence c) noexcept { return c == Confidence::kHigh ? TrackState::kTracking : TrackState::kUncertain; }

}  // namespace

Status TrackingSession::start(const SessionOptions& options, const Pose& initial) noexcept {
  if (!valid(options.filter) || !valid(options.recovery) || !pose_in_range(initial) || initial.depth >= fine_.depth_count()) {
    return Status::kInvalidArgument;
  }
  if (coarse_ != nullptr && coarse_->depth_count() != fine_.depth_count()) return Status::kInvalidArgument;
  options_ = options;
  pose_ = initial;
  last_confident_ = {initial, {}, 0};
  filter_.reset(options.filter);
  search_.reset();
  lost_ = false;
  return Status::kOk;
}

void TrackingSession::begin_lost() noexcept {
  lost_ = true;
  search_.reset();  // nearest placements first
}

Status TrackingSession::step(const ImageView& image, SessionScratch scratch, SessionResult& out) noexcept {
  out = SessionResult{};
  ++last_confident_.frames_since;
  GABARIT_TRY(lost_ ? recover(image, scratch, out) : track_fine(image, scratch, out));
  if (stack_ != nullptr && out.state != TrackState::kLost) {
    GABARIT_TRY(depth_by_intensity(image, pose_, *stack_, pose_.depth));
    out.pose = pose_;
    // The finer angle is reported, not fed back: the votes keep tracking from
    // their own estimate (fed back, it moved the next frames' ROI and cost
    // more than it gained on the microscope scene).
    GABARIT_TRY(angle_by_intensity(image, pose_, *stack_, out.pose.theta_deg));
  }
  if (out.confidence == Confidence::kHigh) last_confident_ = {pose_, filter_.state(), 0};
  return Status::kOk;
}

Status TrackingSession::track_fine(const ImageView& image, SessionScratch scratch, SessionResult& out) noexcept {
  const Pose predicted = options_.motion_filter ? filter_.predict(pose_) : pose_;
  GABARIT_TRY(track_step(fine_, detector_, image, predicted, scratch.fine, out.step));
  const std::int32_t cx = out.step.roi_centre_x, cy = out.step.roi_centre_y;
  const auto refined_pose = [&](std::uint32_t cell) {
    SubCellOffset o;
    if (options_.refine) o = refine_within_cell(fine_, scratch.fine.counters, cell);
    return pose_of_cell(fine_, cell, predicted, cx, cy, o.x, o.y, o.theta_deg);
  };

  if (!options_.motion_filter) {
    // The thesis's loop: the best cell, whatever its score.
    out.score = out.step.score;
    out.confidence = filter_.grade(out.step.score, normalised_score(out.step.runner_up));
    out.state = out.step.state;
    if (out.step.state != TrackState::kLost) pose_ = refined_pose(out.step.best.cell);
    if (out.step.state == TrackState::kLost && options_.recover) begin_lost();
    out.pose = pose_;
    return Status::kOk;
  }

  GatedChoice choice;
  GABARIT_TRY(filter_.choose(fine_, scratch.fine.counters, predicted, cx, cy, pose_.depth, choice));
  Confidence confidence = Confidence::kNone;
  if (choice.found) {
    out.score = choice.score;
    confidence = filter_.grade(choice.score, choice.next_score);
    if (choice.outranked && confidence == Confidence::kHigh) confidence = Confidence::kIntermediate;
  }
  if (confidence != Confidence::kNone) {
    const Pose measured = refined_pose(choice.cell.cell);
    filter_.update(confidence, pose_, measured);
    pose_ = measured;
  } else {
    pose_ = predicted;
    filter_.coast();
  }
  out.confidence = confidence;
  out.state = state_of(confidence);
  if (filter_.lost()) {
    if (options_.recover) begin_lost();
    out.state = TrackState::kLost;
  }
  out.pose = pose_;
  return Status::kOk;
}

Status TrackingSession::recover(const ImageView& image, SessionScratch scratch, SessionResult& out) noexcept {
  SearchResult found;
  GABARIT_TRY(search_.run(image, options_.recovery, last_confident_, pose_.depth, scratch, found));
  out.searched_coarse = found.searched_coarse;
  out.state = TrackState::kLost;
  out.pose = pose_;
  if (!found.searched) return Status::kOk;
  out.step = found.vote;
  out.score = out.step.score;
  const bool confident = out.step.best.votes > 0 &&
                         filter_.classify(out.score, normalised_score(out.step.runner_up)) == Confidence::kHigh;
  out.confidence = confident ? Confidence::kHigh : Confidence::kNone;
  if (confident) {
    SubCellOffset o;
    if (options_.refine) o = refine_within_cell(fine_, scratch.fine.counters, out.step.best.cell);
    pose_ = pose_of_cell(fine_, out.step.best.cell, found.from, out.step.roi_centre_x, out.step.roi_centre_y, o.x, o.y,
                         o.theta_deg);
    filter_.restart();
    lost_ = false;
    out.reacquired = true;
    out.state = TrackState::kUncertain;
    out.pose = pose_;
  }
  return Status::kOk;
}

}  // namespace gabarit
