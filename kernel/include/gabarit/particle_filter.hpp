// The thesis's second tracker (chapter 3): a particle filter (CONDENSATION)
// over the same 4-DOF pose as the stencil tracker, with the chapter's
// improvements against clutter and occlusion, each switchable.
//
// One frame (ParticleFilter::step):
//   1. picking and propagation (the Propagation policy): particles are picked
//      in proportion to their weights (systematic resampling), moved by the
//      estimate's velocity and diffused by Gaussian noise; a fraction may be
//      re-drawn around a recovered pose instead (partial re-initialisation);
//   2. image loading (Loader): once per frame, what the measure reads
//      (an edge map of the particles' window);
//   3. observation (Measure): each particle's weight, the likelihood
//      of the frame at its pose;
//   4. compensation (Compensation): weights re-weighted by kinematics
//      (over-weighting near the predicted pose, in proportion to confidence);
//   5. result analysis (Analysis): particles sorted by weight and
//      clustered into modes; the few heaviest modes disambiguated by a finer
//      measure; the output mode chosen by mode filtering (within an adaptive
//      distance of the prediction); the estimate is that mode's weighted mean.
// Each stage is a template parameter of ParticleFilter with a default below;
// a firmware engineer swaps one by naming another type that has the same
// member functions (the requirements are listed at each default). Templates,
// not virtual calls: every call is direct, so the firmware's static stack
// analysis (platform/cortex-m/firmware_report.py) follows all of them.
//
// Improvements and the thesis sections they come from (each an option):
//   modes (3.5.3): sorted by weight (LSD radix sort, O(n)), then one pass
//     assigns each particle to the first of at most kMaxParticleModes modes
//     whose seed (its heaviest particle) is within the mode radius
//     ((dx^2 + dy^2) / r_px^2 + dtheta^2 / r_deg^2 <= 1, same depth), or
//     else seeds a mode of its own: O(n kMaxParticleModes) = O(n); or, with
//     ModeClustering::kRunningMean, within the radius of a mode's running
//     mean, only heavy enough particles starting modes;
//   disambiguation (3.5.4): the heaviest disambiguate_modes modes scored
//     again by the finer measure; the best of those is the best mode;
//   narrowing (3.6.1): the diffusion's sigma scales from 1 (no confidence)
//     down to narrow_min (full confidence);
//   kinematic over-weighting (3.6.2): w *= 1 + gain c exp(-d^2/2), d the
//     particle's normalised distance to the predicted pose, c the last
//     frame's confidence in [0, 1];
//   partial re-initialisation (3.6.3): each frame after an unconfident one
//     draws reinit_fraction of the particles around the last confident
//     estimate (or around a pose the caller recovered elsewhere,
//     reinitialise_around), so a filter led astray can fall back;
//   mode filtering (3.6.4): the output is the best mode within an adaptive
//     distance of the prediction (base + |vx| + |vy|, growing each
//     unconfident frame); a far mode is taken only after mode_filter_patience frames;
//   vote-guided proposals (issue 31; importance sampling as ICONDENSATION
//     does it): with a Proposer (propose_with), proposal_fraction of the
//     cloud is drawn around the places the proposer found this frame (the
//     stencil vote's best cells) and each such particle's weight is
//     multiplied by prior(x) / proposal(x), so the cloud still estimates the
//     motion model's posterior: a proposal where the motion model does not
//     expect the object counts for little while the filter is confident,
//     and as much as its likelihood once it is lost (the prior then a
//     uniform over the proposer's region).
// With every option off the filter is plain CONDENSATION: resample, diffuse,
// weigh, report the weighted mean.
//
// Determinism: a SplitMix64 generator seeded by the caller, Gaussian noise
// as a sum of four uniforms (Irwin-Hall, only + and *), the kernel's own
// sine and cosine (deterministic_math.hpp) and -ffp-contract=off: the same
// seed and frames give the same bits on every target.
// No heap: the particles and the sort's indices come from the caller
// (ParticleScratch, sized by particle_scratch_*).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "gabarit/frame_ledger.hpp"
#include "gabarit/image_view.hpp"
#include "gabarit/motion_filter.hpp"
#include "gabarit/pose.hpp"
#include "gabarit/status.hpp"
#include "gabarit/tracker.hpp"

