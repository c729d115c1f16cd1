// The particle filter's image loading and measures (particle_filter.hpp),
// each a policy type ParticleFilter takes as a template parameter:
//
//  - EdgeMapLoader: the frame's features (the table's detector: Canny,
//    gradient rows or binary) over the particles' window, as one bit per
//    pixel. It detects in strips of rows, as many as its feature scratch
//    holds, so an MCU bounds its RAM at one bit per window pixel plus one
//    strip's features.
//  - EdgeCorrelationMeasure (thesis 3.4.3): the fraction of the model's
//    feature points (the table's model points of the particle's depth,
//    every stride-th) that land on an edge pixel, or within `tolerance`
//    pixels of one, when placed at the particle's pose:
//      score(P) = |{m : edge near round((x, y) + R(theta) m)}| / |M|.
//    Cost per particle: |M| / stride point transforms and bit tests.
//  - StencilVoteMeasure: the stencil vote reused. Once per frame the table's
//    ROI is voted at the prediction (prepare_frame and the voter, as
//    track_step); a particle's score is then the normalised vote of the cell
//    that contains its motion from the prediction (its stencil's share of
//    features), 0 outside the table's range. Cost per particle: one cell
//    lookup; per frame: one vote.
//  - IntensityCorrelationMeasure: the session's verified score
//    (verification.hpp) as the likelihood: the correlation r of the focus
//    stack's image of the particle's depth with the frame at its pose (over
//    the object's outline, as correlation_at compares), on a sparse, fixed
//    subset of the model's samples: every step-th pixel, the step chosen
//    once so that about `samples` fall on the object and its ring. The
//    weight is max(r, 0). The outline's ring is compared or left out for
//    every particle of a frame as it is at the prediction (OutlineRing), so
//    that all are scored over the same samples. It reads the frame itself
//    (no loader). Cost per particle: about `samples` bilinear samples (the
//    list is made once, so the surround's pixels cost nothing).
//  - StencilVoteProposer: vote-guided proposals (ParticleFilter::
//    propose_with): the table voted at the prediction as track_step votes
//    it, and its best cells as the places to draw particles around.
// No heap: the bitmap, the features and the counters come from the caller.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "gabarit/depth_by_intensity.hpp"
#include "gabarit/particle_filter.hpp"
#include "gabarit/table_view.hpp"
#include "gabarit/tracker.hpp"
#include "gabarit/voter.hpp"

namespace gabarit {

// Words of the edge bitmap for a window of w x h pixels.
constexpr std::size_t edge_map_words(std::uint32_t width, std::uint32_t height) noexcept {
  return std::size_t{height} * ((std::size_t{width} + 63) / 64);
}

// The loader's feature scratch for windows up to `width` wide: strips of 16
// rows (any size of at least one row gives the same map; more rows, fewer
// detector calls).
constexpr std::size_t edge_map_features(std::uint32_t width) noexcept { return std::size_t{width} * 16; }

// One bit per pixel of an image window: set where the detector found a feature.
struct EdgeMap {
  ImageWindow window;
  std::span<const std::uint64_t> bits;
  std::uint32_t words_per_row = 0;
  std::uint32_t features = 0;
  std::uint32_t dropped = 0;  // features beyond the loader's strip scratch (a strip of one row overflowed)

  // Precondition: none (outside the window is false).
  bool at(std::int32_t x, std::int32_t y) const noexcept {
    const std::int32_t c = x - window.x0, r = y - window.y0;
    if (c < 0 || r < 0 || c >= window.width || r >= window.height) return false;
    const std::uint64_t word = bits[static_cast<std::size_t>(r) * words_per_row + static_cast<std::uint32_t>(c) / 64];
    return ((word >> (static_cast<std::uint32_t>(c) & 63u)) & 1u) != 0;
  }
  // A feature in the (2 t + 1)^2 square around (x, y).
  bool near(std::int32_t x, std::int32_t y, std::uint32_t t) const noexcept;
};

class EdgeMapLoader {
 public:
  // bits: edge_map_words of the largest window loaded (load clips larger
  // windows to what the bitmap holds, keeping the window's centre);
  // features: at least the widest window's width (one strip of one row).
  EdgeMapLoader(const Detector& detector, std::span<std::uint64_t> bits, std::span<RoiPoint> features,
                std::uint16_t max_width, std::uint16_t max_height) noexcept
      : detector_(detector), bits_(bits), features_(features), max_width_(max_width), max_height_(max_height) {}
  // Errors: kInvalidArgument for an invalid image or detector threshold,
  // kBufferTooSmall when bits or features are short of the sizes above.
  [[nodiscard]] Status load(const ImageView& image, const ImageWindow& window) noexcept;
  const EdgeMap& map() const noexcept { return map_; }

