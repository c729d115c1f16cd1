// Finding the model anywhere in a frame: what starts tracking without a
// known pose, and re-acquires a target that reappears anywhere.
//
// Two levels, coarse to fine (the thesis's hierarchical stencils):
//
//  1. Coarse: the frame is averaged over f x f blocks (the pyramid factor)
//     and its features are found with the table's detector, each with its
//     quantised edge orientation (orientation_256, one of 16 channels). The
//     model is the table's model points of one depth at the same scale, each
//     with the orientation of the model image's edge there. Every rotation
//     theta_k of the search range is a cell of a translation-invariant
//     stencil: a coarse feature of channel c votes for the reference
//     positions p - R(theta_k) m of the model points m whose rotated
//     orientation lies in channel c (or the next one, whichever is nearer).
//     One accumulator of the coarse frame's size serves every rotation in
//     turn; its peaks (3 x 3 sums) go to a shortlist that keeps one peak per
//     place (no two within min_distance).
//  2. Fine: each of the best `candidates` peaks is voted with the table
//     itself (track_step from the peak's pose, then again from the result,
//     as a tracking frame would) and verified: the score is the fraction of
//     the model points of the chosen depth that have, within one pixel, an
//     edge pixel (Sobel magnitude at least half the detector's threshold)
//     whose orientation is within one channel of theirs (HALCON's shape
//     models score likewise). With a focus stack, the depth and the angle
//     are chosen by intensity before the verification. Candidates below min_score are dropped; the
//     rest are ranked by score, duplicates removed, max_count reported.
//
// Without model images (point models) or with the binary detector there is
// no orientation: every point is in one channel and the coarse features
// are the pixels of a block with any non-zero pixel; the verification then
// asks for a non-zero pixel within one pixel.
//
// Cost: the coarse vote is about features x (points / 8) x rotations
// increments; the fine level about candidates x 2 track_steps. Stack: a few
// hundred bytes (the candidates are the caller's scratch).
// No heap, no recursion: scratch comes from the caller, sized by
// finder_scratch_sizes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "gabarit/depth_by_intensity.hpp"
#include "gabarit/features.hpp"
#include "gabarit/image_view.hpp"
#include "gabarit/pose.hpp"
#include "gabarit/recovery_search.hpp"
#include "gabarit/status.hpp"
#include "gabarit/table_view.hpp"
#include "gabarit/tracker.hpp"

