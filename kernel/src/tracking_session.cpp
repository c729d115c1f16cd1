#include "gabarit/tracking_session.hpp"

#include <array>

#include "gabarit/refinement.hpp"

namespace gabarit {
namespace {

// The recovery grid: 7 x 7 placements at three turns, nearest rings first
// (ring = max(|i|, |j|)), turn 0 before the others within a ring. The first
// kSearchNear (ring <= 1 at turn 0) are voted in every lost frame.
struct SearchPlacement {
  std::int8_t i = 0, j = 0;
  std::uint8_t turn = 0;
};
constexpr std::uint32_t kSearchNear = 9;
constexpr std::array<SearchPlacement, 147> make_search_placements() {
  std::array<SearchPlacement, 147> out{};
  std::size_t n = 0;
  const auto ring_of = [](int i, int j) { return (i < 0 ? -i : i) > (j < 0 ? -j : j) ? (i < 0 ? -i : i) : (j < 0 ? -j : j); };
  for (int pass = 0; pass < 2; ++pass)
    for (int ring = 0; ring <= 3; ++ring)
      for (int turn = 0; turn < 3; ++turn)
        for (int j = -ring; j <= ring; ++j)
          for (int i = -ring; i <= ring; ++i) {
            const bool near = turn == 0 && ring <= 1;
            if (ring_of(i, j) == ring && near == (pass == 0))
              out[n++] = {static_cast<std::int8_t>(i), static_cast<std::int8_t>(j), static_cast<std::uint8_t>(turn)};
          }
  return out;
}
constexpr std::array<SearchPlacement, 147> kSearchPlacements = make_search_placements();
static_assert(kSearchPlacements[0].i == 0 && kSearchPlacements[0].j == 0 && kSearchPlacements[8].turn == 0 &&
                  kSearchPlacements[9].i == 0 && kSearchPlacements[9].turn == 1 && kSearchPlacements[146].turn == 2,
              "the 9 near placements (turn 0, ring <= 1) first, then ring 0 turned, ring by ring");

bool finite_pose(const Pose& p) noexcept {
  const auto ok = [](float v) { return v == v && v > -1.0e6f && v < 1.0e6f; };
  return ok(p.x) && ok(p.y) && ok(p.theta_deg);
}

TrackState state_of(Confidence c) noexcept { return c == Confidence::kHigh ? TrackState::kTracking : TrackState::kUncertain; }

}  // namespace

Status TrackingSession::start(const SessionOptions& options, const Pose& initial) noexcept {
  if (!valid(options.filter) || !finite_pose(initial) || initial.depth >= fine_.depth_count()) return Status::kInvalidArgument;
  if (coarse_ != nullptr && coarse_->depth_count() != fine_.depth_count()) return Status::kInvalidArgument;
  options_ = options;
  pose_ = last_confident_ = initial;
  motion_ = confident_motion_ = {};
  frames_since_confident_ = 0;
  search_cursor_ = 0;
  reference_ = 0.0f;
  lost_ = false;
  return Status::kOk;
}

// Classifies a score and keeps the reference score up to date. The first
// scored frame (its pose was given) sets the reference.
Confidence TrackingSession::grade(float score, float next_score) noexcept {
  if (reference_ <= 0.0f) reference_ = score;
  const Confidence c = classify(score, next_score, reference_, options_.filter);
  if (c == Confidence::kHigh) {
    const float g = options_.filter.reference_gain;
    reference_ = (1.0f - g) * reference_ + g * score;
  }
  return c;
}

Status TrackingSession::step(const ImageView& image, SessionScratch scratch, SessionResult& out) noexcept {
  out = SessionResult{};
  ++frames_since_confident_;
  GABARIT_TRY(lost_ ? search(image, scratch, out) : track_fine(image, scratch, out));
  if (stack_ != nullptr && out.state != TrackState::kLost) {
    GABARIT_TRY(depth_by_intensity(image, pose_, *stack_, pose_.depth));
    out.pose = pose_;
    // The finer angle is reported, not fed back: the votes keep tracking from
    // their own estimate (fed back, it moved the next frames' ROI and cost
    // more than it gained on the microscope scene).
    GABARIT_TRY(angle_by_intensity(image, pose_, *stack_, out.pose.theta_deg));
  }
  if (out.confidence == Confidence::kHigh) {
    last_confident_ = pose_;
    confident_motion_ = motion_;
    frames_since_confident_ = 0;
  }
  return Status::kOk;
}

Status TrackingSession::track_fine(const ImageView& image, SessionScratch scratch, SessionResult& out) noexcept {
  Pose predicted = pose_;
  if (options_.motion_filter) {
    predicted.x += motion_.vx;
    predicted.y += motion_.vy;
    predicted.theta_deg += motion_.vtheta;
  }
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
    out.confidence = grade(out.step.score, normalised_score(out.step.runner_up));
    out.state = out.step.state;
    if (out.step.state != TrackState::kLost) pose_ = refined_pose(out.step.best.cell);
    if (out.step.state == TrackState::kLost && options_.recover) lost_ = true;
    out.pose = pose_;
    return Status::kOk;
  }

