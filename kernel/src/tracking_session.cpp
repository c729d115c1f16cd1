#include "gabarit/tracking_session.hpp"

#include "gabarit/finder_search.hpp"
#include "gabarit/refinement.hpp"

namespace gabarit {
namespace {

TrackState state_of(Confidence c) noexcept { return c == Confidence::kHigh ? TrackState::kTracking : TrackState::kUncertain; }

// How far a score stands above chance: a stencil laid over pixels that are
// features with probability d (this frame's features per ROI pixel) collects
// about d of its size by chance, so (s - d) / (1 - d), at least 0, is what
// the target adds (TrackingSession::clutter_rejects).
float contrast(float score, const StepResult& step, const TableView& table) noexcept {
  const float d = static_cast<float>(step.features) / static_cast<float>(table.roi_pixels());
  if (!(d < 1.0f)) return 0.0f;
  const float c = (score - d) / (1.0f - d);
  return c > 0.0f ? c : 0.0f;
}

}  // namespace

Status TrackingSession::start(const SessionOptions& options, const Pose& initial) noexcept {
  if (!valid(options.filter) || !valid(options.recovery) || !pose_in_range(initial) || initial.depth >= fine_.depth_count() ||
      !(options.theta_observability >= 0.0f && options.theta_observability <= 1.0f) ||
      !(options.depth_switch_correlation >= 0.0f && options.depth_switch_correlation <= 2.0f) ||
      !(options.verified_depth_switch >= 0.0f && options.verified_depth_switch <= 2.0f) ||
      !(options.depth_votes_decisive >= 0.0f) || !(options.clutter_floor >= 0.0f && options.clutter_floor <= 1.0f) ||
      options.vote_proposals < 1 || options.vote_proposals > kMaxVoteProposals ||
      !(options.verify_accept >= 0.0f && options.verify_accept <= 1.0f) ||
      !(options.verify_lost >= 0.0f && options.verify_lost <= 1.0f) ||
      !(options.ambiguity_margin >= 0.0f && options.ambiguity_margin <= 1.0f) ||
      !(options.verification.spacing_px > 0.0f && options.verification.spacing_px <= 4.0f) ||
      !(options.verification.max_angle_spacings > 0.0f && options.verification.max_angle_spacings <= 180.0f) ||
      !(options.verification.distinct_px >= 0.0f) ||
      !(options.survey_frames >= 0.0f && options.survey_frames <= 1000.0f) ||
      !(options.recovery_frames >= 0.0f && options.recovery_frames <= 1000.0f)) {
    return Status::kInvalidArgument;
  }
  if (coarse_ != nullptr && coarse_->depth_count() != fine_.depth_count()) return Status::kInvalidArgument;
  options_ = options;
  verified_reference_ = 0.0f;
  verified_variance_ = 0.0f;
  frame_reference_ = 0.0f;
  pose_ = initial;
  last_confident_ = {initial, {}, 0};
  filter_.reset(options.filter, initial);
  search_.reset();
  lost_ = false;
  surveyed_ = false;
  frame_work_ = 0;
  return Status::kOk;
}

void TrackingSession::begin_lost() noexcept {
  lost_ = true;
  lost_frames_ = 0;
  search_.reset();  // nearest placements first
  if (particles_ != nullptr) particles_->reset();  // the whole cloud spread again
  if (detection_ != nullptr) detection_->reset();
}

Status TrackingSession::step(const ImageView& image, SessionScratch scratch, SessionResult& out) noexcept {
  out = SessionResult{};
  depth_margin_ = 0.0f;
  ++last_confident_.frames_since;
  verdict_ = Verdict{};
  verdict_taken_ = false;
  ledger_ = FrameLedger{};
  const std::uint64_t began = read_ticks(clock_);
  const bool tracking = !lost_;
  GABARIT_TRY(lost_ ? recover(image, scratch, out) : track_fine(image, scratch, out));
  if (verdict_.found) {
    out.verified_score = verdict_.score;
    out.verified_runner_up = verdict_.runner_up;
    out.verified = verdict_taken_;
    out.score = verdict_.score > 0.0f ? verdict_.score : 0.0f;
    // Two distinct placements alike: say so rather than pick one silently.
    if (out.state != TrackState::kLost && verdict_.score > 0.0f &&
        verdict_.runner_up >= (1.0f - options_.ambiguity_margin) * verdict_.score)
      out.state = TrackState::kAmbiguous;
  }
  out.correlations = verdict_.correlations;
  const std::uint64_t depth_began = read_ticks(clock_);
  if (verifying()) {
    // The verified pose is already refined in angle; its depth is the
    // best-correlated stack image there (hysteresis: the current depth stays
    // unless another beats it by the margin).
    if (verdict_taken_ && fine_.depth_count() > 1 && out.state != TrackState::kLost &&
        !(depth_margin_ >= options_.depth_votes_decisive)) {
      GABARIT_TRY(depth_by_intensity(image, pose_, *stack_, pose_.depth, options_.verified_depth_switch));
      out.correlations += fine_.depth_count();
    }
    out.pose = pose_;
  } else if (stack_ != nullptr && out.state != TrackState::kLost && out.confidence != Confidence::kNone) {
    // Intensities only where there is a measurement to compare at: a frame
    // without one has no pose worth correlating the stack with.
    // Only what the table can tell apart: the depth where it has several
    // and the votes did not choose it clearly themselves (edge features
    // change little with focus), the angle where it rotates.
    if (fine_.depth_count() > 1 && !(depth_margin_ >= options_.depth_votes_decisive)) {
      GABARIT_TRY(depth_by_intensity(image, pose_, *stack_, pose_.depth, options_.depth_switch_correlation));
    }
    out.pose = pose_;
    // The finer angle is reported, not fed back: the votes keep tracking from
    // their own estimate (fed back, it moved the next frames' ROI and cost
    // more than it gained on the microscope scene).
    if (fine_.axis_theta().cells > 1) GABARIT_TRY(angle_by_intensity(image, pose_, *stack_, out.pose.theta_deg));
  }
  ledger_.add(FramePhase::kDepth, 0, read_ticks(clock_) - depth_began);
  if (out.confidence == Confidence::kHigh) last_confident_ = {pose_, filter_.state(), 0};
  if (stack_ != nullptr) {
    ledger_.add(FramePhase::kVerify, stack_sample_work(verdict_.samples), 0);
    ledger_.add(FramePhase::kDepth, stack_correlation_work(*stack_, out.correlations - verdict_.correlations), 0);
  }
  ledger_.correlations = out.correlations;
  if (tracking) {
    // What a tracked frame costs: the budget's measure (integers, so every
    // target budgets alike).
    const std::uint64_t work = ledger_.total_work();
    frame_work_ = frame_work_ == 0 ? work : (7 * frame_work_ + work) / 8;
  }
  // Verifying, the survey for look-alikes, a piece after each tracked frame.
  if (detection_ != nullptr && verifying() && !lost_) {
    if (!surveyed_) detection_->restart_survey();
    surveyed_ = true;
    if (!detection_->surveyed()) {
      const std::uint64_t survey_began = read_ticks(clock_);
      GABARIT_TRY(detection_->survey(image, pose_, scratch.fine, survey_budget(image)));
      ledger_.add(FramePhase::kSurvey, detection_->last_work(), read_ticks(clock_) - survey_began);
    }
  }
  // The rest of the step: what no phase above was charged with.
  const std::uint64_t spent = read_ticks(clock_) - began, charged = ledger_.total_ticks();
  ledger_.add(FramePhase::kOther, 0, spent > charged ? spent - charged : 0);
  out.work = ledger_.total_work();
  out.ledger = ledger_;
  return Status::kOk;
}

std::uint64_t TrackingSession::detection_budget(float frames) const noexcept {
  if (!(frames > 0.0f)) return kUnlimitedWork;
  const std::uint64_t frame = frame_work_ > 0 ? frame_work_ : track_step_work(fine_, StepResult{});
  const float budget = frames * static_cast<float>(frame);
  return budget >= 1.0f ? static_cast<std::uint64_t>(budget) : 1;
}

std::uint64_t TrackingSession::survey_budget(const ImageView& image) const noexcept {
  const std::uint64_t budget = detection_budget(options_.survey_frames);
  const std::uint64_t floor = std::uint64_t{image.width} * image.height * kSurveyUnitsPerPixel;
  return budget > floor ? budget : floor;
}

// The confidence ratios (none below low_ratio of the reference score) tell
// the target from chance only while chance scores below that: d, this
// frame's features per ROI pixel, is what a stencil collects by chance. Where
// d reaches low_ratio of the reference (binary frames in heavy noise), a
// measurement must also stand above chance, (s - d) / (1 - d), at least
// clutter_floor as high as the reference does. Below, nothing changes.
bool TrackingSession::clutter_rejects(float score, const StepResult& step) const noexcept {
  const float d = static_cast<float>(step.features) / static_cast<float>(fine_.roi_pixels());
  const float reference = filter_.reference();
  if (!(d >= options_.filter.low_ratio * reference)) return false;
  return contrast(score, step, fine_) < options_.clutter_floor * contrast(reference, step, fine_);
}

// A best cell on the edge of the table's x or y range may be the foot of a
// peak that lies outside the window (the prediction missed): not confident.
bool TrackingSession::on_translation_border(std::uint32_t cell) const noexcept {
  const Axis ax = fine_.axis_x(), ay = fine_.axis_y();
  const std::uint32_t ix = cell % ax.cells, iy = (cell / ax.cells) % ay.cells;
  return (ax.cells > 2 && (ix == 0 || ix + 1 == ax.cells)) || (ay.cells > 2 && (iy == 0 || iy + 1 == ay.cells));
}

// The sub-cell offset of `cell` in the vote just made (`step`, whose
// features and counters are still in scratch.fine): by aligning the features
// when asked (falling back to the parabola when the alignment has too little
// to go on), else by the parabola through the neighbouring cells' scores.
SubCellOffset TrackingSession::sub_cell(SessionScratch scratch, const StepResult& step, std::uint32_t cell) const noexcept {
  SubCellOffset o;
  if (options_.align_features) {
    const std::size_t n = step.features < scratch.fine.features.size() ? step.features : scratch.fine.features.size();
    if (refine_by_alignment(fine_, scratch.fine.features.first(n), scratch.fine.roi_mask, cell, o)) return o;
  }
  return refine_within_cell(fine_, scratch.fine.counters, cell);
}

bool TrackingSession::theta_observable(std::span<const VoteCounter> counters, std::uint32_t cell) const noexcept {
  const Axis ax = fine_.axis_x(), ay = fine_.axis_y(), at = fine_.axis_theta();
  if (at.cells < 2) return true;  // nothing to choose: the angle is the prior's
  const std::uint32_t stride = ax.cells * ay.cells;
  const std::uint32_t it = (cell / stride) % at.cells;
  const auto score = [&](std::uint32_t c) { return normalised_score({c, counters[c], fine_.cell(c).stencil_size}); };
  const float s0 = score(cell);
  float neighbour = 0.0f;
  if (it > 0) neighbour = score(cell - stride);
  if (it + 1 < at.cells) {
    const float s = score(cell + stride);
    neighbour = s > neighbour ? s : neighbour;
  }
  return s0 - neighbour >= options_.theta_observability * s0;
}

// The vote's best cells as poses, best first (cells without a vote left out).
void TrackingSession::propose_top_cells(std::span<const VoteCounter> counters, const Pose& centre, Measurement& m) const noexcept {
  CellScore top[kMaxVoteProposals];
  std::uint32_t k = options_.vote_proposals;
  if (k > fine_.cell_count()) k = fine_.cell_count();
  if (select_top_cells(fine_, counters, std::span<CellScore>(top, k)) != Status::kOk) return;
  for (std::uint32_t i = 0; i < k && top[i].votes > 0; ++i)
    m.proposals[m.proposal_count++] = pose_of_cell(fine_, top[i].cell, centre, m.step.roi_centre_x, m.step.roi_centre_y);
}

// Vote, then verify: the best-correlated proposal, refined, replaces
// `chosen` (which is proposed first, so it wins a tie) where it correlates
// at least verify_accept of the reference; confident frames taken so move
// the reference.
Status TrackingSession::verify_choice(const ImageView& image, const Proposals& proposals, Confidence confidence,
                                      Pose& chosen) noexcept {
  VerifyOptions o = options_.verification;
  o.refine_angle = o.refine_angle && fine_.axis_theta().cells > 1;  // no angle axis: the motion has no rotation
  // Another placement, for near-ties and ambiguity: at least a sixth of the
  // model image's smaller side away (a broad correlation peak is one place).
  const ImageView& model = stack_->images[0];
  const float apart = static_cast<float>(model.width < model.height ? model.width : model.height) / 6.0f;
  if (apart > o.distinct_px) o.distinct_px = apart;
  const std::uint64_t began = read_ticks(clock_);
  const Status verified = verify(image, *stack_, proposals, o, verdict_);
  ledger_.add(FramePhase::kVerify, 0, read_ticks(clock_) - began);  // its work is counted with the frame's correlations
  GABARIT_TRY(verified);
  if (!verdict_.found) return Status::kOk;
  frame_reference_ = verified_reference_;
  if (verdict_.score < options_.verify_accept * frame_reference_) frame_reference_ = reference_at(image, verdict_.pose);
  verdict_taken_ = !(frame_reference_ > 0.0f) || verdict_.score >= options_.verify_accept * frame_reference_;
  if (!verdict_taken_) return Status::kOk;
  chosen = verdict_.pose;
  if (confidence == Confidence::kHigh) {
    verified_reference_ = verified_reference_ > 0.0f ? 0.9f * verified_reference_ + 0.1f * verdict_.score : verdict_.score;
    float variance = 0.0f;
    if (frame_variance_at(image, verdict_.pose, *stack_, verdict_.pose.depth, variance) && variance > 0.0f)
      verified_variance_ = verified_variance_ > 0.0f ? 0.9f * verified_variance_ + 0.1f * variance : variance;
  }
  return Status::kOk;
}

// The reference a frame's verified score is held to, as its contrast at
// `pose` allows. The reference correlation r falls short of 1 by the noise
// (and what else the model does not explain), n^2 = (1 - r^2) V of the
// frame's variance V at confident poses; the object's own share is V - n^2.
// A frame dimmed to variance V' keeps the noise and loses object: it can
// correlate only sqrt(1 - n^2 / V'). So a dim frame's pose is held to that
// (never below half the reference), a brighter frame's to the reference as
// it is. Without it, the trough of a light swing took no measurement and
// declared a tracked target lost (docs/tracking.md, "Vote, then verify").
float TrackingSession::reference_at(const ImageView& image, const Pose& pose) const noexcept {
  float variance = 0.0f;
  if (!(verified_reference_ > 0.0f && verified_variance_ > 0.0f) ||
      !frame_variance_at(image, pose, *stack_, pose.depth, variance) || !(variance < verified_variance_)) {
    return verified_reference_;
  }
  const float noise = (1.0f - verified_reference_ * verified_reference_) * verified_variance_;
  const float r2 = 1.0f - noise / variance;
  const float floor = 0.5f * verified_reference_;
  if (!(r2 > floor * floor)) return floor;
  const float r = correlation_from_signed_square(r2);
  return r < verified_reference_ ? r : verified_reference_;
}

Status TrackingSession::vote_at(const ImageView& image, const Pose& centre, TrackerScratch scratch, StepResult& step) noexcept {
  // Exactly track_step (tracker.cpp), with a clock reading between its halves.
  const std::uint64_t began = read_ticks(clock_);
  PreparedFrame frame;
  GABARIT_TRY(prepare_frame(fine_, detector_, image, centre, scratch, frame));
  const std::uint64_t prepared = read_ticks(clock_);
  VoteTally tally;
  GABARIT_TRY(vote_prepared(fine_, frame, scratch, tally));
  GABARIT_TRY(finish_frame(fine_, centre, frame, scratch.counters, tally, step));
  ledger_.add(FramePhase::kFeatures, track_features_work(fine_), prepared - began);
  ledger_.add(FramePhase::kVote, step.votes, read_ticks(clock_) - prepared);
  ledger_.pixels_scanned += frame.pixels_scanned;
  ledger_.features += step.features;
  ledger_.votes += step.votes;
  return Status::kOk;
}

Status TrackingSession::measure_at(const ImageView& image, const Pose& centre, SessionScratch scratch, Measurement& m) noexcept {
  m = Measurement{};
  GABARIT_TRY(vote_at(image, centre, scratch.fine, m.step));
  if (verifying()) propose_top_cells(scratch.fine.counters, centre, m);
  GatedChoice choice;
  GABARIT_TRY(filter_.choose(fine_, scratch.fine.counters, centre, m.step.roi_centre_x, m.step.roi_centre_y, pose_.depth, choice));
  if (!choice.found) return Status::kOk;
  m.score = choice.score;
  m.next_score = choice.next_score;
  m.confidence = filter_.classify(m.score, m.next_score);
  // Not confident where the cell stands little above what clutter gives by
  // chance, compared with the reference score's standing.
  if (clutter_rejects(choice.score, m.step)) m.confidence = Confidence::kNone;
  if ((choice.outranked || on_translation_border(choice.cell.cell)) && m.confidence == Confidence::kHigh)
    m.confidence = Confidence::kIntermediate;
  if (m.confidence == Confidence::kNone) return Status::kOk;
  SubCellOffset o;
  if (options_.refine) o = sub_cell(scratch, m.step, choice.cell.cell);
  m.theta_observable = theta_observable(scratch.fine.counters, choice.cell.cell);
  if (!m.theta_observable) o.theta_deg = 0.0f;
  // Where the votes barely tell the angles apart (a near-symmetric outline)
  // the angle is the cell's, as in the plain loop: no sub-cell offset.
  m.pose = pose_of_cell(fine_, choice.cell.cell, centre, m.step.roi_centre_x, m.step.roi_centre_y, o.x, o.y, o.theta_deg);
  // How clearly the votes chose the depth: the chosen cell's score over the
  // best of any other depth.
  m.depth_margin = 0.0f;
  if (fine_.depth_count() > 1) {
    float other = 0.0f;
    for (std::uint16_t d = 0; d < fine_.depth_count(); ++d) {
      if (d == m.pose.depth) continue;
      const float sd = normalised_score(best_cell_in(fine_, scratch.fine.counters, fine_.depth_cells(d)));
      other = sd > other ? sd : other;
    }
    m.depth_margin = other > 0.0f ? choice.score / other - 1.0f : 1.0f;
  }
  return Status::kOk;
}

namespace {
// The better of two measurements: higher confidence, then higher score.
bool better(const TrackingSession::Measurement& a, const TrackingSession::Measurement& b) noexcept {
  if (a.confidence != b.confidence) return static_cast<int>(a.confidence) < static_cast<int>(b.confidence);
  return a.score > b.score;
}
}  // namespace

Status TrackingSession::track_fine(const ImageView& image, SessionScratch scratch, SessionResult& out) noexcept {
  const Pose predicted = options_.motion_filter ? filter_.predict(pose_) : pose_;
  if (!options_.motion_filter) {
    // The thesis's loop: the best cell, whatever its score.
    GABARIT_TRY(vote_at(image, predicted, scratch.fine, out.step));
    out.score = out.step.score;
    out.confidence = filter_.grade(out.step.score, normalised_score(out.step.runner_up));
    out.state = out.step.state;
    if (out.step.state != TrackState::kLost) {
      SubCellOffset o;
      if (options_.refine) o = sub_cell(scratch, out.step, out.step.best.cell);
      pose_ = pose_of_cell(fine_, out.step.best.cell, predicted, out.step.roi_centre_x, out.step.roi_centre_y, o.x, o.y, o.theta_deg);
    }
    if (out.step.state == TrackState::kLost && options_.recover) begin_lost();
    out.pose = pose_;
    return Status::kOk;
  }

  Measurement m;
  GABARIT_TRY(measure_at(image, predicted, scratch, m));
  Proposals proposals;
  const auto propose = [&proposals](const Measurement& from) {
    for (std::uint32_t i = 0; i < from.proposal_count; ++i) proposals.add(from.proposals[i]);
  };
  propose(m);
  // The plain loop's choice this frame: the best cell of the vote at the
  // last pose (here the prediction's vote when they coincide).
  StepResult plain = m.step;
  // Not confident at the prediction: the target may have turned back (or the
  // velocity be wrong). Vote at the last pose too, as the plain loop would,
  // and keep the better of the two, so a reversal is measured, not coasted.
  const float dx = predicted.x - pose_.x, dy = predicted.y - pose_.y;
  if (m.confidence != Confidence::kHigh && options_.vote_at_last_pose &&
      (dx * dx + dy * dy >= 0.25f || predicted.theta_deg != pose_.theta_deg)) {
    Measurement at_last;
    GABARIT_TRY(measure_at(image, pose_, scratch, at_last));
    plain = at_last.step;
    propose(at_last);
    if (better(at_last, m)) m = at_last;
  }
  out.step = m.step;
  out.score = m.score;
  depth_margin_ = m.depth_margin;
  Confidence confidence = m.confidence;
  // No measurement the filter trusts: partly hidden, the target still wins
  // the plain loop's vote, so follow that (never worse than the thesis's
  // loop); the filter only predicts, and if it stays unsure the target is
  // declared lost and searched for around the last confident pose.
  Pose chosen = confidence != Confidence::kNone ? m.pose
                : options_.follow_when_unsure && plain.state != TrackState::kLost ? plain.pose
                                                                                   : predicted;
  bool verified_only = false;  // a measurement by the verified score alone
  if (verifying()) {
    // The session's own choice first, then the votes' other proposals.
    Proposals all;
    all.add(chosen);
    if (plain.state != TrackState::kLost) all.add(plain.pose);
    for (std::uint32_t i = 0; i < proposals.count; ++i) all.add(proposals.poses[i]);
    all.add(predicted);
    all.add(pose_);
    GABARIT_TRY(verify_choice(image, all, confidence, chosen));
    // Not taken (the best correlates below verify_accept of the reference:
    // a dim frame, a partial occlusion), the votes' choice still loses to a
    // proposal that correlates better than it: that one is the pose, with
    // the votes' confidence. Keeping the votes' choice, a horse over the moon
    // in the trough of a light swing walked 10 px off onto the moon's edges
    // and was lost (the test
    // Tracking.AHorseInTheTroughOfALightSwingIsTrackedThroughIt).
    if (verdict_.found && !verdict_taken_ && verdict_.winner != 0) chosen = verdict_.pose;
    // Where the votes chose the depth clearly, they keep it (edge features
    // tell depths apart better than intensities over a textured object).
    if (verdict_taken_ && confidence != Confidence::kNone && m.depth_margin >= options_.depth_votes_decisive)
      chosen.depth = m.pose.depth;
    // Lost is declared from the verified score, not from the votes: where
    // the best proposal correlates below verify_lost of the reference, there
    // is no measurement to trust (the filter coasts, and declares the target
    // lost if it stays so).
    if (verdict_.found && frame_reference_ > 0.0f && verdict_.score < options_.verify_lost * frame_reference_)
      confidence = Confidence::kNone;
    // And the other way: where the votes are too weak to trust (a dimmed
    // frame's edges fall below the detector's thresholds) but the verified
    // pose correlates as a tracked frame must, that is a measurement.
    verified_only = confidence == Confidence::kNone && verdict_taken_ && verified_reference_ > 0.0f;
    if (verified_only) confidence = Confidence::kIntermediate;
  }
  // Only the votes' own measurements move the votes' reference score.
  if (confidence != Confidence::kNone && !verified_only) static_cast<void>(filter_.grade(m.score, m.next_score));
  if (confidence != Confidence::kNone) {
    // The angle is measured even where the votes barely constrain it (only
    // its sub-cell offset is dropped): left out of the filter, its velocity
    // went stale and the suite's tuning half tracked worse (docs/tracking.md).
    filter_.update(confidence, chosen);
  } else {
    filter_.coast();
  }
  pose_ = chosen;
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
  GABARIT_TRY(recover_by_stage(image, scratch, out));
  if (out.reacquired || scan_ == nullptr || !verifying() || !(verified_reference_ > 0.0f)) return Status::kOk;
  return recover_by_scan(image, out);
}

Status TrackingSession::recover_by_scan(const ImageView& image, SessionResult& out) noexcept {
  const std::uint64_t began = read_ticks(clock_);
  IntensityScanResult scanned;
  const Status status = scan_->run(image, last_confident_, scanned);
  ledger_.add(FramePhase::kRecovery, scanned.work, read_ticks(clock_) - began);
  // A scan that cannot run (a stack without samples) leaves the frame lost.
  if (status != Status::kOk || !scanned.scored) return Status::kOk;
  if (detection_ != nullptr && !detection_->within_reach(last_confident_, scanned.best)) return Status::kOk;
  Proposals candidate;
  candidate.add(scanned.best);
  Pose found_pose;
  verdict_taken_ = false;
  GABARIT_TRY(verify_choice(image, candidate, Confidence::kNone, found_pose));
  if (!verdict_taken_ || (detection_ != nullptr && !detection_->within_reach(last_confident_, found_pose))) return Status::kOk;
  pose_ = found_pose;
  filter_.restart(pose_);
  lost_ = false;
  out.reacquired = true;
  out.confidence = Confidence::kIntermediate;
  out.state = TrackState::kUncertain;
  out.pose = pose_;
  return Status::kOk;
}

Status TrackingSession::recover_by_stage(const ImageView& image, SessionScratch scratch, SessionResult& out) noexcept {
  SearchResult found;
  // The depth last seen with confidence: the frames since, unsure, may have
  // set the pose's depth from clutter.
  const std::uint32_t lost_frame = lost_frames_++;
  const std::uint64_t began = read_ticks(clock_);
  if (detection_ != nullptr && lost_frame >= options_.recovery.detect_after) {
    GABARIT_TRY(detection_->run(image, last_confident_, scratch.fine, detection_budget(options_.recovery_frames), found));
    found.work = detection_->last_work();
  } else if (particles_ != nullptr) {
    GABARIT_TRY(particles_->run(image, last_confident_, scratch.fine, found));
  } else {
    GABARIT_TRY(search_.run(image, options_.recovery, last_confident_, last_confident_.pose.depth, scratch, found));
  }
  ledger_.add(FramePhase::kRecovery, found.work, read_ticks(clock_) - began);
  out.searched_coarse = found.searched_coarse;
  out.state = TrackState::kLost;
  out.pose = pose_;
  if (!found.searched) return Status::kOk;
  out.step = found.vote;
  out.score = out.step.score;
  const bool confident = out.step.best.votes > 0 &&
                         filter_.classify(out.score, normalised_score(out.step.runner_up)) == Confidence::kHigh &&
                         !clutter_rejects(out.score, out.step);
  out.confidence = confident ? Confidence::kHigh : Confidence::kNone;
  // Verifying, a search whose vote is too weak to trust (a dimmed frame's
  // edges fall below the detector's thresholds) is still taken where the
  // pose it found correlates as a tracked frame must (below), as a tracked
  // frame's verified-only measurement is.
  const bool verified_only = !confident && out.step.best.votes > 0 && verifying() && verified_reference_ > 0.0f;
  if (!confident && !verified_only) return Status::kOk;
  SubCellOffset o;
  if (options_.refine) o = refine_within_cell(fine_, scratch.fine.counters, out.step.best.cell);
  Pose found_pose = pose_of_cell(fine_, out.step.best.cell, found.from, out.step.roi_centre_x, out.step.roi_centre_y, o.x, o.y,
                                 o.theta_deg);
  if (verifying() && verified_reference_ > 0.0f) {
    // Verifying, the target is found again only where the model correlates
    // as well as a tracked frame must (verify_accept of the reference): a
    // look-alike that wins a vote does not.
    Proposals candidate;
    candidate.add(found_pose);
    GABARIT_TRY(verify_choice(image, candidate, Confidence::kNone, found_pose));
    if (!verdict_taken_) {
      out.confidence = Confidence::kNone;
      return Status::kOk;
    }
  }
  if (!confident) out.confidence = Confidence::kIntermediate;
  pose_ = found_pose;
  filter_.restart(pose_);
  lost_ = false;
  out.reacquired = true;
  out.state = TrackState::kUncertain;
  out.pose = pose_;
  return Status::kOk;
}

}  // namespace gabarit
