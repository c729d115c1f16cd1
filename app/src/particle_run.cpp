#include "gabarit/app/particle_run.hpp"

#include <algorithm>
#include <chrono>
#include <optional>
#include <string>

#include "gabarit/app/error.hpp"
#include "gabarit/detection_recovery.hpp"

namespace gabarit::app {

ParticleMeasureKind resolved_measure(ParticleMeasureKind kind, const TableView& table) noexcept {
  return resolved_measure(kind, table.has_model_images());
}

ParticleRunOptions particle_run_options(const SessionProfile& profile) {
  ParticleRunOptions o;
  o.particles = profile.particles;
  o.seed = profile.seed;
  o.edge_stride = profile.edge_stride;
  o.edge_tolerance = profile.edge_tolerance;
  o.filter = particle_filter_options(profile.particle_improvements_off);
  o.filter.mode_clustering = profile.particle_clustering;
  o.measure = profile.particle_measure;
  o.detection = particle_detection(profile);
  // The stencil measure alone: one vote per frame and no edge map, modes
  // ranked by weight, confidence from the vote.
  if (o.measure == ParticleMeasureKind::kStencil) o.finer = false;
  return o;
}

namespace {

// Re-acquisition by detection: the session's stage (detection_recovery.hpp)
// over the particle tracker's frames, with its own finder and scratch.
struct DetectionStage {
  // fine_scratch: track_step's for the table, free between the filter's steps.
  DetectionStage(const TableView& table, const Detector& detector, const FocusStack* stack, TrackerScratch fine_scratch,
                 std::uint32_t width, std::uint32_t height)
      : finder(table, detector),
        finder_buffers(table, detector, FinderOptions{}, width, height),
        fine(fine_scratch),
        stage(finder, FinderOptions{}, finder_buffers.scratch(fine), kParticleDetectionInterval) {
    if (stack != nullptr) finder.use_focus_stack(stack);
  }
  ModelFinder finder;
  FinderBuffers finder_buffers;
  TrackerScratch fine;
  DetectionRecovery stage;
  LastSighting last;       // the last tracking frame's estimate, and the frames since
  bool searching = false;  // since a lost frame, until a tracking one
};

}  // namespace

struct ParticleTracker::Parts {
  using StencilFilter = ParticleFilter<StencilVoteMeasure, EdgeCorrelationMeasure, EdgeMapLoader>;
  using IntensityFilter = IntensityParticleFilter;
  static ParticleRunOptions resolved(ParticleRunOptions o, const TableView& t) {
    o.measure = resolved_measure(o.measure, t);
    return o;
  }
  Parts(const TableView& t, std::uint32_t w, std::uint32_t h, const ParticleRunOptions& o)
      : table(t),
        options(resolved(o, t)),
        detector(o.detector ? *o.detector : detector_of(t)),
        bits(edge_map_words(w, h)),
        features(edge_map_features(w)),
        loader(detector, bits, features, static_cast<std::uint16_t>(w), static_cast<std::uint16_t>(h)),
        edges(t, loader, o.edge_stride, o.edge_tolerance),
        fine(t, loader, 1, o.edge_tolerance),
        buffers(t, o.voter),
        stencil(t, detector, buffers.scratch()),
        table_stack(t),
        cloud(o.particles),
        next(o.particles),
        order(particle_scratch_order(o.particles)) {
    EdgeCorrelationMeasure* finer = o.finer ? &fine : nullptr;
    if (options.measure == ParticleMeasureKind::kEdges) {
      edge_filter.emplace(edges, finer, &loader);
    } else if (options.measure == ParticleMeasureKind::kIntensity) {
      // ParticleTracker refuses a table without images before this.
      intensity.emplace(*table_stack.get(), o.intensity_samples);
      intensity_fine.emplace(*table_stack.get(), 0);
      intensity_filter.emplace(*intensity, o.finer ? &*intensity_fine : nullptr);
      options.filter.sharpness = kIntensitySharpness;
    } else {
      // The edge map only where a measure reads it: the stencil measure alone needs none.
      stencil_filter.emplace(stencil, finer, o.finer ? &loader : nullptr);
    }
    // Vote-guided proposals where the measure is not the vote itself.
    if (o.proposals > 0 && options.filter.proposal_fraction > 0.0f && (edge_filter || intensity_filter)) {
      proposal_buffers.emplace(t, o.voter);
      proposer.emplace(t, detector, proposal_buffers->scratch(), o.proposals);
      if (edge_filter) edge_filter->propose_with(&*proposer);
      if (intensity_filter) intensity_filter->propose_with(&*proposer);
    }
    if (o.detection && table_verifies(t, detector))
      detection.emplace(t, detector, table_stack.get(), buffers.scratch(), w, h);  // the stencil measure votes within a step only
  }
  ParticleFilterCore& core() {
    if (edge_filter) return *edge_filter;
    if (intensity_filter) return *intensity_filter;
    return *stencil_filter;
  }
  const TableView& table;
  ParticleRunOptions options;
  Detector detector;
  std::vector<std::uint64_t> bits;
  std::vector<RoiPoint> features;
  EdgeMapLoader loader;
  EdgeCorrelationMeasure edges, fine;
  app::TrackerBuffers buffers;
  StencilVoteMeasure stencil;
  std::optional<app::TrackerBuffers> proposal_buffers;  // the vote proposer's scratch, apart from the stencil measure's
  std::optional<StencilVoteProposer> proposer;
  TableFocusStack table_stack;
  std::optional<IntensityCorrelationMeasure> intensity, intensity_fine;
  std::vector<Particle> cloud, next;
  std::vector<std::uint32_t> order;
  std::optional<EdgeParticleFilter> edge_filter;
  std::optional<StencilFilter> stencil_filter;
  std::optional<IntensityFilter> intensity_filter;
  std::optional<DetectionStage> detection;
  FrameLedger ledger;
};

ParticleTracker::ParticleTracker(const TableView& table, std::uint32_t max_width, std::uint32_t max_height,
                                 const ParticleRunOptions& options) {
  if (options.particles < 1 || options.particles > kMaxParticles)
    throw app::Error("particle filter: particles must be in 1.." + std::to_string(kMaxParticles));
  if (max_width < 1 || max_height < 1 || max_width > 65535 || max_height > 65535)
    throw app::Error("particle filter: frames must be 1..65535 pixels on a side");
  if (!valid(options.filter)) throw app::Error("particle filter: invalid options");
  if (options.proposals > kMaxParticleProposals)
    throw app::Error("particle filter: at most " + std::to_string(kMaxParticleProposals) + " vote proposals");
  if (resolved_measure(options.measure, table) == ParticleMeasureKind::kIntensity && !table.has_model_images())
    throw app::Error("particle filter: the intensity measure needs a table with model images (tables build from images stores them)");
  parts_ = std::make_unique<Parts>(table, max_width, max_height, options);
}
ParticleTracker::~ParticleTracker() = default;

ParticleFilterCore& ParticleTracker::core() { return parts_->core(); }
const FrameLedger& ParticleTracker::ledger() const { return parts_->ledger; }
bool ParticleTracker::detects() const { return parts_->detection.has_value(); }

EdgeParticleFilter& ParticleTracker::edge_filter() {
  if (!parts_->edge_filter) throw app::Error("particle filter: this one runs the stencil measure, not the edge measure");
  return *parts_->edge_filter;
}

void ParticleTracker::start(const Pose& initial) {
  parts_->core().use_clock(&steady_nanoseconds);
  const Status s = parts_->core().start(parts_->options.filter, initial, parts_->table.depth_count(), parts_->options.seed,
                                        {parts_->cloud, parts_->next, parts_->order});
  if (s != Status::kOk) throw app::Error(std::string("particle filter: start failed: ") + status_name(s));
  if (DetectionStage* d = parts_->detection ? &*parts_->detection : nullptr) {
    d->stage.reset();
    d->stage.restart_survey();
    d->last = {initial, {}, 0};
    d->searching = false;
  }
}

ParticleEstimate ParticleTracker::step(const ImageView& frame) {
  Parts& p = *parts_;
  DetectionStage* d = p.detection ? &*p.detection : nullptr;
  FrameLedger detection_ledger;
  if (d != nullptr) {
    ++d->last.frames_since;
    // After a lost frame, a search on this one, before the filter's step, so
    // that the cloud is drawn around what it finds this frame.
    if (d->searching) {
      const std::uint64_t began = steady_nanoseconds();
      SearchResult found;
      if (const Status s = d->stage.run(frame, d->last, d->fine, kUnlimitedWork, found); s != Status::kOk)
        throw app::Error(std::string("particle filter: detection failed: ") + status_name(s));
      if (found.searched && found.vote.best.votes > 0) {
        const Pose pose =
            pose_of_cell(p.table, found.vote.best.cell, found.from, found.vote.roi_centre_x, found.vote.roi_centre_y);
        if (d->stage.within_reach(d->last, pose)) p.core().reinitialise_around(pose, kParticleDetectionFraction);
      }
      detection_ledger.add(FramePhase::kRecovery, d->stage.last_work(), steady_nanoseconds() - began);
    }
  }
  ParticleEstimate e;
  const Status s = p.edge_filter        ? p.edge_filter->step(frame, e)
                   : p.intensity_filter ? p.intensity_filter->step(frame, e)
                                        : p.stencil_filter->step(frame, e);
  if (s != Status::kOk) throw app::Error(std::string("particle filter: step failed: ") + status_name(s));
  if (d != nullptr) {
    if (e.state == TrackState::kTracking) {
      const ParticleContext& c = p.core().context();
      d->last = {e.pose, {c.vx, c.vy, c.vtheta, 0.0f}, 0};
      d->searching = false;
      // While tracking, the survey for look-alikes, a piece a frame until it
      // has covered the frame (the session's floor of work per piece).
      if (!d->stage.surveyed()) {
        const std::uint64_t began = steady_nanoseconds();
        const std::uint64_t budget = std::uint64_t{frame.width} * frame.height * kSurveyUnitsPerPixel;
        if (const Status v = d->stage.survey(frame, e.pose, d->fine, budget); v != Status::kOk)
          throw app::Error(std::string("particle filter: survey failed: ") + status_name(v));
        detection_ledger.add(FramePhase::kSurvey, d->stage.last_work(), steady_nanoseconds() - began);
      }
    } else if (e.state == TrackState::kLost && !d->searching) {
      d->stage.reset();  // a lost period begins
      d->searching = true;
    }
  }
  p.ledger = p.core().ledger();
  for (std::uint32_t phase = 0; phase < kFramePhaseCount; ++phase)
    p.ledger.add(static_cast<FramePhase>(phase), detection_ledger.work[phase], detection_ledger.ticks[phase]);
  return e;
}

void run_particle_tracking(const TableView& table, app::FrameSource& frames, const Pose& init, const ParticleRunOptions& options,
                           const std::function<void(const app::TrackRow&)>& on_row) {
  std::unique_ptr<ParticleTracker> tracker;
  app::GrayImage frame;
  std::uint32_t width = 0, height = 0;
  for (std::uint32_t index = 0;; ++index) {
    const auto reading = std::chrono::steady_clock::now();
    if (!frames.next(frame)) break;
    if (!tracker) {
      width = frame.width, height = frame.height;
      tracker = std::make_unique<ParticleTracker>(table, width, height, options);
      tracker->start(init);
    } else if (frame.width != width || frame.height != height) {
      throw app::Error("frame " + std::to_string(index) + ": " + std::to_string(frame.width) + "x" + std::to_string(frame.height) +
                       ", the sequence began at " + std::to_string(width) + "x" + std::to_string(height));
    }
    const auto start = std::chrono::steady_clock::now();
    const ParticleEstimate e = tracker->step(frame);
    const auto stop = std::chrono::steady_clock::now();
    // The row from the session's form of the estimate (session_profile.hpp), as HostedSession reports it.
    const SessionResult result = particle_session_result(e, tracker->ledger());
    app::TrackRow row;
    row.frame = index;
    row.step = result.step;
    row.confidence = result.confidence;
    row.micros = std::chrono::duration<double, std::micro>(stop - start).count();
    row.io_micros = std::chrono::duration<double, std::micro>(start - reading).count();
    row.has_ledger = true;
    row.ledger = result.ledger;
    on_row(row);
  }
}

}  // namespace gabarit::app
