#include "gabarit/app/session_profile.hpp"

#include "gabarit/link/protocol.hpp"
#include "gabarit/recovery_search.hpp"

namespace gabarit::app {

ParticleFilterOptions particle_filter_options(std::uint32_t off) noexcept {
  ParticleFilterOptions o = (off & kAllImprovements) != 0 ? plain_condensation() : ParticleFilterOptions{};
  if ((off & kImproveModes) != 0) o.modes = false;
  if ((off & kImproveDisambiguation) != 0) o.disambiguate = false;
  if ((off & kImproveNarrowing) != 0) o.narrow_spread = false;
  if ((off & kImproveKinematics) != 0) o.kinematic_weighting = false;
  if ((off & kImproveReinit) != 0) o.partial_reinit = false;
  if ((off & kImproveModeFilter) != 0) o.mode_filter = false;
  if ((off & kImproveVelocity) != 0) o.constant_velocity = false;
  if ((off & kImproveProposals) != 0) o.proposal_fraction = 0.0f;
  return o;
}

SessionResult particle_session_result(const ParticleEstimate& e, const FrameLedger& ledger) noexcept {
  SessionResult out;
  out.pose = e.pose;
  out.step.pose = e.pose;
  out.step.score = e.score;
  out.step.state = e.state;
  out.state = e.state;
  out.score = e.score;
  out.confidence = e.state == TrackState::kTracking    ? Confidence::kHigh
                   : e.state == TrackState::kUncertain ? Confidence::kIntermediate
                                                       : Confidence::kNone;
  out.ledger = ledger;
  out.step.features = static_cast<std::uint32_t>(ledger.features);
  out.step.votes = ledger.votes;
  out.work = ledger.total_work();
  return out;
}

Status validate(const SessionProfile& p) noexcept {
  const auto within = [](std::uint64_t v, std::uint64_t lo, std::uint64_t hi) { return v >= lo && v <= hi; };
  const bool numbers = within(p.search_budget, 0, kSearchPlacementCount - kSearchNear) && within(p.search_interval, 1, 100) &&
                       within(p.screen_stride, 1, 16) && within(p.detect_after, 0, 1000) &&
                       within(p.recovery_frames, 0, 1000) && within(p.survey_frames, 0, 1000) &&
                       within(p.particles, 1, 1000000) && within(p.edge_stride, 1, 64) && within(p.edge_tolerance, 0, 3) &&
                       (p.particle_improvements_off & ~kKnownImprovements) == 0 &&
                       static_cast<std::uint8_t>(p.particle_clustering) <= static_cast<std::uint8_t>(ModeClustering::kRunningMean);
  const bool kinds = static_cast<std::uint8_t>(p.recovery) <= static_cast<std::uint8_t>(RecoveryKind::kAuto) &&
                     static_cast<std::uint8_t>(p.subcell) <= static_cast<std::uint8_t>(SubCellKind::kAlignment) &&
                     static_cast<std::uint8_t>(p.tracker) <= static_cast<std::uint8_t>(TrackerKind::kParticle) &&
                     static_cast<std::uint8_t>(p.particle_measure) <= static_cast<std::uint8_t>(ParticleMeasureKind::kIntensity);
  // The particle tracker is not the thesis's loop; a measure names the particle tracker's.
  const bool tracker = p.tracker == TrackerKind::kParticle ? !p.plain : p.particle_measure == ParticleMeasureKind::kAuto;
  const bool parts = (p.plain || (!p.motion_filter && !p.refine && !p.recover)) &&
                     (!needs_recovery(p.recovery) || recovers(p)) &&
                     (p.subcell == SubCellKind::kParabola || refines(p));
  return numbers && kinds && parts && tracker ? Status::kOk : Status::kInvalidArgument;
}

SessionProfile resolve_recovery(const SessionProfile& profile, bool verifying_table) noexcept {
  SessionProfile p = profile;
  if (p.recovery == RecoveryKind::kAuto)
    p.recovery = verifying_table && !p.plain && p.verify && p.focus_stack ? RecoveryKind::kDetection : RecoveryKind::kGrid;
  return p;
}

SessionOptions session_options(const SessionProfile& p) noexcept {
  SessionOptions o;
  if (p.plain) {
    const SessionOptions defaults;
    o = kPlainSession;
    o.motion_filter = p.motion_filter;
    o.refine = p.refine;
    o.recover = p.recover;
    if (p.motion_filter) {  // the motion filter brings its own defaults
      o.vote_at_last_pose = defaults.vote_at_last_pose;
      o.follow_when_unsure = defaults.follow_when_unsure;
      o.theta_observability = defaults.theta_observability;
    }
  }
  o.verify = !p.plain && p.verify;
  o.verification.refine_by = p.verify_refine;
  o.align_features = p.subcell == SubCellKind::kAlignment;
  o.recovery.budget = p.search_budget;
  o.recovery.interval = p.search_interval;
  o.recovery.screen_stride = p.screen_stride;
  o.recovery.detect_after = p.detect_after;
  o.recovery_frames = static_cast<float>(p.recovery_frames);
  o.survey_frames = static_cast<float>(p.survey_frames);
  return o;
}

namespace {

// The profile's numbers (and the verifier's refinement) are the defaults
// (they do not travel in CAPS).
bool default_numbers(const SessionProfile& p) noexcept {
  const SessionProfile d;
  return p.search_budget == d.search_budget && p.search_interval == d.search_interval &&
         p.screen_stride == d.screen_stride && p.detect_after == d.detect_after && p.recovery_frames == d.recovery_frames &&
         p.survey_frames == d.survey_frames && p.particles == d.particles &&
         p.seed == d.seed && p.edge_stride == d.edge_stride && p.edge_tolerance == d.edge_tolerance &&
         // Detection on or off travels in CAPS (kModeRecoveryDetection).
         (p.particle_improvements_off & ~kImproveDetection) == (d.particle_improvements_off & ~kImproveDetection) &&
         p.verify_refine == d.verify_refine &&
         p.particle_clustering == d.particle_clustering;
}

// The particle tracker's bits: its measure as the device resolved it.
std::uint32_t particle_tracker_bits(const SessionProfile& p) noexcept {
  std::uint32_t bits = link::kModeParticleTracker;
  bits |= (static_cast<std::uint32_t>(p.particle_measure) << link::kModeParticleMeasureShift) & link::kModeParticleMeasureMask;
  if (particle_detection(p)) bits |= link::kModeRecoveryDetection;
  if (!default_numbers(p)) bits |= link::kModeTuned;
  return bits;
}

}  // namespace

std::uint32_t mode_bits(const SessionProfile& p, bool shares_search, bool has_stack) noexcept {
  if (p.tracker == TrackerKind::kParticle) return particle_tracker_bits(p);
  std::uint32_t bits = 0;
  if (!p.plain) bits |= link::kModeSession;
  if (recovers(p) && p.shared_search && shares_search) bits |= link::kModeSharedSearch;
  if (uses_table_focus_stack(p) && has_stack) bits |= link::kModeFocusStack;
  if (!p.plain && !p.verify) bits |= link::kModeNoVerify;
  if (p.plain && p.motion_filter) bits |= link::kModeMotionFilter;
  if (p.plain && p.refine) bits |= link::kModeRefine;
  if (p.plain && p.recover) bits |= link::kModeRecover;
  if (p.recovery == RecoveryKind::kDetection) bits |= link::kModeRecoveryDetection;
  if (p.recovery == RecoveryKind::kParticles) bits |= link::kModeRecoveryParticles;
  if (p.subcell == SubCellKind::kAlignment) bits |= link::kModeSubCellAlignment;
  if (!default_numbers(p)) bits |= link::kModeTuned;
  return bits;
}

SessionProfile profile_from_mode_bits(std::uint32_t bits) noexcept {
  SessionProfile p;
  if ((bits & link::kModeParticleTracker) != 0) {
    p.tracker = TrackerKind::kParticle;
    p.particle_measure = static_cast<ParticleMeasureKind>((bits & link::kModeParticleMeasureMask) >> link::kModeParticleMeasureShift);
    if ((bits & link::kModeRecoveryDetection) == 0) p.particle_improvements_off |= kImproveDetection;
    return p;
  }
  p.plain = (bits & link::kModeSession) == 0;
  p.shared_search = (bits & link::kModeSharedSearch) != 0;
  p.focus_stack = (bits & link::kModeFocusStack) != 0;
  p.verify = (bits & link::kModeNoVerify) == 0;
  p.motion_filter = p.plain && (bits & link::kModeMotionFilter) != 0;
  p.refine = p.plain && (bits & link::kModeRefine) != 0;
  p.recover = p.plain && (bits & link::kModeRecover) != 0;
  p.recovery = RecoveryKind::kGrid;  // CAPS carries what runs: auto already resolved
  if ((bits & link::kModeRecoveryDetection) != 0) p.recovery = RecoveryKind::kDetection;
  if ((bits & link::kModeRecoveryParticles) != 0) p.recovery = RecoveryKind::kParticles;
  if ((bits & link::kModeSubCellAlignment) != 0) p.subcell = SubCellKind::kAlignment;
  return p;
}

}  // namespace gabarit::app
