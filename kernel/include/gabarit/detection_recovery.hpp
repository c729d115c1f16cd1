// Re-acquisition by detection (the session's default recovery where it
// verifies): the model finder over where the target can have got to,
// bounded by the look-alikes seen, and spread over frames under a budget.
#pragma once

#include <cstdint>

#include "gabarit/finder_search.hpp"
#include "gabarit/image_view.hpp"
#include "gabarit/model_finder.hpp"
#include "gabarit/pose.hpp"
#include "gabarit/recovery_search.hpp"
#include "gabarit/status.hpp"
#include "gabarit/tracker.hpp"

namespace gabarit {

// Re-acquisition by detection: a TrackingSession given this stage
// (use_detection_recovery) searches lost frames with the finder over where
// the target can be (below) instead of the grid around the last sighting, every
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
// nearest the last sighting is taken. Where the survey's look-alikes stand
// clear of the clutter (every other detection below kClutterRatio of the
// target's score, and one that low seen or the list not full), a copy is
// told from a self-match by the model's points' extent rather than the
// image's side, and the copy is followed until the target is seen again: a
// detection alike in score that a lost frame's search does not take is
// the copy, and each later search's detection where the copy can have got
// to since (the table's bound per frame), and nearer it than the last
// sighting, is the copy again: it is set aside and the rest are judged by
// the table's reach alone (a copy that orbits the hidden target comes
// within the midpoint of where the target was last seen, and the target
// may reappear beyond it). within_reach() refuses the copy likewise.
// Cost: each search is spread over frames (finder_search.hpp) under the
// caller's budget of work per frame, so no frame pays for a whole search:
// a lost frame's search goes on where the last one stopped, and its result
// is voted on the frame where it ends. A search covers only the window the
// target can have reached by the time it is expected to end (the reach
// kSearchAhead frames on, plus the model's extent), clipped to the frame,
// and likewise only the angles it can have turned to (the table's theta
// bound per frame; a full turn is searched only once that reaches half a
// turn): soon after a loss that is a small part of a wide frame and of the
// angles, found in a few frames; the area grows with each later search until
// it is the frame and every angle. With the scratch's held_frame, a search
// spread over frames works on the frame it began on (finder_search.hpp);
// what it finds there, some frames ago, is caught up with: up to
// kCatchUpVotes votes on the current frame, each from the last one's result,
// as tracking frames would follow the target; if the session does not take
// the last, the next search follows the detection up (a search around it,
// over the reach of the frames since, kFollowAhead on, whose result is
// taken by the same rules and caught up with likewise), once. The survey likewise runs a piece
// after each tracked frame until it has covered the whole frame; a loss
// before it ends cancels it (the recovery needs the search) and it starts
// again once the target is found.
class DetectionRecovery {
 public:
  // finder must outlive the stage; scratch.fine is ignored (the session's is used).
  DetectionRecovery(ModelFinder& finder, const FinderOptions& options, FinderScratch scratch, std::uint32_t interval = 1) noexcept
      : finder_(finder), options_(options), scratch_(scratch), interval_(interval < 1 ? 1 : interval), search_(finder) {}
  // A lost period begins: a recovery search under way is dropped.
  void reset() noexcept;
  static constexpr std::uint32_t kReachDetections = 4;
  static constexpr float kLookalikeRatio = 0.9f;
  static constexpr float kClutterRatio = 0.75f;
  static constexpr std::uint32_t kSearchAhead = 4;
  static constexpr std::uint32_t kFollowAhead = 1;
  static constexpr std::uint32_t kCatchUpVotes = 3;
  // One lost frame: the search goes on with at most `budget` units of work
  // (kUnlimitedWork: the whole search in this frame); out.searched once it ends.
  [[nodiscard]] Status run(const ImageView& image, const LastSighting& last, TrackerScratch fine, std::uint64_t budget,
                           SearchResult& out) noexcept;
  // Looks for copies of the target, now at `target`, over the whole frame:
  // a piece of at most `budget` units per call, until surveyed().
  [[nodiscard]] Status survey(const ImageView& image, const Pose& target, TrackerScratch fine, std::uint64_t budget) noexcept;
  bool surveyed() const noexcept { return surveyed_; }
  // Another session: the look-alikes seen are forgotten and the survey starts afresh.
  void restart_survey() noexcept;
  // The work of the last run() or survey() (search pieces and votes), in
  // the search's units.
  std::uint64_t last_work() const noexcept { return last_work_; }
  // The search under way (its frames and work so far), for reports and tests.
  const FinderSearch& search() const noexcept { return search_; }
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
  // Notes any pair of `found` alike in score and apart (by the model's
  // points' extent, else its image's side) as a look-alike; true if there
  // is one (the target and a copy both in view).
  bool note_lookalikes(const Detection* found, std::uint32_t count, bool by_extent) noexcept;
  // Within the table's bound of the last sighting, look-alikes aside.
  bool within_table_reach(const LastSighting& last, const Pose& pose) const noexcept;
  // The best kReachDetections detections (at most the finder's candidates) into found.
  // Spread over frames: begins a search for `purpose` if none is under way,
  // goes on with it, and once it ends (done) writes them.
  enum class Purpose : std::uint8_t { kNone, kSurvey, kRecovery };
  struct Window {
    std::uint32_t x0 = 0, y0 = 0, width = 0, height = 0;
    bool narrowed = false;  // the angles below, not the options' range
    float theta_min_deg = 0.0f, theta_max_deg = 0.0f;
  };
  [[nodiscard]] Status find_several(const ImageView& image, const Window& window, TrackerScratch fine, std::uint64_t budget,
                                    Purpose purpose, Detection* found, std::uint32_t& count, bool& done) noexcept;
  // Where a search begun now for a target last seen at `last` must look.
  Window reach_window(const ImageView& image, const LastSighting& last, std::uint32_t ahead) const noexcept;
  void note_survey(Detection* found, std::uint32_t count, const Pose& target) noexcept;
  // The detection to take, by the rules above; `count` for none.
  std::uint32_t nearest_alike(const Detection* found, std::uint32_t count, const LastSighting& last) const noexcept;
  std::uint32_t best_within_reach(const Detection* found, std::uint32_t count, const LastSighting& last) const noexcept;
  bool is_copy(const LastSighting& last, const Pose& pose, std::uint32_t since) const noexcept;
  void note_copy(const LastSighting& last, const Pose& pose) noexcept;
  // Sets the look-alike aside (count then excludes it) and notes where it is.
  std::uint32_t choose(Detection* found, std::uint32_t& count, const LastSighting& last) noexcept;
  FinderSearch search_;
  Purpose purpose_ = Purpose::kNone;
  Window window_;  // the search's, fixed while it goes on
  std::uint32_t search_begun_ = 0;  // the lost frame the search began on
  LastSighting search_from_;        // and where it searched from
  bool following_ = false;          // a detection from an earlier frame to follow up
  Pose lead_;
  std::uint32_t lead_frame_ = 0;    // the lost frame it was seen on
  Pose survey_target_;              // the target when the survey began
  std::uint64_t last_work_ = 0;
  bool surveyed_ = false;
  std::uint32_t lost_frames_ = 0;
  Detection last_;
  float lookalike_d2_ = 0.0f;
  bool copies_distinct_ = false;  // the survey's look-alikes stand clear of the clutter
  // The look-alike followed since the target's last sighting (copy_last_):
  // where it was seen, copy_since_ frames after that sighting.
  bool copy_known_ = false;
  Pose copy_;
  Pose copy_last_;
  std::uint32_t copy_since_ = 0;
  std::uint32_t search_since_ = 0;  // the frames since the last sighting when the search began
  float target_score_ = 0.0f;  // the survey's score at the target (0: no survey)
};

}  // namespace gabarit