 private:
  Detector detector_;
  std::span<std::uint64_t> bits_;
  std::span<RoiPoint> features_;
  std::uint16_t max_width_, max_height_;
  EdgeMap map_;
};

class EdgeCorrelationMeasure {
 public:
  // The model points come from `table` (which must outlive the measure);
  // stride >= 1, tolerance 0..3 pixels.
  EdgeCorrelationMeasure(const TableView& table, const EdgeMapLoader& edges, std::uint32_t stride,
                         std::uint32_t tolerance) noexcept;
  [[nodiscard]] Status prepare(const ImageView&, const Pose&) noexcept { return Status::kOk; }
  void weigh(std::span<Particle> particles) noexcept;
  float score(const Pose& pose) noexcept;
  std::uint32_t reach_px() const noexcept;

 private:
  const TableView& table_;
  const EdgeMapLoader& edges_;
  std::uint32_t stride_;
  std::uint32_t tolerance_;
  std::uint32_t reach_ = 0;
};

class StencilVoteMeasure {
 public:
  // scratch: as track_step's (tracker.hpp). The table must outlive the measure.
  StencilVoteMeasure(const TableView& table, const Detector& detector, TrackerScratch scratch) noexcept
      : table_(table), detector_(detector), scratch_(scratch) {}
  // Votes the ROI at `predicted`. Errors: track_step's.
  [[nodiscard]] Status prepare(const ImageView& image, const Pose& predicted) noexcept;
  void weigh(std::span<Particle> particles) noexcept;
  float score(const Pose& pose) noexcept;
  std::uint32_t reach_px() const noexcept { return 0; }
  // The cell whose motion from this frame's prediction contains `pose`, or kNoCell.
  std::uint32_t cell_of(const Pose& pose) const noexcept;
  const PreparedFrame& frame() const noexcept { return frame_; }
  std::uint64_t votes() const noexcept { return tally_.votes; }

 private:
  const TableView& table_;
  Detector detector_;
  TrackerScratch scratch_;
  PreparedFrame frame_;
  VoteTally tally_;
  Pose predicted_;
  SinCos rotation_;
  bool prepared_ = false;
};

class StencilVoteProposer {
 public:
  // scratch: as track_step's (tracker.hpp), not shared with another voter
  // of the same frame. count: the best cells proposed, 1..kMaxParticleProposals.
  // The table must outlive the proposer.
  StencilVoteProposer(const TableView& table, const Detector& detector, TrackerScratch scratch, std::uint32_t count = 4) noexcept;
  // The best `count` cells with any votes, each as the pose its motion from
  // `predicted` gives; drawn around with one cell's spacing as sigma (at
  // least 0.5 px and 0.25 deg); the region is the table's range at every
  // depth. Errors: track_step's.
  [[nodiscard]] Status propose(const ImageView& image, const Pose& predicted, ParticleProposals& out) noexcept;
  // The last proposal's vote in a frame ledger: its work (the features'
  // and the counter increments, as the session counts them) under kVote,
  // and the pixels scanned, features and votes.
  void account(FrameLedger& ledger) const noexcept;
  std::uint64_t votes() const noexcept { return tally_.votes; }

