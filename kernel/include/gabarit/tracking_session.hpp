// A tracking session: the per-frame loop a camera application runs, on top of
// track_step. It keeps the pose between frames and composes, each optional:
//   - the motion filter (motion_filter.hpp): the ROI at the predicted pose,
//     candidates gated by the motion model, confidence, velocity;
//   - sub-cell refinement (refinement.hpp) of the chosen cell;
//   - recovery (recovery_search.hpp): once lost, a search around the last
//     confident pose, whose best candidate returns the session to tracking
//     only at high confidence (verifying, and correlating as a tracked frame
//     must; a vote too weak to trust is taken on that correlation alone);
//     or a detection (detection_recovery.hpp) or particle recovery stage
//     (particle_recovery.hpp) over the whole frame;
//   - depth and angle by intensity (depth_by_intensity.hpp), with a focus stack.
// With everything off (kPlainSession) a session is exactly track_step frame
// after frame, a lost frame keeping the previous pose.
// No heap: scratch comes from the caller, as for track_step.
#pragma once

#include <cstdint>
#include <span>

#include "gabarit/depth_by_intensity.hpp"
#include "gabarit/detection_recovery.hpp"
#include "gabarit/frame_ledger.hpp"
#include "gabarit/intensity_scan.hpp"
#include "gabarit/model_finder.hpp"
#include "gabarit/motion_filter.hpp"
#include "gabarit/particle_recovery.hpp"
#include "gabarit/recovery_search.hpp"
#include "gabarit/refinement.hpp"
#include "gabarit/tracker.hpp"
#include "gabarit/verification.hpp"

