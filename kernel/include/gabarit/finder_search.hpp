// A detection spread over frames: ModelFinder::find's work cut into small
// pieces, so that a tracker that re-acquires by detection, or surveys its
// first frame for look-alikes, never pays for a whole search in one frame.
//
// The search runs the finder's steps in order (model_finder.hpp): the coarse
// frame a few rows at a time, its features likewise (then their channels and
// list places, a few hundred at a time), every rotation's coarse vote
// (itself cut by features and by rows of the peak scan), then each coarse
// peak's first fine vote and each converging candidate's further votes. Each
// call to advance() does pieces until it has spent its budget of work, at
// least one piece. Work is counted, not timed, so that every target cuts the
// search at the same places and gets the same detections: a unit is about a
// counter increment (one vote), and track_step_work() counts a tracking vote
// in the same units, so a caller can budget in multiples of its own frames.
//
// Spread over frames, the search works on the first frame it is given,
// held in the scratch's held_frame: its detections are that frame's, bit for
// bit ModelFinder::find's on it (find is this search in one call), however
// the work is cut; they are as old as the frames the search took (frames()),
// and a tracker must follow them up to the current frame (detection_recovery.hpp).
// Without a held_frame, each piece works on the frame it is given: the coarse
// peaks found on the first frames are voted on later ones, which a moving
// target has left.
//
// No heap, no recursion. The FinderScratch given to begin() must be given to
// every advance() of the search (its spans hold the search between calls);
// its `fine` may differ from call to call (only a piece's own votes use it).
#pragma once

#include <cstdint>
#include <span>

#include "gabarit/depth_by_intensity.hpp"
#include "gabarit/image_view.hpp"
#include "gabarit/model_finder.hpp"
#include "gabarit/status.hpp"
#include "gabarit/tracker.hpp"

namespace gabarit {

// The work of one track_step with `table` that made `step` (its ROI's
// feature extraction and its votes), in the search's units.
std::uint64_t track_step_work(const TableView& table, const StepResult& step) noexcept;
// Its two terms: the ROI's feature extraction, and the votes (one unit each).
std::uint64_t track_features_work(const TableView& table) noexcept;
// The work of a tracking detector's extraction over `pixels` pixels.
std::uint64_t feature_extraction_work(std::uint64_t pixels) noexcept;
// The work of `correlations` correlations of a stack image with a frame
// (depth_by_intensity.hpp), in the same units.
std::uint64_t stack_correlation_work(const FocusStack& stack, std::uint32_t correlations) noexcept;
// The work of comparing `samples` model samples with a frame (Verdict::samples).
std::uint64_t stack_sample_work(std::uint64_t samples) noexcept;

inline constexpr std::uint64_t kUnlimitedWork = ~std::uint64_t{0};

class FinderSearch {
 public:
  explicit FinderSearch(const ModelFinder& finder) noexcept : finder_(finder) {}

  // Starts a search of frames of this size (no work yet). Errors: as
  // ModelFinder::find (kInvalidArgument for invalid options or size,
  // kBufferTooSmall for scratch short of finder_scratch_sizes).
  [[nodiscard]] Status begin(std::uint32_t width, std::uint32_t height, const FinderOptions& options,
                             FinderScratch scratch) noexcept;
  // Goes on with the search on `image` until `budget` units are spent (at
  // least one piece; kUnlimitedWork: to the end). Errors: kInvalidArgument
  // without a search begun or for a frame of another size; track_step's.
  // After an error the search is over (done() is false: begin again).
  [[nodiscard]] Status advance(const ImageView& image, FinderScratch scratch, std::uint64_t budget) noexcept;
  // The detections, best first, once done(): as ModelFinder::find's.
  // kBufferTooSmall if out is shorter than the options' max_count.
  [[nodiscard]] Status results(FinderScratch scratch, std::span<Detection> out, std::uint32_t& count) const noexcept;

