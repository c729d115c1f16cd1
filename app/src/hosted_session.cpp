#include "gabarit/app/hosted_session.hpp"

#include <string>

#include "gabarit/app/error.hpp"
#include "gabarit/app/particle_run.hpp"
#include "gabarit/app/pose_row.hpp"

namespace gabarit::app {

namespace {

const SessionProfile& checked(const SessionProfile& profile) {
  if (validate(profile) != Status::kOk) throw Error("the session profile is not valid");
  return profile;
}

// The profile as it runs on `table`: the recovery stage and the particle
// tracker's measure resolved (CAPS reports them so).
SessionProfile resolved(const SessionProfile& profile, const TableView& table, const std::optional<Detector>& detector) {
  const bool verifies = table_verifies(table, detector ? *detector : detector_of(table));
  SessionProfile p = resolve_recovery(checked(profile), verifies);
  if (p.tracker == TrackerKind::kParticle) {
    // Detection runs where the table verifies (ParticleRunOptions::detection).
    if (!verifies) p.particle_improvements_off |= kImproveDetection;
    p.particle_measure = resolved_measure(p.particle_measure, table.has_model_images());
    if (p.particle_measure == ParticleMeasureKind::kIntensity && !table.has_model_images())
      throw Error("particle filter: the intensity measure needs a table with model images (tables build from images stores them)");
  }
  return p;
}

}  // namespace

HostedSession::HostedSession(const TableView& table, const SessionProfile& profile, SessionExtras extras)
    : table_(table),
      profile_(resolved(profile, table, extras.detector)),
      extras_(std::move(extras)),
      options_(extras_.research_options ? *extras_.research_options : session_options(profile_)),
      detector_(extras_.detector ? *extras_.detector : detector_of(table)),
      // The grid search detects once per lost frame (recovery_search.hpp) unless the profile says not to.
      buffers_(table, extras_.coarse, extras_.voter, options_.recover && profile_.shared_search),
      table_stack_(table),
      finder_(table, detector_) {
  if (!extras_.focus_stack.empty()) {
    if (extras_.focus_stack.size() != table.depth_count()) {
      throw Error("the focus stack has " + std::to_string(extras_.focus_stack.size()) + " images; the table has " +
                  std::to_string(table.depth_count()) + " depths");
    }
    for (const GrayImage& image : extras_.focus_stack) {
      if (image.width != extras_.focus_stack[0].width || image.height != extras_.focus_stack[0].height) {
        throw Error("the focus stack's images differ in size");
      }
      stack_views_.push_back(image.view());
    }
    stack_ = FocusStack{stack_views_, table.model_ref_x(), table.model_ref_y(), 2};
    stack_in_use_ = &stack_;
  } else if (uses_table_focus_stack(profile_)) {
    stack_in_use_ = table_stack_.get();
  }
  if (uses_table_focus_stack(profile_)) finder_.use_focus_stack(table_stack_.get());
  const bool detection = profile_.recovery == RecoveryKind::kDetection;
  const bool particles = profile_.recovery == RecoveryKind::kParticles;
  if ((detection || particles) && !options_.recover) throw Error("the profile's recovery stage needs recovery on");
  if (!valid(extras_.finder)) throw Error("detection: invalid options");
  if (particles && !valid(ParticleRecoveryOptions{})) throw Error("particle recovery: invalid options");
}

HostedSession::~HostedSession() = default;

bool HostedSession::start(const Pose& initial) {
  session_.reset();
  detection_.reset();  // the recovery stages start afresh with the session
  particle_recovery_.reset();
  particles_.reset();
  particle_started_ = false;
  if (profile_.tracker == TrackerKind::kParticle) {
    // The pose checks the session's start makes (pose_in_range, the depth).
    if (!pose_in_range(initial) || initial.depth >= table_.depth_count()) return false;
    start_pose_ = initial;
    particle_started_ = true;
    return true;
  }
  session_.emplace(table_, extras_.coarse, detector_);
  if (session_->start(options_, initial) != Status::kOk) {
    session_.reset();
    return false;
  }
  start_pose_ = initial;
  session_->use_focus_stack(stack_in_use_);
  session_->use_clock(&steady_nanoseconds);
  return true;
}

void HostedSession::fit_frame(std::uint32_t width, std::uint32_t height) {
  const bool detection = profile_.recovery == RecoveryKind::kDetection;
  if ((detection || !session_) && (!finder_buffers_ || finder_buffers_->width() != width || finder_buffers_->height() != height)) {
    // The finder's buffers are the frame's size; a new size needs new ones.
    finder_buffers_.emplace(table_, detector_, extras_.finder, width, height);
    detection_.reset();
  }
  if (!session_) return;
  if (detection && !detection_) {
    detection_.emplace(finder_, extras_.finder, finder_buffers_->scratch(buffers_.scratch().fine));
    session_->use_detection_recovery(&*detection_);
    if (stack_in_use_ != nullptr && !scan_) {
      scan_ = std::make_unique<IntensityScan>();
      scan_->reset(table_, *stack_in_use_, IntensityScanOptions{});
    }
    if (scan_) session_->use_intensity_scan(scan_.get());
  }
  if (profile_.recovery == RecoveryKind::kParticles && !particles_) {
    // Its edge map is the first frame's size.
    // ParticleRecovery drives an EdgeParticleFilter: the edge measure.
    ParticleRunOptions po = particle_run_options(profile_);
    po.measure = ParticleMeasureKind::kEdges;
    po.proposals = 0;  // ParticleRecovery votes the heaviest modes itself (docs/particle-filter.md, "Re-acquisition")
    po.detection = false;  // it drives the filter itself (edge_filter), not ParticleTracker::step
    particles_ = std::make_unique<ParticleTracker>(table_, width, height, po);
    particles_->start(start_pose_);
    particle_recovery_.emplace(table_, detector_, particles_->edge_filter());
    session_->use_particle_recovery(&*particle_recovery_);
  }
}

bool HostedSession::start_by_detection(const ImageView& frame) {
  fit_frame(frame.width, frame.height);
  FinderOptions one = extras_.finder;
  one.max_count = 1;
  Detection found[1];
  std::uint32_t count = 0;
  if (const Status s = finder_.find(frame, one, finder_buffers_->scratch(buffers_.scratch().fine), found, count); s != Status::kOk)
    throw Error(std::string("detection failed: ") + status_name(s));
  if (count == 0) return false;
  if (!start(found[0].pose)) throw Error("the session rejected the detected pose");
  return true;
}

Status HostedSession::particle_step(const ImageView& frame, SessionResult& out) {
  if (!particles_) {
    // As gabarit track --tracker particle runs it (run_particle_tracking): built at the first frame, for its size.
    ParticleRunOptions po = particle_run_options(profile_);
    po.voter = extras_.voter;
    po.detector = extras_.detector;
    particles_ = std::make_unique<ParticleTracker>(table_, frame.width, frame.height, po);
    particles_->start(start_pose_);
    particle_width_ = frame.width, particle_height_ = frame.height;
  } else if (frame.width != particle_width_ || frame.height != particle_height_) {
    return Status::kInvalidArgument;
  }
  out = particle_session_result(particles_->step(frame), particles_->ledger());
  return Status::kOk;
}

Status HostedSession::step(const ImageView& frame, SessionResult& out) {
  if (profile_.tracker == TrackerKind::kParticle) return particle_started_ ? particle_step(frame, out) : Status::kInvalidArgument;
  if (!session_) return Status::kInvalidArgument;
  fit_frame(frame.width, frame.height);
  return session_->step(frame, buffers_.scratch(), out);
}

std::uint32_t HostedSession::mode() const {
  return mode_bits(profile_, buffers_.shares_search_features(), stack_in_use_ != nullptr && stack_in_use_ == table_stack_.get());
}

}  // namespace gabarit::app