namespace gabarit {

struct Particle {
  Pose pose;
  float weight = 0.0f;
};

// SplitMix64 (Steele, Lea and Flood 2014): 64 bits of state, the same
// sequence on every target.
class ParticleRng {
 public:
  explicit ParticleRng(std::uint64_t seed = 0) noexcept : state_(seed) {}
  std::uint64_t next() noexcept {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // Uniform in [0, 1): the top 24 bits.
  float uniform() noexcept { return static_cast<float>(next() >> 40) * (1.0f / 16777216.0f); }
  // Approximately standard normal (bounded by +-3.46): the sum of four
  // uniforms, centred and scaled to unit variance.
  float normal() noexcept {
    const float s = uniform() + uniform() + uniform() + uniform();
    return (s - 2.0f) * 1.7320508f;
  }

 private:
  std::uint64_t state_;
};

inline constexpr std::uint32_t kMaxParticleModes = 16;

// How the sorted particles are grouped into modes (3.5.3); both one pass in
// order of weight, O(n * modes):
//   kSeed: a particle joins the first mode whose seed (its heaviest
//     particle) is within the mode radius, else seeds a mode of its own;
//   kRunningMean: as the thesis's eq. 3.4-3.5 are read in issue 31: a
//     particle joins the first mode whose running weighted mean is within the
//     radius, and that mean moves to take it in; a particle that joins none
//     starts a mode only if it is heavy enough (mode_seed_ratio), else it
//     counts in no mode.
enum class ModeClustering : std::uint8_t { kSeed, kRunningMean };
inline constexpr std::uint32_t kMaxParticles = 1u << 20;

// Caller-owned memory for n particles.
constexpr std::size_t particle_scratch_particles(std::uint32_t n) noexcept { return n; }      // each of cloud and next
constexpr std::size_t particle_scratch_order(std::uint32_t n) noexcept { return 2 * std::size_t{n}; }
struct ParticleScratch {
  std::span<Particle> cloud;        // n particles (n = its size, 1..kMaxParticles)
  std::span<Particle> next;         // >= n
  std::span<std::uint32_t> order;   // >= 2n: the radix sort's indices
};

struct ParticleMode {
  Pose pose;                // the weighted mean of its particles (its seed's depth)
  float weight = 0.0f;      // its share of the total weight
  float score = 0.0f;       // the finer measure's score, with disambiguation (else the measure's)
  std::uint32_t particles = 0;
};

struct ParticleFilterOptions {
  // Propagation (3.3): diffusion per frame, before narrowing.
  float sigma_px = 2.0f;
  float sigma_deg = 1.0f;
  float depth_change = 0.1f;        // probability of moving to a neighbouring depth
  bool constant_velocity = true;    // move particles by the estimate's velocity
  // The measure's likelihood is its score raised to this power (1..64):
  // sharper weights concentrate the cloud faster.
  std::uint32_t sharpness = 8;
  // 3.5.3: modes.
  bool modes = true;
  ModeClustering mode_clustering = ModeClustering::kSeed;
  float mode_radius_px = 4.0f;
  float mode_radius_deg = 3.0f;
  std::uint32_t max_modes = 8;      // 1..kMaxParticleModes
  // kRunningMean: a particle that joins no mode starts one only if its
  // weight is at least this share (0..1) of the heaviest particle's.
  float mode_seed_ratio = 0.05f;
  // 3.5.4: disambiguation of the heaviest modes by the finer measure.
  bool disambiguate = true;
  std::uint32_t disambiguate_modes = 3;
  // 3.6.1: narrowing the spread with confidence.
  bool narrow_spread = true;
  float narrow_min = 0.4f;
  // 3.6.2: kinematic over-weighting.
  bool kinematic_weighting = true;
  float kinematic_gain = 1.0f;
  float kinematic_px = 2.0f;        // distance scales of the over-weighting
  float kinematic_deg = 1.0f;
  // 3.6.3: partial re-initialisation.
  bool partial_reinit = true;
  float reinit_fraction = 0.1f;
  float reinit_px = 3.0f;
  float reinit_deg = 1.5f;
  // 3.6.4: mode filtering with an adaptive distance.
  bool mode_filter = true;
  float mode_filter_px = 6.0f;      // base distance
  float mode_filter_growth_px = 3.0f;  // added per unconfident frame
  std::uint32_t mode_filter_patience = 5;
  // Vote-guided proposals: the share of the cloud drawn each frame around
  // the proposer's places (0: none; no effect without a proposer), and
  // whether their weights are corrected by prior / proposal. The prior is
  // the last frame's modes moved by the velocity, each a Gaussian as wide as
  // the diffusion plus half the mode radius, mixed with a uniform over the
  // proposer's region in the share max(proposal_floor, 1 - confidence): a
  // jump is unlikely while confident and anywhere is as likely once lost.
  // Chosen on the suite's tuning half (docs/particle-filter.md, "Vote-guided
  // proposals"): of fractions 0.05-0.7 and floors 0.05-0.5, half the cloud
  // and a floor of 0.2 placed the object best and re-acquired it soonest.
  float proposal_fraction = 0.5f;
  bool proposal_correction = true;
  float proposal_floor = 0.2f;
  // Confidence: the chosen mode's score over the reference (the first
  // frame's), high at >= high_ratio, lost below lost_ratio.
  float high_ratio = 0.7f;
  float lost_ratio = 0.35f;
  // While lost, the diffusion grows by this factor per frame, up to lost_spread_max.
  float lost_spread_growth = 1.3f;
  float lost_spread_max = 4.0f;
};
bool valid(const ParticleFilterOptions& options) noexcept;

// Plain CONDENSATION: every improvement off.
ParticleFilterOptions plain_condensation() noexcept;

// 5. Image loading: once per frame, before any particle is weighed, with the
// window the particles (and the measures' reach) cover, clipped to the image.
//   Status load(const ImageView& image, const ImageWindow& window) noexcept;
// NoFrameLoader loads nothing (a measure that reads the image itself).
struct NoFrameLoader {
  [[nodiscard]] Status load(const ImageView&, const ImageWindow&) noexcept { return Status::kOk; }
};

// 3. Observation (particle_measures.hpp has two). A measure has
//   Status prepare(const ImageView& image, const Pose& predicted) noexcept;
//     once per frame after the loader, at the predicted pose;
//   void weigh(std::span<Particle> particles) noexcept;
//     each particle's score in [0, 1] written to its weight;
//   float score(const Pose& pose) noexcept;   one pose's score;
//   std::uint32_t reach_px() const noexcept;
//     how far (pixels) beyond a pose it reads the frame: the loader's window
//     covers the particles plus this.

// 6. Proposals (optional; ParticleFilter::propose_with): once per frame,
// after propagation and before the measure,
//   Status propose(const ImageView& image, const Pose& predicted, ParticleProposals& out) noexcept;
// the places worth drawing particles around this frame, found some other
// way than by the cloud (StencilVoteProposer: the stencil vote's best cells
// at the prediction). NoProposer proposes nothing.
inline constexpr std::uint32_t kMaxParticleProposals = 8;
struct ParticleProposals {
  Pose poses[kMaxParticleProposals];
  std::uint32_t count = 0;
  float sigma_px = 1.0f, sigma_deg = 1.0f;  // the Gaussian drawn around each (about its cell)
  // The volume the proposer searched, in px^2 x deg x depths: the prior's
  // uniform part is 1 / region_volume.
  float region_volume = 1.0f;
};
struct NoProposer {
  [[nodiscard]] Status propose(const ImageView&, const Pose&, ParticleProposals& out) noexcept {
    out.count = 0;
    return Status::kOk;
  }
};

// What the policies know of the filter's state.
struct ParticleContext {
  Pose estimate;            // last frame's estimate
  Pose predicted;           // this frame's prediction (estimate + velocity)
  float vx = 0.0f, vy = 0.0f, vtheta = 0.0f;  // per frame
  float confidence = 0.0f;  // last frame's, in [0, 1]
  float spread = 1.0f;      // diffusion scale this frame (narrowing, growth while lost)
  bool lost = false;
  Pose reinit_centre;       // where partial re-initialisation draws
  float reinit_fraction = 0.0f;  // this frame's
  std::uint32_t unconfident_frames = 0;  // frames since the last confident one
  std::uint32_t held_frames = 0;         // consecutive frames mode filtering held the prediction
  std::uint16_t depth_count = 1;
  const ParticleFilterOptions* options = nullptr;
};

// 1. Picking and propagation: `next` (the same size) from the weighted `cloud`.
//   void propagate(std::span<const Particle> cloud, std::span<Particle> next,
//                  const ParticleContext& context, ParticleRng& rng) noexcept;
class DefaultPropagation {
 public:
  void propagate(std::span<const Particle> cloud, std::span<Particle> next, const ParticleContext& context,
                 ParticleRng& rng) noexcept;
};

// 4. Compensation, after the measure and before analysis:
//   void compensate(std::span<Particle> particles, const ParticleContext& context) noexcept;
class KinematicCompensation {
 public:
  void compensate(std::span<Particle> particles, const ParticleContext& context) noexcept;
};

// 2. Result analysis, in two halves around the finer measure's scores:
//   std::uint32_t cluster(std::span<const Particle> particles, std::span<std::uint32_t> order,
//                         const ParticleContext& context, std::span<ParticleMode> modes) noexcept;
//     the modes, heaviest first (at most modes.size()), and their count;
//   void choose(std::span<const ParticleMode> modes, std::uint32_t scored,
//               const ParticleContext& context, ParticleAnalysisResult& out) noexcept;
//     the best and the output mode, the first `scored` modes carrying the
//     finer measure's score.
struct ParticleAnalysisResult {
  std::uint32_t modes = 0;
  std::uint32_t chosen = 0;
  std::uint32_t best = 0;         // the best mode (before mode filtering)
  bool held = false;              // mode filtering kept the prediction: no mode near enough
};
class ModeAnalysis {
 public:
  std::uint32_t cluster(std::span<const Particle> particles, std::span<std::uint32_t> order, const ParticleContext& context,
                        std::span<ParticleMode> modes) noexcept;
  void choose(std::span<const ParticleMode> modes, std::uint32_t scored, const ParticleContext& context,
              ParticleAnalysisResult& out) noexcept;
};

// Sorts indices 0..n-1 of `particles` by weight, heaviest first, ties by
// index (stable LSD radix sort on the weights' bits; weights >= 0).
// Precondition: order.size() >= 2n; the result is order[0, n).
void sort_by_weight(std::span<const Particle> particles, std::span<std::uint32_t> order) noexcept;

struct ParticleEstimate {
  Pose pose;
  float score = 0.0f;         // the chosen mode's score
  float confidence = 0.0f;    // score / reference over high_ratio, clamped to [0, 1]
  TrackState state = TrackState::kLost;
  std::uint32_t modes = 0;
  std::uint32_t mode_particles = 0;
  float mode_weight = 0.0f;
  bool held = false;          // mode filtering held the prediction
  bool reinitialised = false; // part of the cloud was re-drawn this frame
  std::uint32_t proposed = 0; // particles drawn around the proposer's places this frame
};

// The part of the filter that does not depend on its policies' types.
class ParticleFilterCore {
 public:
  // Errors: kInvalidArgument for bad options, a pose outside pose_in_range,
  // depth_count 0 or initial.depth >= depth_count, a cloud that is empty or
  // over kMaxParticles; kBufferTooSmall for `next` or `order` short of the
  // sizes above.
  [[nodiscard]] Status start(const ParticleFilterOptions& options, const Pose& initial, std::uint16_t depth_count,
                             std::uint64_t seed, ParticleScratch scratch) noexcept;
  // Partial re-initialisation around a pose found elsewhere (the stencil
  // tracker's, a detector's): the next step draws `fraction` (0..1) of the
  // cloud around it. Ignored for a pose outside pose_in_range.
  void reinitialise_around(const Pose& pose, float fraction) noexcept;
  // Spreads the cloud uniformly over a region of the image (x0..x1, y0..y1,
  // theta0..theta1, every depth), for a search from nothing. With fraction 1
  // the whole cloud, which the next step measures as it is; with less, the
  // next step propagates the cloud as usual and then re-draws that fraction
  // of it over the region (a search that keeps looking elsewhere). Errors:
  // kInvalidArgument before start(), for a reversed or non-finite region or
  // a fraction outside (0, 1].
  [[nodiscard]] Status scatter(float x0, float x1, float y0, float y1, float theta0_deg, float theta1_deg,
                               float fraction = 1.0f) noexcept;