namespace gabarit {

struct SessionOptions {
  bool motion_filter = true;
  bool refine = true;
  bool recover = true;  // search for the target once lost (else keep predicting)
  RecoveryOptions recovery;
  MotionFilterParams filter;
  // With the motion filter: when the vote at the prediction is not of high
  // confidence, vote at the last pose too and keep the better measurement.
  bool vote_at_last_pose = true;
  // With the motion filter: a frame without a measurement it trusts takes
  // the plain loop's pose (the best cell at the last pose) instead of the
  // prediction; the filter still only predicts (and may declare it lost).
  bool follow_when_unsure = true;
  // The sub-cell angle is taken from the votes only where they constrain it:
  // the chosen cell must outscore its neighbours along theta by this fraction
  // of its score; else the angle is the cell's (a near-symmetric outline),
  // as in the plain loop. 0.05 was chosen on the scene suite's tuning half.
  float theta_observability = 0.05f;
  // With a focus stack: the depth by intensity replaces the votes' depth
  // only if it correlates better by this much (depth_by_intensity.hpp).
  float depth_switch_correlation = 0.02f;
  // With refine: the sub-cell offset by a least-squares alignment of the
  // matched features (refinement.hpp) instead of the parabola through the
  // neighbouring cells' scores.
  bool align_features = false;
  // With a focus stack: where the votes' depth beats every other depth's
  // best cell by this fraction, the votes keep it and the intensities are
  // not asked (1e38: always asked). 0.15 was chosen on the scene suite's
  // tuning half (docs/tracking.md).
  float depth_votes_decisive = 0.15f;
  // With the motion filter, where chance alone (d, this frame's features per
  // ROI pixel) scores at least low_ratio of the reference: a measurement is
  // not confident if its score stands above chance, (s - d) / (1 - d), by less
  // than this fraction of the reference score's standing (0: off). Binary
  // frames in heavy noise, where noise alone scores nearly what the target
  // does (tracking_session.cpp).
  float clutter_floor = 0.5f;
  // With the motion filter, a focus stack and a grayscale detector: vote, then verify
  // (verification.hpp). The frame's pose is the best-correlated of the
  // proposals (the vote's best `vote_proposals` cells at the prediction and
  // at the last pose, the gate's choice, the plain loop's winner, the
  // prediction and the last pose), refined on the correlation; its depth the
  // best-correlated stack image there, kept unless another beats it by
  // verified_depth_switch.
  bool verify = true;
  std::uint8_t vote_proposals = 4;  // 1..kMaxVoteProposals
  VerifyOptions verification;
  // The verified pose is taken only where the model is seen well: its
  // correlation at least this fraction of the reference (the running mean
  // over confident frames). Partly hidden, the correlation over the model's
  // rectangle is pulled by the occluder, while the votes, on the edges still
  // in view, hold the pose.
  float verify_accept = 0.8f;
  // Below this fraction of the reference, the frame has no measurement (the
  // motion filter coasts and declares the target lost if it stays so).
  float verify_lost = 0.5f;
  // A distinct placement (a sixth of the model image's smaller side away, at
  // least verification.distinct_px) correlating within this fraction of the
  // chosen one: the frame is reported ambiguous (TrackState::kAmbiguous)
  // instead of one being picked silently.
  float ambiguity_margin = 0.02f;
  // Verifying, the depth's hysteresis in correlation. Compared over the
  // object's own samples (depth_by_intensity.hpp), a 7-depth stack's
  // neighbouring depths differ by about 0.005 at the true one, so 0.01 held
  // a wrong depth for whole sweeps; 0.002 was chosen on the suite's tuning
  // half and the extra tuning scenes (0, 0.002, 0.005 and 0.01 measured;
  // docs/tracking.md).
  float verified_depth_switch = 0.002f;
  // With a detection stage, verifying: the work the survey for look-alikes
  // may spend after a tracked frame, in tracked frames (the running mean of
  // their work, finder_search.hpp), and at least kSurveyUnitsPerPixel a pixel
  // of the frame; it goes on over the next frames until it has covered the
  // frame. 0: the whole survey after the first frame (a frame 30 to 100
  // times the median on the scene suite's wide frames).
  float survey_frames = 2.0f;
  // Likewise for a lost frame's search (0, the default: each search in the
  // frame that needs it; the search's area, where the target can be, bounds
  // its cost). Spread, a search works on the frame it began on and what it
  // finds is caught up with (detection_recovery.hpp): on the scene suite the
  // worst frame is then about 7 times the median instead of 13 with 6, but
  // the target is found a few frames later and the tuning half tracks worse
  // (docs/detection.md, "A per-frame budget").
  float recovery_frames = 0.0f;
};
inline constexpr std::uint8_t kMaxVoteProposals = 6;
// track_step frame after frame, nothing added: the thesis's tracker.
inline constexpr SessionOptions kPlainSession{false, false, false, {}, {}, false, false, 0.0f, 0.0f, false, 1.0e38f, 0.0f, false, 4, {}, 0.8f, 0.5f, 0.02f};

struct SessionResult {
  Pose pose;                 // the session's estimate after this frame
  StepResult step;           // the raw vote of the table searched this frame
  Confidence confidence = Confidence::kNone;
  TrackState state = TrackState::kLost;
  // Verifying (a focus stack and the motion filter): the correlation of the
  // model image with the frame at the pose, 0..1 (verification.hpp); else the
  // normalised vote score of the chosen cell.
  float score = 0.0f;
  // Verifying: the verified pose's correlation with the model image (-1..1),
  // the best distinct proposal's (-1 without one), correlations computed,
  // and whether the verified pose was taken (verify_accept).
  float verified_score = 0.0f, verified_runner_up = -1.0f;
  std::uint32_t correlations = 0;
  bool verified = false;
  bool searched_coarse = false;
  bool reacquired = false;   // this frame ended a lost period
  // What the frame cost, in work units (finder_search.hpp: about a vote
  // each; counted, not timed, so the same on every target): its votes, its
  // correlations with the focus stack and its recovery's work (a particle
  // recovery's own measures are not counted). Equal to ledger.total_work().
  std::uint64_t work = 0;
  // The same frame phase by phase, in work and, with a clock, in ticks
  // (frame_ledger.hpp).
  FrameLedger ledger;
};

// The survey's least work a tracked frame, per pixel of the frame: a whole
// frame's survey costs about 150 units a pixel on the scene suite's frames
// whatever the model's size (the coarse level scales with it), so it ends
// within about 16 tracked frames. In tracked frames' work alone, a small
// model's (36 x 32 px on a 640 x 480 frame) took about 150 frames, a loss
// restarted it, and it never ended: it taxed every frame and told nothing.
inline constexpr std::uint64_t kSurveyUnitsPerPixel = 10;

class TrackingSession {
 public:
  // `fine` (and `coarse`, if not null) must outlive the session. Errors from
  // start(): kInvalidArgument for bad options, a pose outside pose_in_range
  // or a depth the table does not have, or a coarse table of another depth count.
  TrackingSession(const TableView& fine, const TableView* coarse, const Detector& detector) noexcept
      : fine_(fine), coarse_(coarse), detector_(detector), search_(fine, coarse, detector) {}
  [[nodiscard]] Status start(const SessionOptions& options, const Pose& initial) noexcept;
  [[nodiscard]] Status step(const ImageView& image, SessionScratch scratch, SessionResult& out) noexcept;
  // With a focus stack (which must outlive the session; nullptr to stop),
  // each frame's depth is then chosen by intensity at the tracked pose
  // (depth_by_intensity.hpp) instead of by the winning stencils' stack index.
  void use_focus_stack(const FocusStack* stack) noexcept { stack_ = stack; }
  // With a particle recovery stage (which must outlive the session; nullptr
  // to stop), lost frames re-acquire through it (particle_recovery.hpp)
  // instead of the grid search; its result is accepted by the same rule.
  void use_particle_recovery(ParticleRecovery* stage) noexcept { particles_ = stage; }
  // With a detection stage (model_finder.hpp; must outlive the session;
  // nullptr to stop), lost frames after the first recovery.detect_after
  // re-acquire by detection over the whole frame; its result is accepted by
  // the same rule. It takes precedence over a particle stage. Verifying, the
  // session's first frame is surveyed with it for look-alikes of the target
  // (DetectionRecovery::survey), which bound where it re-acquires; the
  // survey (survey_frames) and each search (recovery_frames) may be spread
  // over frames.
  void use_detection_recovery(DetectionRecovery* stage) noexcept { detection_ = stage; }
  // With an intensity scan (intensity_scan.hpp; must outlive the session;
  // nullptr to stop), verifying, a lost frame the recovery stage did not end
  // scores poses around the last sighting by intensity, and its best is
  // taken where the verification takes it (as a search's weak vote is), and
  // where the detection stage's reach and look-alikes allow.
  void use_intensity_scan(IntensityScan* stage) noexcept { scan_ = stage; }
  // With a clock (nullptr to stop), each frame's ledger is timed phase by
  // phase (SessionResult::ledger); the poses are the same either way.
  void use_clock(TickSource clock) noexcept { clock_ = clock; }