namespace gabarit {

inline constexpr std::uint32_t kMaxFinderCandidates = 64;
inline constexpr std::uint32_t kMaxPyramidFactor = 8;
inline constexpr std::uint32_t kMaxFinderRotations = 4096;

struct FinderOptions {
  // The range of absolute angles searched, degrees: a full turn by default.
  float theta_min_deg = -180.0f;
  float theta_max_deg = 180.0f;
  // The coarse rotation step; 0: the table's theta extent (so that one fine
  // vote covers the step), at most one radian over the coarse model's radius.
  float theta_step_deg = 0.0f;
  // Coarse blocks of f x f pixels, 1..kMaxPyramidFactor; 0: from the
  // model's radius (about 12 coarse pixels, at most 4).
  std::uint32_t pyramid_factor = 0;
  std::uint32_t candidates = 6;  // coarse peaks checked with the table, 1..kMaxFinderCandidates
  std::uint32_t max_count = 5;   // detections reported, at most candidates
  float min_score = 0.5f;        // 0..1: the verified fraction of model points
  float min_distance_px = 0.0f;  // closer detections are one; 0: half the model's radius
  bool orientation = true;       // false: the coarse vote ignores orientation (position only)
  // The depth whose model points make the coarse model; -1: the middle one.
  std::int32_t coarse_depth = -1;
};
bool valid(const FinderOptions& options) noexcept;

struct Detection {
  Pose pose;
  float score = 0.0f;         // verified fraction of model points, 0..1
  float coarse_score = 0.0f;  // the coarse peak's votes over the coarse model's points
  float vote_score = 0.0f;    // the table's normalised score of the chosen cell
};

// What a finder derives from the table, the options and the frame size.
struct FinderGeometry {
  std::uint32_t factor = 1;          // pyramid factor
  std::uint32_t coarse_width = 0;    // ceil(width / factor)
  std::uint32_t coarse_height = 0;
  std::uint32_t pad = 0;             // accumulator border: the coarse model's radius + 1
  std::uint32_t rotations = 0;       // coarse angles searched
  float theta_step_deg = 0.0f;
  std::uint16_t coarse_depth = 0;
  float model_radius_px = 0.0f;      // farthest model point of the coarse depth from the reference
  float min_distance_px = 0.0f;
  bool orientation = false;          // the model carries orientations
};
// Precondition: the table opened; options valid; width, height > 0.
FinderGeometry finder_geometry(const TableView& table, const Detector& detector, const FinderOptions& options,
                               std::uint32_t width, std::uint32_t height) noexcept;

// Entries of each FinderScratch span.
struct FinderScratchSizes {
  std::size_t coarse_pixels = 0;      // coarse_image, coarse_features, feature_index
  std::size_t accumulator = 0;        // (coarse_width + 2 pad) x (coarse_height + 2 pad)
  std::size_t model_points = 0;       // the largest depth's model points: model, rotated (x2 for the lists)
};
FinderScratchSizes finder_scratch_sizes(const FinderGeometry& geometry, const TableView& table) noexcept;

// A model point of the coarse model, or of the verification model.
struct OrientedPoint {
  std::int16_t x = 0;
  std::int16_t y = 0;
  std::uint8_t orientation = 0;  // orientation_256 of the model image's edge
};

// One coarse peak and what the fine level made of it (FinderScratch::candidates).
struct FinderCandidate {
  std::int32_t x = 0, y = 0;   // the peak's reference position, coarse pixels
  std::uint32_t rotation = 0;  // its rotation's index
  std::uint32_t votes = 0;     // its 3 x 3 sum
  Detection result;            // after the fine level
  bool found = false;          // result verified at or above min_score
};

struct FinderScratch {
  std::span<std::uint8_t> coarse_image;     // coarse_pixels
  std::span<RoiPoint> coarse_features;      // coarse_pixels
  std::span<std::int32_t> feature_index;    // coarse_pixels
  std::span<std::uint16_t> accumulator;     // accumulator
  std::span<OrientedPoint> model;           // model_points
  std::span<std::int32_t> rotated;          // 2 x model_points
  std::span<FinderCandidate> candidates;    // options.candidates (kMaxFinderCandidates fits any)
  TrackerScratch fine;                      // for the table, as track_step wants it
  // Optional, width x height: a search spread over frames keeps its first
  // frame here and works on it throughout (finder_search.hpp); find ignores it.
  std::span<std::uint8_t> held_frame;
};

class ModelFinder {
 public:
  // `table` must outlive the finder.
  ModelFinder(const TableView& table, const Detector& detector) noexcept : table_(table), detector_(detector) {}

  // Finds up to options.max_count detections in `image`, best first, into
  // out[0, count). Errors: kInvalidArgument for invalid options or image,
  // kBufferTooSmall for scratch short of finder_scratch_sizes or out shorter
  // than max_count; the tracker's errors.
  [[nodiscard]] Status find(const ImageView& image, const FinderOptions& options, FinderScratch scratch,
                            std::span<Detection> out, std::uint32_t& count) noexcept;

  // The verification score of a pose (the fraction of the depth's model
  // points with an edge of their orientation within a pixel). Uses
  // scratch.model. Errors: as find.
  [[nodiscard]] Status verify(const ImageView& image, const Pose& pose, FinderScratch scratch, float& score) const noexcept;

  // With a focus stack (the table's model images; must outlive the finder;
  // nullptr to stop), each converged candidate's depth and angle are then
  // chosen by intensity (depth_by_intensity.hpp), as a session does: edge
  // votes tell depths and the angle of a near-symmetric outline apart poorly.
  void use_focus_stack(const FocusStack* stack) noexcept { stack_ = stack; }

  const TableView& table() const noexcept { return table_; }
  const Detector& detector() const noexcept { return detector_; }
  const FocusStack* focus_stack() const noexcept { return stack_; }

 private:
  friend class FinderSearch;  // find's steps, spread over frames (finder_search.hpp)
  std::uint32_t load_model(std::uint16_t depth, std::uint32_t factor, bool orientation,
                           std::span<OrientedPoint> out) const noexcept;
  const TableView& table_;
  Detector detector_;
  const FocusStack* stack_ = nullptr;
};

}  // namespace gabarit