  // The frame-cost ledger (frame_ledger.hpp) of the last step, timed with
  // `clock` (null: not timed): the proposer under kVote (its feature
  // detection and its vote; work: its features' and counter increments),
  // the loader under kFeatures, the measure and the finer measure under
  // kVerify (correlations: the particles and modes they scored), the rest
  // (propagation, weights, clustering, the estimate) under kOther.
  void use_clock(TickSource clock) noexcept { clock_ = clock; }
  const FrameLedger& ledger() const noexcept { return ledger_; }
  const ParticleContext& context() const noexcept { return context_; }
  std::span<const Particle> particles() const noexcept { return cloud_; }
  std::span<const ParticleMode> modes() const noexcept { return {modes_, mode_count_}; }

 protected:
  ParticleFilterCore() = default;
  ~ParticleFilterCore() = default;
  // The steps around the policies' calls (ParticleFilter::step).
  [[nodiscard]] Status begin_step(const ImageView& image, ParticleEstimate& out) noexcept;
  void after_propagation(ParticleEstimate& out) noexcept;  // next becomes the cloud; a pending partial scatter
  ImageWindow loader_window(const ImageView& image, std::uint32_t reach) const noexcept;
  void sharpen() noexcept;  // weights: scores to the power `sharpness`
  // Vote-guided proposals: draws proposal_fraction of the cloud around
  // `proposals_` (the particles between those of a partial scatter), and
  // after sharpening multiplies their weights by prior / proposal.
  void draw_proposals(ParticleEstimate& out) noexcept;
  void correct_proposals() noexcept;
  void finish_step(const ParticleAnalysisResult& analysis, float score, ParticleEstimate& out) noexcept;

