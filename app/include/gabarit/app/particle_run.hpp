// The kernel's particle filter (particle_filter.hpp) as a host program runs
// it: its buffers on the heap, the edge map over the whole frame, and the
// frame loop gabarit track --tracker particle and the bench share.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "gabarit/app/image_io.hpp"
#include "gabarit/app/pose_row.hpp"
#include "gabarit/app/scratch.hpp"
#include "gabarit/app/session_profile.hpp"
#include "gabarit/particle_filter.hpp"
#include "gabarit/particle_measures.hpp"
#include "gabarit/particle_recovery.hpp"
#include "gabarit/table_view.hpp"

namespace gabarit::app {

// ParticleMeasureKind and its name_of are the profile's (session_profile.hpp).
// The measure a table runs: kAuto resolved, the others as they are.
ParticleMeasureKind resolved_measure(ParticleMeasureKind kind, const TableView& table) noexcept;

struct ParticleRunOptions {
  std::uint32_t particles = 1000;
  std::uint64_t seed = 1;
  ParticleMeasureKind measure = ParticleMeasureKind::kAuto;
  ParticleFilterOptions filter;             // the chapter's improvements, each on by default
  std::optional<Detector> detector;         // overrides the table's detector
  std::uint32_t edge_stride = 2;            // the edge measure's model points: every n-th
  std::uint32_t edge_tolerance = 0;         // pixels (0 was better than 1 on the pipette scenes' tuning half)
  // The finer measure (edge correlation over every model point) for
  // disambiguation and confidence; it needs the edge map, which the stencil
  // measure alone does not (gabarit track turns it off with --measure stencil).
  bool finer = true;
  app::VoterChoice voter = app::VoterChoice::kAuto;  // the stencil measure's vote
  std::uint32_t intensity_samples = kIntensityMeasureSamples;  // the intensity measure's sparse subset
  // Vote-guided proposals (filter.proposal_fraction of the cloud, with the
  // intensity and edge measures): the stencil vote's best cells drawn
  // around each frame, 0..kMaxParticleProposals (0: none).
  std::uint32_t proposals = kDefaultParticleProposals;
  // Re-acquisition by detection (docs/particle-filter.md, "Re-acquisition by
  // detection"): where the table verifies (model images, a grayscale
  // detector), every kParticleDetectionInterval-th frame after a lost one the
  // model finder searches where the target can have got to (the session's
  // DetectionRecovery), and kParticleDetectionFraction of the cloud is drawn
  // around what it finds within reach; while tracking, the stage surveys the
  // frame for look-alikes. Off with kImproveDetection in the profile.
  bool detection = true;
};
// Chosen on the scene suite's tuning half (docs/particle-filter.md).
inline constexpr std::uint32_t kParticleDetectionInterval = 3;
inline constexpr float kParticleDetectionFraction = 0.3f;

// The profile's particle numbers (particles, seed, the edge measure's stride
// and tolerance, the improvements switched off) and its measure (the stencil
// measure without the finer one) over the defaults above.
ParticleRunOptions particle_run_options(const SessionProfile& profile);

// A particle filter with its buffers, for frames of at most max_width x max_height.
class ParticleTracker {
 public:
  ParticleTracker(const TableView& table, std::uint32_t max_width, std::uint32_t max_height, const ParticleRunOptions& options);
  ParticleTracker(const ParticleTracker&) = delete;
  ParticleTracker& operator=(const ParticleTracker&) = delete;
  ~ParticleTracker();
  // Throws app::Error with the kernel's status name on failure.
  void start(const Pose& initial);
  ParticleEstimate step(const app::GrayImage& frame) { return step(frame.view()); }
  ParticleEstimate step(const ImageView& frame);
  ParticleFilterCore& core();
  // The last step's frame-cost ledger: the filter's, and the detection
  // stage's search under kRecovery and survey under kSurvey.
  const FrameLedger& ledger() const;
  // Whether the detection stage runs (asked for, and the table verifies).
  bool detects() const;
  // The filter with the edge measure (particle_recovery.hpp runs it).
  // Throws app::Error with the stencil measure.
  EdgeParticleFilter& edge_filter();

 private:
  struct Parts;
  std::unique_ptr<Parts> parts_;
};

// Calls on_row for every frame: the estimate as step.pose, state and score
// (votes 0); micros is the filter's time for the frame.
void run_particle_tracking(const TableView& table, app::FrameSource& frames, const Pose& init, const ParticleRunOptions& options,
                           const std::function<void(const app::TrackRow&)>& on_row);

}  // namespace gabarit::app
