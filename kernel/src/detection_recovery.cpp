#include "gabarit/detection_recovery.hpp"

#include "gabarit/deterministic_math.hpp"

namespace gabarit {

namespace {
float distance_squared(const Pose& a, const Pose& b) noexcept {
  const float dx = a.x - b.x, dy = a.y - b.y;
  return dx * dx + dy * dy;
}
// The table's largest step along an axis between two frames.
float axis_bound(const Axis& a) noexcept { return a.max > -a.min ? a.max : -a.min; }
// The model image's larger side.
float model_side(const TableView& table) noexcept {
  return static_cast<float>(table.model_width() > table.model_height() ? table.model_width() : table.model_height());
}
// The model's points' larger extent: the ROI less the translations' span
// (the model image may have a margin of background around them).
float points_extent(const TableView& table) noexcept {
  const float w = static_cast<float>(table.roi_width()) - (table.axis_x().max - table.axis_x().min);
  const float h = static_cast<float>(table.roi_height()) - (table.axis_y().max - table.axis_y().min);
  return w > h ? w : h;
}
}  // namespace

float DetectionRecovery::frame_bound_squared() const noexcept {
  const float bx = axis_bound(finder_.table().axis_x()), by = axis_bound(finder_.table().axis_y());
  return bx * bx + by * by;
}

bool DetectionRecovery::within_table_reach(const LastSighting& last, const Pose& pose) const noexcept {
  const float frames = static_cast<float>(last.frames_since) + 1.0f;
  return distance_squared(pose, last.pose) <= frames * frames * frame_bound_squared();
}

bool DetectionRecovery::within_reach(const LastSighting& last, const Pose& pose) const noexcept {
  if (is_copy(last, pose, last.frames_since)) return false;
  if (lookalike_d2_ > 0.0f && distance_squared(pose, last.pose) > 0.25f * lookalike_d2_) return false;  // beyond the midpoint
  return within_table_reach(last, pose);
}

// Whether `pose`, seen `since` frames after the target's last sighting, is
// the look-alike followed since that sighting: where it can have got to
// since it was seen, and nearer there than the last sighting.
bool DetectionRecovery::is_copy(const LastSighting& last, const Pose& pose, std::uint32_t since) const noexcept {
  if (!copy_known_ || !copies_distinct_ || since < copy_since_ || last.pose.x != copy_last_.x || last.pose.y != copy_last_.y ||
      last.pose.theta_deg != copy_last_.theta_deg)
    return false;
  const float frames = static_cast<float>(since - copy_since_) + 1.0f;
  const float d2 = distance_squared(pose, copy_);
  return d2 <= frames * frames * frame_bound_squared() && d2 < distance_squared(pose, last.pose);
}

void DetectionRecovery::note_copy(const LastSighting& last, const Pose& pose) noexcept {
  copy_known_ = true;
  copy_ = pose;
  copy_last_ = last.pose;
  copy_since_ = search_since_;
}

// The detection of a search's to take (`count` for none), the look-alike
// followed set aside first (and noted where it is now, or first noted).
std::uint32_t DetectionRecovery::choose(Detection* found, std::uint32_t& count, const LastSighting& last) noexcept {
  std::uint32_t copy = count;
  for (std::uint32_t j = 0; j < count; ++j)
    if (is_copy(last, found[j].pose, search_since_) &&
        (copy == count || distance_squared(found[j].pose, copy_) < distance_squared(found[copy].pose, copy_)))
      copy = j;
  if (copy < count) {
    note_copy(last, found[copy].pose);
    for (std::uint32_t j = copy + 1; j < count; ++j) found[j - 1] = found[j];
    --count;
    // Where the look-alike is, the target is not: the rest are judged by
    // the table's reach alone (the midpoint bound stands for a copy whose
    // place is unknown).
    std::uint32_t k = 0;
    while (k < count && !within_table_reach(last, found[k].pose)) ++k;
    return k;
  }
  const std::uint32_t k = note_lookalikes(found, count, copies_distinct_) ? nearest_alike(found, count, last) : best_within_reach(found, count, last);
  if (copies_distinct_) {
    // A look-alike known, the target hidden: the best alike detection not
    // taken is the copy, followed from now on until the target is seen again.
    for (std::uint32_t j = 0; j < count; ++j)
      if (j != k && found[j].score >= kLookalikeRatio * target_score_) {
        note_copy(last, found[j].pose);
        break;
      }
  }
  return k;
}

bool DetectionRecovery::note_lookalikes(const Detection* found, std::uint32_t count, bool by_extent) noexcept {
  if (!(target_score_ > 0.0f)) return false;  // no survey: nothing to compare with
  // Apart: two per-frame bounds, and the model image's larger side (shifted
  // along itself, an elongated or self-similar object matches well: that
  // is the target, not a copy of it); by_extent (where the look-alikes
  // stand clear of the clutter, note_survey), the model's points' extent:
  // two objects no nearer than that do not overlap.
  const float side = by_extent ? points_extent(finder_.table()) : model_side(finder_.table());
  const float bound2 = 4.0f * frame_bound_squared();
  const float apart = side * side > bound2 ? side * side : bound2;
  const float alike = kLookalikeRatio * target_score_;
  bool seen = false;
  for (std::uint32_t i = 0; i < count; ++i)
    for (std::uint32_t j = i + 1; j < count; ++j) {
      const float d2 = distance_squared(found[i].pose, found[j].pose);
      if (found[i].score < alike || found[j].score < alike || d2 <= apart) continue;
      if (lookalike_d2_ == 0.0f || d2 < lookalike_d2_) lookalike_d2_ = d2;
      seen = true;
    }
  return seen;
}

void DetectionRecovery::reset() noexcept {
  lost_frames_ = 0;
  following_ = false;
  if (purpose_ == Purpose::kRecovery) {
    search_.cancel();
    purpose_ = Purpose::kNone;
  }
}

void DetectionRecovery::restart_survey() noexcept {
  surveyed_ = false;
  copy_known_ = false;
  copies_distinct_ = false;
  lookalike_d2_ = 0.0f;
  target_score_ = 0.0f;
  if (purpose_ == Purpose::kSurvey) {
    search_.cancel();
    purpose_ = Purpose::kNone;
  }
}

DetectionRecovery::Window DetectionRecovery::reach_window(const ImageView& image, const LastSighting& last,
                                                          std::uint32_t ahead) const noexcept {
  const TableView& table = finder_.table();
  const float bx = axis_bound(table.axis_x()), by = axis_bound(table.axis_y()), side = model_side(table);
  // The reach when the search is expected to end, one more vote's range, and the model around it.
  const float frames = static_cast<float>(last.frames_since) + 2.0f + static_cast<float>(ahead);
  const float w = static_cast<float>(image.width), h = static_cast<float>(image.height);
  auto clamp = [](float v, float hi) { return v < 0.0f ? 0.0f : (v > hi ? hi : v); };
  const float x0 = clamp(last.pose.x - frames * bx - side, w), x1 = clamp(last.pose.x + frames * bx + side + 1.0f, w);
  const float y0 = clamp(last.pose.y - frames * by - side, h), y1 = clamp(last.pose.y + frames * by + side + 1.0f, h);
  Window win;
  win.x0 = static_cast<std::uint32_t>(x0);
  win.y0 = static_cast<std::uint32_t>(y0);
  const auto xe = static_cast<std::uint32_t>(x1), ye = static_cast<std::uint32_t>(y1);
  win.width = xe > win.x0 ? xe - win.x0 : 0;
  win.height = ye > win.y0 ? ye - win.y0 : 0;
  // The angles: where the options search a full turn, only those within the
  // table's theta bound per frame (one more cell: a vote's reach) of the last sighting's.
  const Axis at = table.axis_theta();
  const float cell = at.cells > 1 ? (at.max - at.min) / static_cast<float>(at.cells - 1) : 0.0f;
  const float bt = axis_bound(at) + cell;
  if (options_.theta_max_deg - options_.theta_min_deg >= 360.0f && frames * bt < 180.0f) {
    // Wrapped: a session that has turned many times has a large angle, and
    // the finder reports wrapped angles anyway.
    const float centre = wrap_degrees(last.pose.theta_deg);
    win.narrowed = true;
    win.theta_min_deg = centre - frames * bt;
    win.theta_max_deg = centre + frames * bt;
  }
  return win;
}

Status DetectionRecovery::find_several(const ImageView& image, const Window& window, TrackerScratch fine, std::uint64_t budget,
                                       Purpose purpose, Detection* found, std::uint32_t& count, bool& done) noexcept {
  count = 0;
  done = false;
  FinderScratch s = scratch_;
  s.fine = fine;
  if (purpose_ != purpose || !search_.active()) {
    FinderOptions several = options_;
    several.max_count = several.candidates < kReachDetections ? several.candidates : kReachDetections;
    if (window.narrowed) {
      several.theta_min_deg = window.theta_min_deg;
      several.theta_max_deg = window.theta_max_deg;
    }
    purpose_ = Purpose::kNone;
    if (window.width == 0 || window.height == 0) return Status::kOk;  // the target cannot be in the frame
    GABARIT_TRY(search_.begin(window.width, window.height, several, s));
    purpose_ = purpose;
    window_ = window;
  }
  const ImageView part{image.pixels + std::size_t{window_.y0} * image.stride + window_.x0, window_.width, window_.height, image.stride};
  const Status advanced = search_.advance(part, s, budget);
  last_work_ += search_.last_work();
  if (advanced != Status::kOk) {
    purpose_ = Purpose::kNone;
    return advanced;
  }
  if (!search_.done()) return Status::kOk;
  purpose_ = Purpose::kNone;
  done = true;
  GABARIT_TRY(search_.results(s, std::span<Detection>(found, kReachDetections), count));
  for (std::uint32_t i = 0; i < count; ++i) {
    found[i].pose.x += static_cast<float>(window_.x0);
    found[i].pose.y += static_cast<float>(window_.y0);
  }
  return Status::kOk;
}

Status DetectionRecovery::survey(const ImageView& image, const Pose& target, TrackerScratch fine, std::uint64_t budget) noexcept {
  last_work_ = 0;
  if (surveyed_) return Status::kOk;
  // The survey's detections are of the frame it began on: so is the target.
  if (!(purpose_ == Purpose::kSurvey && search_.active())) survey_target_ = target;
  Detection found[kReachDetections + 1];  // room for the target's own pose
  std::uint32_t count = 0;
  bool done = false;
  GABARIT_TRY(find_several(image, {0, 0, image.width, image.height}, fine, budget, Purpose::kSurvey, found, count, done));
  if (!done) return Status::kOk;
  surveyed_ = true;
  note_survey(found, count, survey_target_);
  return Status::kOk;
}

// The target itself, as detected or not: the detection at its pose, else
// the pose with the best score found (a look-alike must match the target).
void DetectionRecovery::note_survey(Detection* found, std::uint32_t count, const Pose& target) noexcept {
  lookalike_d2_ = 0.0f;
  target_score_ = 0.0f;
  copies_distinct_ = false;
  std::uint32_t k = 0;
  while (k < count && distance_squared(found[k].pose, target) > frame_bound_squared()) ++k;
  if (count == 0) return;
  // Fewer detections than asked for: the rest scored below the finder's floor.
  const bool list_full = count >= (options_.candidates < kReachDetections ? options_.candidates : kReachDetections);
  if (k == count) {
    found[count] = found[0];
    found[count].pose = target;
    ++count;
  }
  target_score_ = found[k].score;
  // The look-alikes stand clear of the clutter when every other detection
  // scores well below the target, and the clutter's level is seen (a
  // detection that low, or the list not full).
  bool clear = !list_full;
  for (std::uint32_t i = 0; i < count; ++i) {
    const float score = found[i].score;
    if (score < kLookalikeRatio * target_score_ && score >= kClutterRatio * target_score_) {
      clear = false;
      break;
    }
    if (score < kClutterRatio * target_score_) clear = true;
  }
  // Look-alikes apart by the model image's side first; failing those, and
  // only clear of the clutter, a copy nearer the target than that side is a
  // look-alike if it is apart by the points' extent.
  if (note_lookalikes(found, count, false)) copies_distinct_ = clear;
  else if (clear) copies_distinct_ = note_lookalikes(found, count, true);
}

// The target and a copy both in view: the one nearer where the target would
// be at its last velocity, within the table's reach (count: none).
std::uint32_t DetectionRecovery::nearest_alike(const Detection* found, std::uint32_t count, const LastSighting& last) const noexcept {
  const float since = static_cast<float>(last.frames_since);
  const Pose expected{last.pose.x + since * last.motion.vx, last.pose.y + since * last.motion.vy, last.pose.theta_deg, last.pose.depth};
  const float alike = kLookalikeRatio * target_score_;
  std::uint32_t k = count;
  for (std::uint32_t j = 0; j < count; ++j)
    if (found[j].score >= alike && within_table_reach(last, found[j].pose) &&
        (k == count || distance_squared(found[j].pose, expected) < distance_squared(found[k].pose, expected)))
      k = j;
  return k;
}

// Detections come best first: the best within reach, or one nearly as good
// nearer the last sighting (count: none).
std::uint32_t DetectionRecovery::best_within_reach(const Detection* found, std::uint32_t count, const LastSighting& last) const noexcept {
  std::uint32_t k = 0;
  while (k < count && !within_reach(last, found[k].pose)) ++k;
  if (k == count) return count;
  const float best = found[k].score;
  for (std::uint32_t j = k + 1; j < count; ++j)
    if (found[j].score >= kLookalikeRatio * best && within_reach(last, found[j].pose) &&
        distance_squared(found[j].pose, last.pose) < distance_squared(found[k].pose, last.pose))
      k = j;
  return k;
}

Status DetectionRecovery::run(const ImageView& image, const LastSighting& last, TrackerScratch fine, std::uint64_t budget,
                              SearchResult& out) noexcept {
  out = SearchResult{};
  last_work_ = 0;
  const std::uint32_t n = lost_frames_++;
  // A search begins every interval-th lost frame (or to follow a detection up);
  // one under way goes on.
  const bool going_on = purpose_ == Purpose::kRecovery && search_.active();
  if (!going_on && !following_ && n % interval_ != 0) return Status::kOk;
  Window window;  // a search under way keeps the one it began with
  if (!going_on) {
    search_begun_ = n;
    search_since_ = last.frames_since;
    // Following: the lead, as far off as the frames since it was seen.
    search_from_ = following_ ? LastSighting{lead_, {}, n - lead_frame_} : last;
    window = reach_window(image, search_from_, following_ ? kFollowAhead : kSearchAhead);
  }
  Detection found[kReachDetections];
  std::uint32_t count = 0;
  bool done = false;
  GABARIT_TRY(find_several(image, window, fine, budget, Purpose::kRecovery, found, count, done));
  if (!done) return Status::kOk;
  // Following up or not, the rules are the last sighting's: a lead is where
  // to look, not what to take.
  const std::uint32_t k = choose(found, count, last);
  const bool followed = following_;
  following_ = false;
  out.searched = true;
  if (k == count) return Status::kOk;  // out.vote stays empty: nothing to accept
  last_ = found[k];
  out.from = found[k].pose;
  GABARIT_TRY(track_step(finder_.table(), finder_.detector(), image, out.from, fine, out.vote));
  last_work_ += track_step_work(finder_.table(), out.vote);
  if (n == search_begun_) return Status::kOk;
  // Found on the frame the search began on, some frames ago: the target
  // has moved since. Catch up as tracking frames would, a few votes on this
  // frame from each one's result; if the session does not take the last,
  // the next search follows the detection up (a search around it), once:
  // then the search is around the last sighting again.
  following_ = !followed;
  lead_ = found[k].pose;
  lead_frame_ = search_begun_;
  for (std::uint32_t v = 1; v < kCatchUpVotes && out.vote.state != TrackState::kLost; ++v) {
    const float dx = out.vote.pose.x - out.from.x, dy = out.vote.pose.y - out.from.y;
    if (dx * dx + dy * dy < 0.25f) break;  // in place
    out.from = out.vote.pose;
    GABARIT_TRY(track_step(finder_.table(), finder_.detector(), image, out.from, fine, out.vote));
    last_work_ += track_step_work(finder_.table(), out.vote);
  }
  return Status::kOk;
}

}  // namespace gabarit
