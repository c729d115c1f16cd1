// Re-acquisition by particle filter (thesis 3.8.1): the stage a
// TrackingSession runs while its target is lost, instead of the grid search
// (recovery_search.hpp), when it is given one (use_particle_recovery).
//
// Each lost frame: the filter's cloud (an EdgeParticleFilter) is spread over a search region (every
// depth): all of it on the first lost frame, rescatter of it on the next
// ones, so the search keeps looking while the rest of the cloud converges on
// the best edge correlation. The region is centred where the target would be
// had it kept its last confident velocity (the grid search's first centre),
// reach_px around it growing by growth_px per lost frame until it covers the
// frame, and the angle it would have turned to +- turn_deg (growing by
// growth_deg per frame up to 180). The filter steps (its own measure, e.g. edge correlation over
// the frame); its `candidates` heaviest modes are each voted by the fine
// table from their pose, and the best of those votes is voted once more from
// its own estimate: that vote is the stage's result, which the session
// accepts only at high confidence, exactly as the grid search's. A strong
// result draws half the next cloud around it (partial re-initialisation).
// A target that reappears anywhere is inside the region once it has grown
// over the frame.
//
// No heap: the filter (started by the caller, with its policies and
// scratch) and the fine table's scratch come from the caller.
#pragma once

#include <cstdint>

#include "gabarit/image_view.hpp"
#include "gabarit/particle_filter.hpp"
#include "gabarit/particle_measures.hpp"
#include "gabarit/recovery_search.hpp"
#include "gabarit/status.hpp"
#include "gabarit/table_view.hpp"
#include "gabarit/tracker.hpp"

namespace gabarit {

// The filter this stage runs: edge correlation, the finer edge correlation,
// the edge map; the particle tracker (gabarit track --tracker particle) may
// give it a vote proposer, which this stage does not.
using EdgeParticleFilter = ParticleFilter<EdgeCorrelationMeasure, EdgeCorrelationMeasure, EdgeMapLoader, DefaultPropagation,
                                          KinematicCompensation, ModeAnalysis, StencilVoteProposer>;

struct ParticleRecoveryOptions {
  float reach_px = 40.0f;         // the region's half-side on the first lost frame
  float growth_px = 10.0f;        // added per lost frame
  float turn_deg = 10.0f;         // the angles searched: the extrapolated one +- this
  float growth_deg = 1.0f;        // added per lost frame
  float rescatter = 0.3f;         // the share of the cloud re-drawn over the frame each later lost frame, (0, 1]
  std::uint32_t candidates = 3;   // modes voted by the fine table, 1..kMaxParticleModes
};
bool valid(const ParticleRecoveryOptions& options) noexcept;

class ParticleRecovery {
 public:
  // `fine` and `filter` must outlive the stage; the filter must have been
  // started (ParticleFilter::start; any pose, its depth count the table's).
  ParticleRecovery(const TableView& fine, const Detector& detector, EdgeParticleFilter& filter,
                   const ParticleRecoveryOptions& options = {}) noexcept
      : fine_(fine), detector_(detector), filter_(filter), options_(options) {}
  // Starts a lost period: the next run spreads the whole cloud.
  void reset() noexcept { frames_ = 0; }
  // One lost frame. Errors: kInvalidArgument for invalid options or an
  // unstarted filter; the filter's and the tracker's.
  [[nodiscard]] Status run(const ImageView& image, const LastSighting& last, TrackerScratch fine_scratch,
                           SearchResult& out) noexcept;
  std::uint32_t frames() const noexcept { return frames_; }

 private:
  const TableView& fine_;
  Detector detector_;
  EdgeParticleFilter& filter_;
  ParticleRecoveryOptions options_;
  std::uint32_t frames_ = 0;  // lost frames run in this period
};

}  // namespace gabarit
