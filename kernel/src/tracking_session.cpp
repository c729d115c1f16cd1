#include "gabarit/tracking_session.hpp"

#include <array>

#include "gabarit/deterministic_math.hpp"
#include "gabarit/refinement.hpp"

namespace gabarit {
namespace {

// The recovery grid: (2 kSearchRings + 1)^2 ROI positions at 2 kSearchTurns + 1
// angle offsets (multiples of search_turn_deg). Ordered in shells, nearest
// first: shell = max(ring, |turn|) with ring = max(|i|, |j|); within a shell
// by ring, then |turn|. The first kSearchNear (ring <= 1 at turn 0) are voted
// in every lost frame, the rest search_budget at a time.
struct SearchPlacement {
  std::int8_t i = 0, j = 0;
  std::int8_t turn = 0;
};
constexpr int abs_of(int v) { return v < 0 ? -v : v; }
constexpr int max_of(int a, int b) { return a > b ? a : b; }
constexpr std::array<SearchPlacement, kSearchPlacementCount> make_search_placements() {
  std::array<SearchPlacement, kSearchPlacementCount> out{};
  std::size_t n = 0;
  const auto add = [&](int i, int j, int turn) {
    out[n++] = {static_cast<std::int8_t>(i), static_cast<std::int8_t>(j), static_cast<std::int8_t>(turn)};
  };
  for (int j = -1; j <= 1; ++j)
    for (int i = -1; i <= 1; ++i) add(i, j, 0);
  for (int shell = 0; shell <= max_of(kSearchRings, kSearchTurns); ++shell)
    for (int ring = 0; ring <= kSearchRings; ++ring)
      for (int t = 0; t <= kSearchTurns; ++t)
        for (int sign = 1; sign >= -1; sign -= 2) {
          if (max_of(ring, t) != shell || (t == 0 && sign < 0)) continue;
          for (int j = -ring; j <= ring; ++j)
            for (int i = -ring; i <= ring; ++i) {
              if (max_of(abs_of(i), abs_of(j)) != ring || (ring <= 1 && t == 0)) continue;
              add(i, j, sign * t);
            }
        }
  return out;
}
constexpr std::array<SearchPlacement, kSearchPlacementCount> kSearchPlacements = make_search_placements();
constexpr bool all_distinct() {
  for (std::size_t a = 0; a < kSearchPlacements.size(); ++a)
    for (std::size_t b = a + 1; b < kSearchPlacements.size(); ++b)
      if (kSearchPlacements[a].i == kSearchPlacements[b].i && kSearchPlacements[a].j == kSearchPlacements[b].j &&
          kSearchPlacements[a].turn == kSearchPlacements[b].turn)
        return false;
  return true;
}
static_assert(all_distinct() && kSearchPlacements[8].i == 1 && kSearchPlacements[8].j == 1 &&
                  kSearchPlacements[9].i == 0 && kSearchPlacements[9].turn == 1 && kSearchPlacements[10].turn == -1,
              "every placement once: the 9 near ones first, then ring 0 turned by +-1 step, shell by shell");

bool finite_pose(const Pose& p) noexcept {
  const auto ok = [](float v) { return v == v && v > -1.0e6f && v < 1.0e6f; };
  return ok(p.x) && ok(p.y) && ok(p.theta_deg);
}

TrackState state_of(Confidence c) noexcept { return c == Confidence::kHigh ? TrackState::kTracking : TrackState::kUncertain; }

}  // namespace

Status TrackingSession::start(const SessionOptions& options, const Pose& initial) noexcept {
  const bool search_ok = options.coarse_proposals >= 1 && options.coarse_proposals <= kMaxCoarseProposals &&
                         options.screen_stride >= 1 && options.search_interval >= 1;
  if (!valid(options.filter) || !search_ok || !finite_pose(initial) || initial.depth >= fine_.depth_count()) {
    return Status::kInvalidArgument;
  }
  if (coarse_ != nullptr && coarse_->depth_count() != fine_.depth_count()) return Status::kInvalidArgument;
  options_ = options;
  pose_ = last_confident_ = initial;
  motion_ = confident_motion_ = {};
  frames_since_confident_ = 0;
  search_cursor_[0] = search_cursor_[1] = 0;
  lost_frames_ = searches_ = 0;
  reference_ = 0.0f;
  lost_ = false;
  return Status::kOk;
}

void TrackingSession::begin_lost() noexcept {
  lost_ = true;
  lost_frames_ = searches_ = 0;
  search_cursor_[0] = search_cursor_[1] = 0;  // nearest placements first
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
    if (out.step.state == TrackState::kLost && options_.recover) begin_lost();
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
    if (options_.recover) begin_lost();
    out.state = TrackState::kLost;
  }
  out.pose = pose_;
  return Status::kOk;
}

