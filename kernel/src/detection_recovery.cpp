#include "gabarit/detection_recovery.hpp"

namespace gabarit {

float DetectionRecovery::frame_bound_squared() const noexcept {
  const Axis ax = finder_.table().axis_x(), ay = finder_.table().axis_y();
  const float bx = ax.max > -ax.min ? ax.max : -ax.min, by = ay.max > -ay.min ? ay.max : -ay.min;
  return bx * bx + by * by;
}

namespace {
float distance_squared(const Pose& a, const Pose& b) noexcept {
  const float dx = a.x - b.x, dy = a.y - b.y;
  return dx * dx + dy * dy;
}
}  // namespace

bool DetectionRecovery::within_table_reach(const LastSighting& last, const Pose& pose) const noexcept {
  const float frames = static_cast<float>(last.frames_since) + 1.0f;
  return distance_squared(pose, last.pose) <= frames * frames * frame_bound_squared();
}

bool DetectionRecovery::within_reach(const LastSighting& last, const Pose& pose) const noexcept {
  if (lookalike_d2_ > 0.0f && distance_squared(pose, last.pose) > 0.25f * lookalike_d2_) return false;  // beyond the midpoint
  return within_table_reach(last, pose);
}

bool DetectionRecovery::note_lookalikes(const Detection* found, std::uint32_t count) noexcept {
  if (!(target_score_ > 0.0f)) return false;  // no survey: nothing to compare with
  // Apart: two per-frame bounds, and the model image's larger side (shifted
  // along itself, an elongated or self-similar object matches well: that
  // is the target, not a copy of it).
  const TableView& table = finder_.table();
  const float side = static_cast<float>(table.model_width() > table.model_height() ? table.model_width() : table.model_height());
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

Status DetectionRecovery::find_several(const ImageView& image, TrackerScratch fine, Detection* found, std::uint32_t& count) noexcept {
  FinderOptions several = options_;
  several.max_count = several.candidates < kReachDetections ? several.candidates : kReachDetections;
  FinderScratch s = scratch_;
  s.fine = fine;
  return finder_.find(image, several, s, std::span<Detection>(found, several.max_count), count);
}

Status DetectionRecovery::survey(const ImageView& image, const Pose& target, TrackerScratch fine) noexcept {
  lookalike_d2_ = 0.0f;
  target_score_ = 0.0f;
  Detection found[kReachDetections + 1];  // room for the target's own pose
  std::uint32_t count = 0;
  GABARIT_TRY(find_several(image, fine, found, count));
  // The target itself, as detected or not: the detection at its pose, else
  // the pose with the best score found (a look-alike must match the target).
  std::uint32_t k = 0;
  while (k < count && distance_squared(found[k].pose, target) > frame_bound_squared()) ++k;
  if (count == 0) return Status::kOk;
  if (k == count) {
    found[count] = found[0];
    found[count].pose = target;
    ++count;
  }
  target_score_ = found[k].score;
  note_lookalikes(found, count);
  return Status::kOk;
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

Status DetectionRecovery::run(const ImageView& image, const LastSighting& last, TrackerScratch fine, SearchResult& out) noexcept {
  out = SearchResult{};
  const std::uint32_t n = lost_frames_++;
  if (n % interval_ != 0) return Status::kOk;
  Detection found[kReachDetections];
  std::uint32_t count = 0;
  GABARIT_TRY(find_several(image, fine, found, count));
  out.searched = true;
  const std::uint32_t k = note_lookalikes(found, count) ? nearest_alike(found, count, last) : best_within_reach(found, count, last);
  if (k == count) return Status::kOk;  // out.vote stays empty: nothing to accept
  last_ = found[k];
  out.from = found[k].pose;
  return track_step(finder_.table(), finder_.detector(), image, out.from, fine, out.vote);
}

}  // namespace gabarit
