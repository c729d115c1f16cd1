// Re-acquisition by detection (the session's default recovery where it
// verifies): the model finder over the whole frame, bounded by where the
// target can have got to and by the look-alikes seen.
#pragma once

#include <cstdint>

#include "gabarit/image_view.hpp"
#include "gabarit/model_finder.hpp"
#include "gabarit/pose.hpp"
#include "gabarit/recovery_search.hpp"
#include "gabarit/status.hpp"
#include "gabarit/tracker.hpp"

namespace gabarit {

// Re-acquisition by detection: a TrackingSession given this stage
// (use_detection_recovery) searches lost frames with the finder over the
// whole frame instead of the grid around the last sighting, every
// `interval`-th lost frame. Of the best kReachDetections detections, the
// best-scored one the target can have reached is voted once more with the
// table from its pose (its counters stay in the session's fine scratch), and
// the session accepts that vote by the rule it applies to every search.
// Reach: the table bounds the motion between two frames (its x and y
// ranges), so n frames after the last sighting the target is within n + 1
// times that bound of it. A look-alike farther off is not the target,
// however well it scores (the suite's distractor family: without the bound,
// an occlusion handed the track to the look-alike). The reach grows with
// every lost frame, so a target that reappears anywhere is found in bounded
// time: (frame diagonal) / (per-frame bound) frames at most.
// Look-alikes: a copy of the target elsewhere in the frame passes that test
// while the target is hidden, so the stage surveys the first frame of a
// session (survey) and every frame it searches for two detections that both
// score at least kLookalikeRatio of the target's score in the survey (the
// best score there where the target itself was not detected), farther apart
// than the model image's larger side (a near-symmetric or self-similar
// object matches itself shifted or turned: that is not a copy) and than two
// per-frame bounds. Once one has been seen at distance D, the reach is never
// more than D / 2: a candidate nearer the last sighting than the midpoint is
// taken for the target, one beyond it is not taken at all (the session stays
// lost rather than follow the copy), unless the target and a copy are both
// in view: then the one nearer where the target would be at its last
// velocity is taken. Of candidates alike in score within reach, the one
// nearest the last sighting is taken.
class DetectionRecovery {
 public:
  // finder must outlive the stage; scratch.fine is ignored (the session's is used).
  DetectionRecovery(ModelFinder& finder, const FinderOptions& options, FinderScratch scratch, std::uint32_t interval = 1) noexcept
      : finder_(finder), options_(options), scratch_(scratch), interval_(interval < 1 ? 1 : interval) {}
  void reset() noexcept { lost_frames_ = 0; }
  static constexpr std::uint32_t kReachDetections = 4;
  static constexpr float kLookalikeRatio = 0.9f;
  [[nodiscard]] Status run(const ImageView& image, const LastSighting& last, TrackerScratch fine, SearchResult& out) noexcept;
  // Looks for copies of the target, at `target`, over the whole frame.
  [[nodiscard]] Status survey(const ImageView& image, const Pose& target, TrackerScratch fine) noexcept;
  const Detection& last() const noexcept { return last_; }
  // Whether the target, last seen at `last`, can be at `pose` (see above).
  bool within_reach(const LastSighting& last, const Pose& pose) const noexcept;
  // The squared distance of the nearest look-alike seen (0: none).
  float lookalike_distance_squared() const noexcept { return lookalike_d2_; }

 private:
  ModelFinder& finder_;
  FinderOptions options_;
  FinderScratch scratch_;
  std::uint32_t interval_ = 1;
  // The table's largest x and y step between two frames, as a distance.
  float frame_bound_squared() const noexcept;
  // Notes any pair of `found` alike in score and apart as a look-alike;
  // true if there is one (the target and a copy both in view).
  bool note_lookalikes(const Detection* found, std::uint32_t count) noexcept;
  // Within the table's bound of the last sighting, look-alikes aside.
  bool within_table_reach(const LastSighting& last, const Pose& pose) const noexcept;
  // The best kReachDetections detections (at most the finder's candidates) into found.
  [[nodiscard]] Status find_several(const ImageView& image, TrackerScratch fine, Detection* found, std::uint32_t& count) noexcept;
  // The detection to take, by the rules above; `count` for none.
  std::uint32_t nearest_alike(const Detection* found, std::uint32_t count, const LastSighting& last) const noexcept;
  std::uint32_t best_within_reach(const Detection* found, std::uint32_t count, const LastSighting& last) const noexcept;
  std::uint32_t lost_frames_ = 0;
  Detection last_;
  float lookalike_d2_ = 0.0f;
  float target_score_ = 0.0f;  // the survey's score at the target (0: no survey)
};

}  // namespace gabarit