  ParticleFilterOptions options_;
  ParticleContext context_;
  ParticleRng rng_;
  std::span<Particle> cloud_, next_;
  std::span<std::uint32_t> order_;
  ParticleMode modes_[kMaxParticleModes];
  std::uint32_t mode_count_ = 0;
  ParticleProposals proposals_;
  std::uint32_t proposed_ = 0;      // this frame's proposed particles (0: none)
  TickSource clock_ = nullptr;
  FrameLedger ledger_;
  bool started_ = false;
  bool scattered_ = false;          // the cloud was scattered: the next step skips propagation

 private:
  void draw_uniform(Particle& p, const float* region) noexcept;
  std::size_t proposal_index(std::uint32_t k) const noexcept;
  float prior_density(const Pose& pose) const noexcept;
  float proposal_density(const Pose& pose) const noexcept;

  float reference_ = 0.0f;          // the score at the first frame (0: not yet)
  std::uint32_t unconfident_ = 0;   // frames since the last confident one
  std::uint32_t held_ = 0;          // consecutive frames mode filtering held
  Pose last_confident_;
  Pose external_reinit_;
  float external_fraction_ = 0.0f;
  float scatter_[6] = {};           // a pending partial scatter's region
  float scatter_fraction_ = 0.0f;   // and its share of the cloud (0: none)
};

// The filter over a measure type, an optional finer measure of type Finer
// (disambiguation and confidence; null: the measure's own score), an
// optional loader, and the three other policies. The measure, finer measure
// and loader must outlive the filter.
template <class Measure, class Finer = Measure, class Loader = NoFrameLoader, class Propagation = DefaultPropagation,
          class Compensation = KinematicCompensation, class Analysis = ModeAnalysis, class Proposer = NoProposer>
class ParticleFilter : public ParticleFilterCore {
 public:
  explicit ParticleFilter(Measure& measure, Finer* finer = nullptr, Loader* loader = nullptr, Propagation propagation = {},
                          Compensation compensation = {}, Analysis analysis = {}) noexcept
      : measure_(measure), finer_(finer), loader_(loader), propagation_(propagation), compensation_(compensation),
        analysis_(analysis) {}
  // Vote-guided proposals from `proposer` (which must outlive the filter;
  // null: none) each step, proposal_fraction of the cloud.
  void propose_with(Proposer* proposer) noexcept { proposer_ = proposer; }

