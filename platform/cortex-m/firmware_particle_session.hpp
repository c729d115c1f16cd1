// The firmware's particle tracker: the static twin of app::HostedSession
// with the profile's particle tracker (app/hosted_session.hpp, which runs
// app::ParticleTracker). Same profile, same kernel compositions, but every
// buffer is the caller's (static arrays in the HIL firmware). Like
// app::ParticleTracker it is built at the first frame, for that frame's
// size, and refuses a later frame of another size. It runs the measure the
// table resolves (auto: the intensity measure with model images, else the
// edge measure), the finer measure and the vote-guided proposals, as
// gabarit track --tracker particle does by default.
// Header-only and free of anything MCU-specific, so the host's tests build it
// and compare it with HostedSession frame by frame
// (tests/app/session_profile_test.cpp).
#pragma once

#include <cstdint>
#include <optional>
#include <span>

#include "gabarit/app/session_profile.hpp"
#include "gabarit/particle_measures.hpp"
#include "gabarit/particle_recovery.hpp"
#include "gabarit/table_view.hpp"

namespace gabarit::mcu {

// What the particle HIL firmware runs: gabarit track --tracker particle's defaults.
inline constexpr app::SessionProfile kFirmwareParticleProfile = [] {
  app::SessionProfile p;
  p.tracker = app::TrackerKind::kParticle;
  // No room for the finder beside the cloud and the frame slot: no
  // re-acquisition by detection (CAPS says so: no kModeRecoveryDetection).
  p.particle_improvements_off = app::kImproveDetection;
  return p;
}();

// The caller's memory: the cloud (particle_scratch_particles and
// particle_scratch_order of the profile's particles), the edge map of the
// largest frame (edge_map_words, edge_map_features of its width), the
// proposals' vote (track_step's scratch for the table), and the intensity
// measure's views (one per depth) and measures (2).
struct FirmwareParticleScratch {
  ParticleScratch particles;
  std::span<std::uint64_t> edge_bits;
  std::span<RoiPoint> edge_features;
  TrackerScratch proposer;
  std::span<ImageView> stack_views;
  std::span<IntensityCorrelationMeasure> intensity;
};

class FirmwareParticleSession {
 public:
  // `table` must outlive the session.
  FirmwareParticleSession(const TableView& table, FirmwareParticleScratch scratch) noexcept
      : table_(table),
        scratch_(scratch),
        measure_(app::resolved_measure(kFirmwareParticleProfile.particle_measure, table.has_model_images())),
        detector_(detector_of(table)) {}
  // The CAPS mode bits (app::mode_bits of the profile as it runs here: its measure resolved).
  std::uint32_t mode() const noexcept {
    app::SessionProfile p = kFirmwareParticleProfile;
    p.particle_measure = measure_;
    return app::mode_bits(p, false, false);
  }
  // False for a pose outside pose_in_range or a depth the table does not have.
  [[nodiscard]] bool start(const Pose& initial) noexcept {
    stop();
    if (!pose_in_range(initial) || initial.depth >= table_.depth_count()) return false;
    initial_ = initial;
    started_ = true;
    return true;
  }
  bool started() const noexcept { return started_; }
  // The proposals' vote scratch (track_step's for the table), when the
  // caller makes it per frame; it takes effect when the filter is built (at
  // the first frame after start()).
  void use_proposer_scratch(TrackerScratch scratch) noexcept { scratch_.proposer = scratch; }
  // Errors: kInvalidArgument before start() or for a frame of another size
  // than the first; kBufferTooSmall for a frame or cloud larger than the
  // scratch holds; the filter's.
  [[nodiscard]] Status step(const ImageView& image, SessionResult& out) noexcept {
    if (!started_) return Status::kInvalidArgument;
    if (!built_) {
      GABARIT_TRY(build(image.width, image.height));
    } else if (image.width != width_ || image.height != height_) {
      return Status::kInvalidArgument;
    }
    ParticleEstimate e;
    GABARIT_TRY(edge_filter_ ? edge_filter_->step(image, e) : intensity_filter_->step(image, e));
    out = app::particle_session_result(e, edge_filter_ ? edge_filter_->ledger() : intensity_filter_->ledger());
    return Status::kOk;
  }