Status TrackingSession::search(const ImageView& image, SessionScratch scratch, SessionResult& out) noexcept {
  // Every search_interval-th lost frame searches; the others only report lost.
  const std::uint32_t interval = options_.search_interval;
  if (lost_frames_++ % interval != 0) {
    out.state = TrackState::kLost;
    out.pose = pose_;
    return Status::kOk;
  }
  // Alternate searches: where the target would be at its last confident
  // velocity; where it was last seen.
  const bool extrapolate = searches_++ % 2 == 0;
  Pose centre = last_confident_;
  if (extrapolate) {
    const auto n = static_cast<float>(frames_since_confident_);
    centre.x += n * confident_motion_.vx;
    centre.y += n * confident_motion_.vy;
    centre.theta_deg += n * confident_motion_.vtheta;
  }
  // Each placement's fine vote goes to a shortlist of the three best scores;
  // each of those is then voted again from its own estimate (the target, once
  // centred in the ROI, scores far above clutter) and the best is kept.
  constexpr int kShortlist = 3;
  Pose shortlist[kShortlist];
  float shortlist_score[kShortlist] = {-1.0f, -1.0f, -1.0f};
  // A grid search with scratch for it detects features once, over the whole
  // search window, and scores each placement from them (map_features).
  const std::uint32_t reach = search_reach(fine_);
  const bool shared = coarse_ == nullptr && 2 * reach + 1 <= 0xFFFFu &&
                      scratch.search_features.size() >= search_feature_capacity(fine_);
  ImageWindow searched;
  std::span<const RoiPoint> detected;
  if (shared) {
    const auto r = static_cast<std::int32_t>(reach);
    const auto side = static_cast<std::uint16_t>(2 * reach + 1);
    searched = {round_to_int(centre.x) - r, round_to_int(centre.y) - r, side, side};
    FeatureCount found;
    GABARIT_TRY(extract_features(image, searched, detector_.kind, detector_.threshold, scratch.search_features, found));
    // Screening votes every screen_stride-th feature (in raster order): the
    // target, when under a placement's ROI, still stands far above clutter,
    // and the shortlist is voted again in full below.
    std::uint32_t kept = 0;
    for (std::uint32_t k = 0; k < found.written; k += options_.screen_stride) {
      scratch.search_features[kept++] = scratch.search_features[k];
    }
    detected = scratch.search_features.first(kept);
  }
  const std::uint32_t per_depth = fine_.cell_count() / fine_.depth_count();
  const std::uint32_t screen_depth = pose_.depth < fine_.depth_count() ? pose_.depth : 0u;
  const std::uint32_t screen_begin = screen_depth * per_depth, screen_end = screen_begin + per_depth;
  const auto place = [&](const Pose& p) -> Status {
    StepResult trial;
    if (shared) {
      // Screening: the cells of the last known depth only (depth changes
      // slowly, and edges differ little between neighbouring depths); the
      // shortlist is voted over every depth below.
      PreparedFrame frame;
      GABARIT_TRY(map_features(fine_, detected, searched, p, scratch.fine, frame));
      for (std::uint32_t c = screen_begin; c < screen_end; ++c) scratch.fine.counters[c] = 0;
      VoteTally tally;
      GABARIT_TRY(accumulate_votes_for_cells(fine_, scratch.fine.features.first(frame.features), scratch.fine.counters,
                                             screen_begin, screen_end, tally));
      CellScore best{kNoCell, 0, 0};
      for (std::uint32_t c = screen_begin; c < screen_end; ++c) {
        const CellScore cs{c, scratch.fine.counters[c], fine_.stencil_size(c)};
        if (best.cell == kNoCell || ranks_before(cs, best)) best = cs;
      }
      trial.best = best;
      trial.score = normalised_score(best);
      trial.pose = pose_of_cell(fine_, best.cell, p, frame.roi_centre_x, frame.roi_centre_y);
    } else {
      GABARIT_TRY(track_step(fine_, detector_, image, p, scratch.fine, trial));
    }
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
  if (coarse_ != nullptr) {
    // The coarse vote only proposes where to look: its best cells are each
    // checked by the fine table (in clutter the coarse winner alone is often
    // wrong, its stencils being large), and the fine votes decide.
    StepResult coarse_step;
    GABARIT_TRY(track_step(*coarse_, detector_, image, centre, scratch.coarse, coarse_step));
    out.searched_coarse = true;
    CellScore proposals[kMaxCoarseProposals];
    const std::uint32_t wanted = options_.coarse_proposals < coarse_->cell_count() ? options_.coarse_proposals : coarse_->cell_count();
    GABARIT_TRY(select_top_cells(*coarse_, scratch.coarse.counters, std::span<CellScore>(proposals, wanted)));
    for (std::uint32_t k = 0; k < wanted && proposals[k].votes > 0; ++k) {
      GABARIT_TRY(place(pose_of_cell(*coarse_, proposals[k].cell, centre, coarse_step.roi_centre_x, coarse_step.roi_centre_y)));
    }
  } else {
    // The fine table on a grid of placements around the centre.
    const float sx = search_step(fine_.axis_x()), sy = search_step(fine_.axis_y());
    const auto place_on_grid = [&](const SearchPlacement& at) -> Status {
      Pose p = centre;
      p.x += static_cast<float>(at.i) * sx;
      p.y += static_cast<float>(at.j) * sy;
      p.theta_deg += static_cast<float>(at.turn) * options_.search_turn_deg;
      return place(p);
    };
    constexpr std::uint32_t kOuter = kSearchPlacements.size() - kSearchNear;
    for (std::uint32_t k = 0; k < kSearchNear; ++k) GABARIT_TRY(place_on_grid(kSearchPlacements[k]));
    // Each centre has its own cursor, so each one's grid is covered in turn.
    std::uint32_t& cursor = search_cursor_[extrapolate ? 0 : 1];
    const std::uint32_t budget = options_.search_budget == 0 || options_.search_budget > kOuter ? kOuter : options_.search_budget;
    for (std::uint32_t k = 0; k < budget; ++k) {
      GABARIT_TRY(place_on_grid(kSearchPlacements[kSearchNear + (cursor + k) % kOuter]));
    }
    cursor = (cursor + budget) % kOuter;
  }
  Pose from = centre;
  float best = -1.0f;
  for (int k = 0; k < kShortlist && shortlist_score[k] >= 0.0f; ++k) {
    StepResult again;
    GABARIT_TRY(track_step(fine_, detector_, image, shortlist[k], scratch.fine, again));
    if (again.score > best) {
      best = again.score;
      from = again.pose;
    }
  }
  // The best voted once more from its own estimate, which centres it better
  // still (and leaves its counters for refinement).
  GABARIT_TRY(track_step(fine_, detector_, image, from, scratch.fine, out.step));
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
