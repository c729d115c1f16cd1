#include "gabarit/recovery_search.hpp"

#include <array>

#include "gabarit/assert.hpp"
#include "gabarit/deterministic_math.hpp"
#include "gabarit/finder_search.hpp"

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
// Each (i, j, turn) once: one flag per grid position, linear time (clang
// bounds the steps of a constant evaluation).
constexpr bool all_distinct() {
  constexpr int kSide = 2 * kSearchRings + 1, kTurns = 2 * kSearchTurns + 1;
  bool seen[kSide * kSide * kTurns] = {};
  for (const SearchPlacement& p : kSearchPlacements) {
    const int at = ((p.turn + kSearchTurns) * kSide + (p.j + kSearchRings)) * kSide + (p.i + kSearchRings);
    if (seen[at]) return false;
    seen[at] = true;
  }
  return true;
}
static_assert(all_distinct() && kSearchPlacements[8].i == 1 && kSearchPlacements[8].j == 1 &&
                  kSearchPlacements[9].i == 0 && kSearchPlacements[9].turn == 1 && kSearchPlacements[10].turn == -1,
              "every placement once: the 9 near ones first, then ring 0 turned by +-1 step, shell by shell");

// Lost periods longer than this extrapolate no further (the centre is clamped
// to the frame anyway); it keeps turn / 360 inside round_to_int's range.
constexpr std::uint32_t kMaxExtrapolatedFrames = 1u << 20;

float clamp_to(float v, float lo, float hi) noexcept { return v < lo ? lo : (v > hi ? hi : v); }

}  // namespace

bool valid(const RecoveryOptions& o) noexcept {
  return o.coarse_proposals >= 1 && o.coarse_proposals <= kMaxCoarseProposals && o.screen_stride >= 1 && o.interval >= 1 &&
         within_limit(o.turn_deg, 360.0f);
}

namespace {

// Where a search is centred: the last confident pose, or (extrapolate) where
// the target would be at its last confident velocity. However long the target
// has been lost, the extrapolated centre stays where a target can be seen:
// inside the frame, and within half a turn of the last confident angle (a
// rotation is periodic). Without this a long lost period walked the centre
// out of range (past +-1e6 px after ~3e5 frames at a few px per frame) and
// every search failed.
Pose search_centre(const LastSighting& last, bool extrapolate, const ImageView& image) noexcept {
  Pose centre = last.pose;
  if (!extrapolate) return centre;
  const float n = static_cast<float>(last.frames_since < kMaxExtrapolatedFrames ? last.frames_since : kMaxExtrapolatedFrames);
  centre.x += n * last.motion.vx;
  centre.y += n * last.motion.vy;
  if (image.valid()) {
    centre.x = clamp_to(centre.x, 0.0f, static_cast<float>(image.width - 1));
    centre.y = clamp_to(centre.y, 0.0f, static_cast<float>(image.height - 1));
  }
  const float turn = n * last.motion.vtheta;
  centre.theta_deg += turn - 360.0f * static_cast<float>(round_to_int(turn / 360.0f));
  return centre;
}

// The three best placements by score, best first (a later equal score does
// not displace an earlier one).
struct SearchShortlist {
  static constexpr int kSize = 3;
  Pose pose[kSize];
  float score[kSize] = {-1.0f, -1.0f, -1.0f};
  void offer(const Pose& p, float s) noexcept {
    for (int k = 0; k < kSize; ++k) {
      if (s > score[k]) {
        for (int m = kSize - 1; m > k; --m) {
          pose[m] = pose[m - 1];
          score[m] = score[m - 1];
        }
        pose[k] = p;
        score[k] = s;
        return;
      }
    }
  }
};

}  // namespace