 private:
  const TableView& table_;
  Detector detector_;
  TrackerScratch scratch_;
  std::uint32_t count_;
  PreparedFrame frame_;
  VoteTally tally_;
};

// The sparse subset's default size: about 256 samples on the object and its
// ring (docs/particle-filter.md, "The measures"), and its largest.
inline constexpr std::uint32_t kIntensityMeasureSamples = 256;
inline constexpr std::uint32_t kMaxIntensityMeasureSamples = 1024;
// The weights' power (ParticleFilterOptions::sharpness) with this measure:
// a correlation falls off more slowly around the true pose than the edge
// measure's fraction, so the default 8 left the cloud wide and its mean
// off the tip. On the pipette scenes' tuning half (bench --pipette, tip
// within 6 px): 8: 30.9%, 12: 35.4%, 16: 51.4%, 24: 47.2%, 32: 40.9%.
inline constexpr std::uint32_t kIntensitySharpness = 16;

class IntensityCorrelationMeasure {
 public:
  // `stack` (its images must outlive the measure) is the table's focus
  // stack. samples 16..kMaxIntensityMeasureSamples: the model's pixels every
  // step-th row and column (step at least the stack's own) that lie on the
  // object or its ring, step the smallest that keeps them within `samples`,
  // listed once here. 0: every sample at the stack's own step, exactly
  // correlation_at (the session's verified score; its cost grows with the
  // model's area, not the list's).
  IntensityCorrelationMeasure(const FocusStack& stack, std::uint32_t samples) noexcept { reset(stack, samples); }
  // A measure of nothing until reset (scores 0): static storage a firmware
  // fills once it knows its table, without a temporary of the list's size.
  // Every byte zero, so such storage is .bss rather than an initialised
  // image in flash.
  constexpr IntensityCorrelationMeasure() noexcept : stack_{{}, 0.0f, 0.0f, 0}, ring_{} {}
  // As the constructor, in place.
  void reset(const FocusStack& stack, std::uint32_t samples) noexcept;
  // Keeps the frame (it must outlive the frame's weighing) and decides the
  // ring at the prediction. kInvalidArgument for an invalid frame or stack.
  [[nodiscard]] Status prepare(const ImageView& image, const Pose& predicted) noexcept;
  void weigh(std::span<Particle> particles) noexcept;
  // 0 outside pose_in_range, at a depth the stack lacks, or where fewer
  // than 16 samples fall inside the frame.
  float score(const Pose& pose) noexcept;
  std::uint32_t reach_px() const noexcept { return 0; }
  std::uint32_t step() const noexcept { return stack_.step; }
  // The listed samples (0 for every sample), and how many lie on the object.
  std::uint32_t samples() const noexcept { return count_; }

 private:
  struct Sample {
    std::uint16_t u = 0, v = 0;  // model pixel
    bool object = false;         // on the object (else on its ring)
    // Its column and row of the sampling grid within the list's bounding
    // box ((u - box u min) / step, likewise v), when the box spans at most
    // kGridLines of each.
    std::uint8_t column = 0, row = 0;
    // With the grid: at the first sample of a run (the samples after it in
    // the list on the same grid row, at the next columns, in the same part),
    // the run's length (1..255); 0 within a run. Runs tile each part.
    std::uint8_t run = 0;
  };
  static constexpr std::uint32_t kGridLines = 128;
  // The correlation over the list: false where fewer than 16 samples fall
  // in the frame or a side is flat; `ring_compared` as correlation_at's.
  bool listed_correlation(const Pose& pose, OutlineRing ring, float& signed_r2, bool& ring_compared) const noexcept;
  bool correlate(const Pose& pose, OutlineRing ring, float& signed_r2, bool& ring_compared) const noexcept;
  FocusStack stack_;
  ImageView frame_{};
  OutlineRing ring_ = OutlineRing::kWhereItAgrees;
  std::uint8_t surround_ = 0;
  std::uint32_t count_ = 0;
  std::uint32_t object_count_ = 0;  // list_[0, object_count_) on the object, the rest on its ring
  Sample list_[kMaxIntensityMeasureSamples];
  // The list's bounding box (u min, v min, u max, v max), and the model's
  // sums of each part (object, ring) at each of the first kSummedDepths
  // depths: a particle whose every sample lands in the frame needs only the
  // frame's sums.
  static constexpr std::size_t kSummedDepths = 16;
  struct ModelSums {
    std::uint64_t a = 0, aa = 0;
  };
  std::uint16_t sample_box_[4] = {0, 0, 0, 0};
  std::uint32_t grid_columns_ = 0, grid_rows_ = 0;  // 0: the box spans more than kGridLines
  ModelSums model_sums_[kSummedDepths][2] = {};
};

// The filter gabarit track --tracker particle runs on a table with model
// images: the intensity measure on its sparse subset, the same measure on
// every sample as the finer one, no frame loader, vote proposals.
using IntensityParticleFilter = ParticleFilter<IntensityCorrelationMeasure, IntensityCorrelationMeasure, NoFrameLoader,
                                               DefaultPropagation, KinematicCompensation, ModeAnalysis, StencilVoteProposer>;

}  // namespace gabarit