  // The best cells in rank order; the first within the gate is the measurement.
  CellScore candidates[kMaxCandidates];
  const std::size_t n = fine_.cell_count() < options_.filter.candidates ? fine_.cell_count() : options_.filter.candidates;
  GABARIT_TRY(select_top_cells(fine_, scratch.fine.counters, std::span<CellScore>(candidates, n)));
  const float gate = options_.filter.gate_px + motion_.uncertainty_px;
  std::size_t chosen = n;
  for (std::size_t i = 0; i < n && candidates[i].votes > 0; ++i) {
    const Pose p = pose_of_cell(fine_, candidates[i].cell, predicted, cx, cy);
    const float dx = p.x - predicted.x, dy = p.y - predicted.y;
    if (dx * dx + dy * dy <= gate * gate) {
      chosen = i;
      break;
    }
  }
  // Depth changes slowly: a cell of another depth must beat the best cell of
  // the current depth by depth_switch_margin (relative) to change it.
  if (chosen < n && fine_.cell(candidates[chosen].cell).depth != pose_.depth && pose_.depth < fine_.depth_count()) {
    const std::uint32_t per_depth = fine_.cell_count() / fine_.depth_count();
    CellScore same{kNoCell, 0, 0};
    for (std::uint32_t c = pose_.depth * per_depth; c < (pose_.depth + 1u) * per_depth; ++c) {
      const CellScore s{c, scratch.fine.counters[c], fine_.stencil_size(c)};
      if (same.cell == kNoCell || ranks_before(s, same)) same = s;
    }
    const Pose p = pose_of_cell(fine_, same.cell, predicted, cx, cy);
    const float dx = p.x - predicted.x, dy = p.y - predicted.y;
    if (same.votes > 0 && dx * dx + dy * dy <= gate * gate &&
        normalised_score(candidates[chosen]) < (1.0f + options_.filter.depth_switch_margin) * normalised_score(same)) {
      candidates[chosen] = same;
    }
  }
  Confidence confidence = Confidence::kNone;
  if (chosen < n) {
    out.score = normalised_score(candidates[chosen]);
    const float next = chosen + 1 < n ? normalised_score(candidates[chosen + 1]) : 0.0f;
    confidence = grade(out.score, next);
    if (chosen > 0 && confidence == Confidence::kHigh) confidence = Confidence::kIntermediate;  // a distractor outranked it
  }
  const MotionFilterParams& f = options_.filter;
  if (confidence != Confidence::kNone) {
    const Pose measured = refined_pose(candidates[chosen].cell);
    const float k = confidence == Confidence::kHigh ? f.k1 : f.k2;
    motion_.vx = (1.0f - k) * motion_.vx + k * (measured.x - pose_.x);
    motion_.vy = (1.0f - k) * motion_.vy + k * (measured.y - pose_.y);
    motion_.vtheta = (1.0f - k) * motion_.vtheta + k * (measured.theta_deg - pose_.theta_deg);
    motion_.uncertainty_px = confidence == Confidence::kHigh ? 0.0f : motion_.uncertainty_px + f.u1;
    pose_ = measured;
  } else {
    pose_ = predicted;
    motion_.vx *= f.k3;
    motion_.vy *= f.k3;
    motion_.vtheta *= f.k3;
    motion_.uncertainty_px += f.u2;
  }
  out.confidence = confidence;
  out.state = state_of(confidence);
  if (motion_.uncertainty_px > f.lost_uncertainty_px) {
    lost_ = options_.recover;
    out.state = TrackState::kLost;
  }
  out.pose = pose_;
  return Status::kOk;
}