Status RecoverySearch::run(const ImageView& image, const RecoveryOptions& options, const LastSighting& last,
                           std::uint16_t screen_depth, SessionScratch scratch, SearchResult& out) noexcept {
  GABARIT_ASSERT(valid(options));
  out = SearchResult{};
  // Every search_interval-th lost frame searches; the others only report lost.
  if (lost_frames_++ % options.interval != 0) return Status::kOk;
  out.searched = true;
  // Alternate searches: where the target would be at its last confident
  // velocity; where it was last seen.
  const bool extrapolate = searches_++ % 2 == 0;
  const Pose centre = search_centre(last, extrapolate, image);
  // Each placement's fine vote goes to a shortlist of the three best scores;
  // each of those is then voted again from its own estimate (the target, once
  // centred in the ROI, scores far above clutter) and the best is kept.
  SearchShortlist shortlist;
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
    GABARIT_TRY(extract_features(image, searched, detector_.kind, detector_.threshold, scratch.search_features, found,
                                 scratch.fine.magnitudes));
    out.work += feature_extraction_work(std::uint64_t{side} * side);
    // Screening votes every screen_stride-th feature (in raster order): the
    // target, when under a placement's ROI, still stands far above clutter,
    // and the shortlist is voted again in full below.
    std::uint32_t kept = 0;
    for (std::uint32_t k = 0; k < found.written; k += options.screen_stride) {
      scratch.search_features[kept++] = scratch.search_features[k];
    }
    detected = scratch.search_features.first(kept);
  }
  const CellRange screened = fine_.depth_cells(screen_depth < fine_.depth_count() ? screen_depth : std::uint16_t{0});
  const auto place = [&](const Pose& p) -> Status {
    StepResult trial;
    if (shared) {
      // Screening: the cells of the last known depth only (depth changes
      // slowly, and edges differ little between neighbouring depths); the
      // shortlist is voted over every depth below.
      PreparedFrame frame;
      GABARIT_TRY(map_features(fine_, image, detected, searched, p, scratch.fine, frame));
      for (std::uint32_t c = screened.begin; c < screened.end; ++c) scratch.fine.counters[c] = 0;
      VoteTally tally;
      GABARIT_TRY(accumulate_votes_for_cells(fine_, scratch.fine.features.first(frame.features), scratch.fine.counters,
                                             screened.begin, screened.end, tally));
      out.work += tally.votes;
      const CellScore best = best_cell_in(fine_, scratch.fine.counters, screened);
      trial.best = best;
      trial.score = normalised_score(best);
      trial.pose = pose_of_cell(fine_, best.cell, p, frame.roi_centre_x, frame.roi_centre_y);
    } else {
      GABARIT_TRY(track_step(fine_, detector_, image, p, scratch.fine, trial));
      out.work += track_step_work(fine_, trial);
    }
    if (trial.best.votes != 0) shortlist.offer(trial.pose, trial.score);
    return Status::kOk;
  };
  if (coarse_ != nullptr) {
    // The coarse vote only proposes where to look: its best cells are each
    // checked by the fine table (in clutter the coarse winner alone is often
    // wrong, its stencils being large), and the fine votes decide.
    StepResult coarse_step;
    GABARIT_TRY(track_step(*coarse_, detector_, image, centre, scratch.coarse, coarse_step));
    out.work += track_step_work(*coarse_, coarse_step);
    out.searched_coarse = true;
    CellScore proposals[kMaxCoarseProposals];
    const std::uint32_t wanted = options.coarse_proposals < coarse_->cell_count() ? options.coarse_proposals : coarse_->cell_count();
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
      p.theta_deg += static_cast<float>(at.turn) * options.turn_deg;
      return place(p);
    };
    constexpr std::uint32_t kOuter = kSearchPlacements.size() - kSearchNear;
    for (std::uint32_t k = 0; k < kSearchNear; ++k) GABARIT_TRY(place_on_grid(kSearchPlacements[k]));
    // Each centre has its own cursor, so each one's grid is covered in turn.
    std::uint32_t& cursor = cursor_[extrapolate ? 0 : 1];
    const std::uint32_t budget = options.budget == 0 || options.budget > kOuter ? kOuter : options.budget;
    for (std::uint32_t k = 0; k < budget; ++k) {
      GABARIT_TRY(place_on_grid(kSearchPlacements[kSearchNear + (cursor + k) % kOuter]));
    }
    cursor = (cursor + budget) % kOuter;
  }
  Pose from = centre;
  float best = -1.0f;
  for (int k = 0; k < SearchShortlist::kSize && shortlist.score[k] >= 0.0f; ++k) {
    StepResult again;
    GABARIT_TRY(track_step(fine_, detector_, image, shortlist.pose[k], scratch.fine, again));
    out.work += track_step_work(fine_, again);
    if (again.score > best) {
      best = again.score;
      from = again.pose;
    }
  }
  // The best voted once more from its own estimate, which centres it better
  // still (and leaves its counters for refinement).
  GABARIT_TRY(track_step(fine_, detector_, image, from, scratch.fine, out.vote));
  out.work += track_step_work(fine_, out.vote);
  out.from = from;
  return Status::kOk;
}

}  // namespace gabarit