  bool active() const noexcept { return phase_ != Phase::kIdle && phase_ != Phase::kDone; }
  bool done() const noexcept { return phase_ == Phase::kDone; }
  void cancel() noexcept { phase_ = Phase::kIdle; }
  // Work spent by the last advance(), and by the whole search so far.
  std::uint64_t last_work() const noexcept { return last_work_; }
  std::uint64_t total_work() const noexcept { return total_work_; }
  // Frames (advance calls) the search has taken so far.
  std::uint32_t frames() const noexcept { return frames_; }

 private:
  enum class Phase : std::uint8_t { kIdle, kCoarseRows, kCoarseFeatures, kFeatureChannels, kFeatureIndex, kRotationLists,
                                    kRotationVote, kRotationScan, kFirstVotes, kConverge, kDone };
  // One piece of the current phase, spending at most about `allowance`
  // (at least one item); adds its work to `spent`.
  Status piece(const ImageView& image, FinderScratch& scratch, std::uint64_t allowance, std::uint64_t& spent) noexcept;
  std::uint64_t coarse_rows(const ImageView& image, FinderScratch& scratch, std::uint64_t allowance) noexcept;
  Status coarse_features(FinderScratch& scratch, std::uint64_t allowance, std::uint64_t& spent) noexcept;
  std::uint64_t feature_channels(FinderScratch& scratch, std::uint64_t allowance) noexcept;
  std::uint64_t feature_index(FinderScratch& scratch, std::uint64_t allowance) noexcept;
  std::uint64_t rotation_lists(FinderScratch& scratch) noexcept;
  std::uint64_t rotation_vote(FinderScratch& scratch, std::uint64_t allowance) noexcept;
  std::uint64_t rotation_scan(FinderScratch& scratch, std::uint64_t allowance) noexcept;
  Status first_vote(const ImageView& image, FinderScratch& scratch, std::uint64_t& spent) noexcept;
  Status converge_vote(const ImageView& image, FinderScratch& scratch, std::uint64_t& spent) noexcept;
  Status finish_candidate(const ImageView& image, FinderScratch& scratch, std::uint64_t& spent) noexcept;
  Status fine_vote(const ImageView& image, const Pose& from, FinderScratch& scratch, StepResult& step,
                   std::uint64_t& spent) noexcept;
  void offer_peak(FinderScratch& scratch, std::int32_t x, std::int32_t y, std::uint32_t votes) noexcept;
  void rank(FinderScratch& scratch) noexcept;
  std::uint64_t verify_work(std::uint16_t depth) const noexcept;

  const ModelFinder& finder_;
  FinderOptions options_;
  FinderGeometry g_;
  FinderScratchSizes need_;
  Phase phase_ = Phase::kIdle;
  std::uint32_t width_ = 0, height_ = 0;
  std::uint32_t next_ = 0;      // the phase's next row, rotation or candidate
  std::uint32_t rotation_ = 0;  // the rotation being voted
  std::uint32_t channel_ = 0, feature_ = 0;  // where its vote goes on
  static constexpr std::uint32_t kChannelSlots = kOrientationChannels + 1;
  std::uint32_t channel_begin_[kChannelSlots] = {};  // the coarse features' channels
  std::uint32_t list_begin_[kChannelSlots] = {};     // the rotated model's lists
  std::uint32_t model_n_ = 0;
  std::uint32_t features_ = 0;  // the coarse features found so far
  // The shortlist of coarse peaks (in scratch.candidates).
  std::uint32_t peaks_ = 0;
  std::int64_t peak_distance2_ = 0;
  std::uint32_t floor_votes_ = 0;
  float best_first_ = 0.0f;
  // The converging candidate: its votes so far, the pose voted from and the last vote.
  std::uint32_t votes_ = 0;
  Pose from_;
  StepResult step_;
  std::uint64_t last_work_ = 0, total_work_ = 0;
  std::uint32_t frames_ = 0;
  bool holding_ = false;  // the first frame is in scratch.held_frame
};

}  // namespace gabarit