 private:
  void stop() noexcept {
    edge_filter_.reset(), intensity_filter_.reset();
    edges_.reset(), fine_edges_.reset(), loader_.reset(), proposer_.reset();
    started_ = built_ = false;
  }

  // The compositions app::ParticleTracker makes for a frame of width x height.
  Status build(std::uint32_t width, std::uint32_t height) noexcept {
    const std::uint32_t n = kFirmwareParticleProfile.particles;
    const ParticleScratch& ps = scratch_.particles;
    if (ps.cloud.size() < particle_scratch_particles(n) || ps.next.size() < particle_scratch_particles(n) ||
        ps.order.size() < particle_scratch_order(n))
      return Status::kBufferTooSmall;
    ParticleFilterOptions options = app::particle_filter_options(kFirmwareParticleProfile.particle_improvements_off);
    options.mode_clustering = kFirmwareParticleProfile.particle_clustering;
    if (measure_ == app::ParticleMeasureKind::kEdges) {
      if (width > 65535 || height > 65535 || scratch_.edge_bits.size() < edge_map_words(width, height) ||
          scratch_.edge_features.size() < edge_map_features(width))
        return Status::kBufferTooSmall;
      loader_.emplace(detector_, scratch_.edge_bits.first(edge_map_words(width, height)),
                      scratch_.edge_features.first(edge_map_features(width)), static_cast<std::uint16_t>(width),
                      static_cast<std::uint16_t>(height));
      edges_.emplace(table_, *loader_, kFirmwareParticleProfile.edge_stride, kFirmwareParticleProfile.edge_tolerance);
      fine_edges_.emplace(table_, *loader_, 1, kFirmwareParticleProfile.edge_tolerance);
      edge_filter_.emplace(*edges_, &*fine_edges_, &*loader_);
    } else if (measure_ == app::ParticleMeasureKind::kIntensity) {
      const std::uint16_t depths = table_.depth_count();
      if (!table_.has_model_images() || scratch_.stack_views.size() < depths || scratch_.intensity.size() < 2)
        return Status::kBufferTooSmall;
      for (std::uint16_t d = 0; d < depths; ++d) scratch_.stack_views[d] = table_.model_image(d);
      stack_ = FocusStack{scratch_.stack_views.first(depths), table_.model_ref_x(), table_.model_ref_y(), 2};
      scratch_.intensity[0].reset(stack_, kIntensityMeasureSamples);
      scratch_.intensity[1].reset(stack_, 0);
      intensity_filter_.emplace(scratch_.intensity[0], &scratch_.intensity[1]);
      options.sharpness = kIntensitySharpness;
    } else {
      return Status::kInvalidArgument;  // the stencil measure is not built here
    }
    if (app::kDefaultParticleProposals > 0 && options.proposal_fraction > 0.0f) {
      proposer_.emplace(table_, detector_, scratch_.proposer, app::kDefaultParticleProposals);
      if (edge_filter_) edge_filter_->propose_with(&*proposer_);
      if (intensity_filter_) intensity_filter_->propose_with(&*proposer_);
    }
    ParticleFilterCore& core = edge_filter_ ? static_cast<ParticleFilterCore&>(*edge_filter_) : *intensity_filter_;
    GABARIT_TRY(core.start(options, initial_, table_.depth_count(), kFirmwareParticleProfile.seed,
                           {ps.cloud.first(n), ps.next.first(n), ps.order}));
    width_ = width, height_ = height;
    built_ = true;
    return Status::kOk;
  }

  const TableView& table_;
  FirmwareParticleScratch scratch_;
  app::ParticleMeasureKind measure_;
  Detector detector_;
  Pose initial_;
  bool started_ = false, built_ = false;
  std::uint32_t width_ = 0, height_ = 0;
  FocusStack stack_;
  std::optional<EdgeMapLoader> loader_;
  std::optional<EdgeCorrelationMeasure> edges_, fine_edges_;
  std::optional<StencilVoteProposer> proposer_;
  std::optional<EdgeParticleFilter> edge_filter_;
  std::optional<IntensityParticleFilter> intensity_filter_;
};

}  // namespace gabarit::mcu