  // One frame. Errors: kInvalidArgument for an invalid image or before
  // start(); the loader's and the measures'.
  [[nodiscard]] Status step(const ImageView& image, ParticleEstimate& out) noexcept {
    ledger_ = {};
    std::uint64_t mark = read_ticks(clock_);
    GABARIT_TRY(begin_step(image, out));
    if (!scattered_) propagation_.propagate(cloud_, next_, context_, rng_);
    after_propagation(out);
    proposals_.count = 0;
    proposed_ = 0;
    mark = charge(FramePhase::kOther, mark);
    if (proposer_ != nullptr && options_.proposal_fraction > 0.0f) {
      GABARIT_TRY(proposer_->propose(image, context_.predicted, proposals_));
      if constexpr (requires(const Proposer& p, FrameLedger& l) { p.account(l); }) proposer_->account(ledger_);
      draw_proposals(out);
    }
    mark = charge(FramePhase::kVote, mark);
    if (loader_ != nullptr) {
      std::uint32_t reach = measure_.reach_px();
      if (finer_ != nullptr && finer_->reach_px() > reach) reach = finer_->reach_px();
      GABARIT_TRY(loader_->load(image, loader_window(image, reach)));
    }
    mark = charge(FramePhase::kFeatures, mark);
    GABARIT_TRY(measure_.prepare(image, context_.predicted));
    const bool finer_is_measure = static_cast<const void*>(finer_) == static_cast<const void*>(&measure_);
    if (finer_ != nullptr && !finer_is_measure) GABARIT_TRY(finer_->prepare(image, context_.predicted));
    measure_.weigh(cloud_);
    ledger_.correlations += static_cast<std::uint32_t>(cloud_.size());
    mark = charge(FramePhase::kVerify, mark);
    sharpen();
    correct_proposals();
    compensation_.compensate(cloud_, context_);
    mode_count_ = analysis_.cluster(cloud_, order_, context_, {modes_, kMaxParticleModes});
    mark = charge(FramePhase::kOther, mark);
    // Disambiguation: the finer measure scores the heaviest modes.
    std::uint32_t scored = 0;
    if (options_.disambiguate && finer_ != nullptr)
      scored = options_.disambiguate_modes < mode_count_ ? options_.disambiguate_modes : mode_count_;
    for (std::uint32_t m = 0; m < mode_count_; ++m) modes_[m].score = m < scored ? finer_->score(modes_[m].pose) : -1.0f;
    ledger_.correlations += scored;
    mark = charge(FramePhase::kVerify, mark);
    ParticleAnalysisResult analysis;
    analysis_.choose({modes_, mode_count_}, scored, context_, analysis);
    out.modes = mode_count_;
    if (mode_count_ > 0) {  // else a custom analysis that found none: nothing to report
      ParticleMode& chosen = modes_[analysis.chosen];
      if (chosen.score < 0.0f) {  // not among the modes scored above: one more score, charged as theirs
        mark = charge(FramePhase::kOther, mark);
        chosen.score = finer_ != nullptr ? finer_->score(chosen.pose) : measure_.score(chosen.pose);
        ++ledger_.correlations;
        mark = charge(FramePhase::kVerify, mark);
      }
      finish_step(analysis, chosen.score, out);
    }
    charge(FramePhase::kOther, mark);
    return Status::kOk;
  }

 private:
  Measure& measure_;
  Finer* finer_;
  Loader* loader_;
  Propagation propagation_;
  Compensation compensation_;
  Analysis analysis_;
  Proposer* proposer_ = nullptr;

  // Adds the ticks since `mark` to `phase`; returns the reading as the next mark.
  std::uint64_t charge(FramePhase phase, std::uint64_t mark) noexcept {
    const std::uint64_t now = read_ticks(clock_);
    ledger_.add(phase, 0, now - mark);
    return now;
  }
};

}  // namespace gabarit