  const Pose& pose() const noexcept { return pose_; }
  const MotionFilterState& motion() const noexcept { return filter_.state(); }
  bool lost() const noexcept { return lost_; }

 // One vote and the gate's choice in it (public for the comparison helper).
  struct Measurement {
    StepResult step;
    Confidence confidence = Confidence::kNone;
    float score = 0.0f, next_score = 0.0f;  // normalised scores of the chosen cell and the next candidate
    Pose pose;                     // the chosen cell's pose, refined
    bool theta_observable = true;
    float depth_margin = 0.0f;     // the chosen cell's score over the best other depth's, minus 1
    Pose proposals[kMaxVoteProposals];  // verifying: the vote's best cells, best first
    std::uint32_t proposal_count = 0;
  };

 private:
  // track_step, its halves timed and charged to the ledger.
  Status vote_at(const ImageView& image, const Pose& centre, TrackerScratch scratch, StepResult& step) noexcept;
  Status measure_at(const ImageView& image, const Pose& centre, SessionScratch scratch, Measurement& m) noexcept;
  bool theta_observable(std::span<const VoteCounter> counters, std::uint32_t cell) const noexcept;
  bool on_translation_border(std::uint32_t cell) const noexcept;
  bool clutter_rejects(float score, const StepResult& step) const noexcept;
  SubCellOffset sub_cell(SessionScratch scratch, const StepResult& step, std::uint32_t cell) const noexcept;
  Status track_fine(const ImageView& image, SessionScratch scratch, SessionResult& out) noexcept;
  Status recover(const ImageView& image, SessionScratch scratch, SessionResult& out) noexcept;
  Status recover_by_stage(const ImageView& image, SessionScratch scratch, SessionResult& out) noexcept;
  Status recover_by_scan(const ImageView& image, SessionResult& out) noexcept;
  void begin_lost() noexcept;
  // Binary frames (the thesis's synthetic sequences) have no intensities to
  // correlate: their votes decide.
  bool verifying() const noexcept {
    return stack_ != nullptr && options_.verify && options_.motion_filter &&
           detector_.kind != table_format::DetectorKind::kBinary;
  }
  void propose_top_cells(std::span<const VoteCounter> counters, const Pose& centre, Measurement& m) const noexcept;
  Status verify_choice(const ImageView& image, const Proposals& proposals, Confidence confidence, Pose& chosen) noexcept;

  const TableView& fine_;
  const TableView* coarse_;
  Detector detector_;
  SessionOptions options_;
  MotionFilter filter_;
  RecoverySearch search_;
  Pose pose_;
  LastSighting last_confident_;  // where recovery searches
  bool lost_ = false;
  const FocusStack* stack_ = nullptr;
  ParticleRecovery* particles_ = nullptr;
  DetectionRecovery* detection_ = nullptr;
  IntensityScan* scan_ = nullptr;
  std::uint32_t lost_frames_ = 0;  // frames of this lost period so far
  bool surveyed_ = false;          // the survey for look-alikes begun
  std::uint64_t frame_work_ = 0;   // the running mean of tracked frames' work (0: none yet)
  FrameLedger ledger_;             // this frame's so far
  TickSource clock_ = nullptr;
  std::uint64_t detection_budget(float frames) const noexcept;
  std::uint64_t survey_budget(const ImageView& image) const noexcept;
  float depth_margin_ = 0.0f;  // this frame's measurement's (0 without one)
  Verdict verdict_;            // verifying: this frame's
  bool verdict_taken_ = false;  // and whether its pose was taken
  float verified_reference_ = 0.0f;  // the running mean of confident frames' correlations (0: none yet)
  float verified_variance_ = 0.0f;   // and of the frame's variance at their poses (frame_variance_at; 0: none yet)
  float frame_reference_ = 0.0f;     // verified_reference_ as this frame's contrast allows (reference_at)
  float reference_at(const ImageView& image, const Pose& pose) const noexcept;
};

}  // namespace gabarit