Status TrackingSession::search(const ImageView& image, SessionScratch scratch, SessionResult& out) noexcept {
  // Odd frames: where the target would be at its last confident velocity;
  // even frames: where it was last seen.
  Pose centre = last_confident_;
  if (frames_since_confident_ % 2 == 1) {
    const auto n = static_cast<float>(frames_since_confident_);
    centre.x += n * confident_motion_.vx;
    centre.y += n * confident_motion_.vy;
    centre.theta_deg += n * confident_motion_.vtheta;
  }
  Pose from = centre;
  if (coarse_ != nullptr) {
    // The coarse vote only proposes where to look; the fine vote decides.
    StepResult coarse_step;
    GABARIT_TRY(track_step(*coarse_, detector_, image, centre, scratch.coarse, coarse_step));
    out.searched_coarse = true;
    if (coarse_step.best.votes > 0) from = coarse_step.pose;
    GABARIT_TRY(track_step(fine_, detector_, image, from, scratch.fine, out.step));
  } else {
    // The fine table on a grid of placements; the best-scoring one is kept
    // (its counters are recomputed below so refinement sees them).
    const Axis ax = fine_.axis_x(), ay = fine_.axis_y();
    const float sx = ax.max - ax.min + (ax.cells > 1 ? (ax.max - ax.min) / static_cast<float>(ax.cells - 1) : 1.0f);
    const float sy = ay.max - ay.min + (ay.cells > 1 ? (ay.max - ay.min) / static_cast<float>(ay.cells - 1) : 1.0f);
    const float turns[3] = {0.0f, options_.search_turn_deg, -options_.search_turn_deg};
    // The three best placements by score, then each voted again from its own
    // estimate: the target, once centred in the ROI, scores far above clutter.
    constexpr int kShortlist = 3;
    Pose shortlist[kShortlist];
    float shortlist_score[kShortlist] = {-1.0f, -1.0f, -1.0f};
    const auto place = [&](const SearchPlacement& at) -> Status {
      Pose p = centre;
      p.x += static_cast<float>(at.i) * sx;
      p.y += static_cast<float>(at.j) * sy;
      p.theta_deg += turns[at.turn];
      StepResult trial;
      GABARIT_TRY(track_step(fine_, detector_, image, p, scratch.fine, trial));
      if (trial.best.votes == 0) return Status::kOk;
      for (int k = 0; k < kShortlist; ++k) {
        if (trial.score > shortlist_score[k]) {
          for (int m = kShortlist - 1; m > k; --m) {
            shortlist[m] = shortlist[m - 1];
            shortlist_score[m] = shortlist_score[m - 1];
          }
          shortlist[k] = trial.pose;
          shortlist_score[k] = trial.score;
          break;
        }
      }
      return Status::kOk;
    };
    constexpr std::uint32_t kOuter = kSearchPlacements.size() - kSearchNear;
    for (std::uint32_t k = 0; k < kSearchNear; ++k) GABARIT_TRY(place(kSearchPlacements[k]));
    const std::uint32_t budget = options_.search_budget == 0 || options_.search_budget > kOuter ? kOuter : options_.search_budget;
    for (std::uint32_t k = 0; k < budget; ++k) {
      GABARIT_TRY(place(kSearchPlacements[kSearchNear + (search_cursor_ + k) % kOuter]));
    }
    search_cursor_ = (search_cursor_ + budget) % kOuter;
    float best = -1.0f;
    for (int k = 0; k < kShortlist && shortlist_score[k] >= 0.0f; ++k) {
      StepResult again;
      GABARIT_TRY(track_step(fine_, detector_, image, shortlist[k], scratch.fine, again));
      if (again.score > best) {
        best = again.score;
        from = shortlist[k];
      }
    }
    GABARIT_TRY(track_step(fine_, detector_, image, from, scratch.fine, out.step));
  }
  out.score = out.step.score;
  const float next = normalised_score(out.step.runner_up);
  const bool confident = out.step.best.votes > 0 &&
                         classify(out.score, next, reference_, options_.filter) == Confidence::kHigh;
  out.confidence = confident ? Confidence::kHigh : Confidence::kNone;
  if (confident) {
    SubCellOffset o;
    if (options_.refine) o = refine_within_cell(fine_, scratch.fine.counters, out.step.best.cell);
    pose_ = pose_of_cell(fine_, out.step.best.cell, from, out.step.roi_centre_x, out.step.roi_centre_y, o.x, o.y, o.theta_deg);
    motion_ = {};
    lost_ = false;
    out.reacquired = true;
    out.state = TrackState::kUncertain;
  } else {
    out.state = TrackState::kLost;
  }
  out.pose = pose_;
  return Status::kOk;
}

}  // namespace gabarit
