// One tracking step: place the ROI around the previous pose, extract features,
// vote, pick the best cell, update the pose.
//
// Geometry. The ROI centre is the previous position rounded to the nearest
// pixel, c = (round(x), round(y)). Table ROI pixel (col, row) is the offset
// d = (roi_origin_x + col, roi_origin_y + row) from c in the *table frame*,
// which is the image frame rotated by the previous angle theta: an image
// pixel p maps to d = R(-theta) (p - c), rounded to the nearest pixel. With a
// winning cell U (centre t = (tx, ty), angle centre a, depth n) the updated pose is
//   (x, y) = c + R(theta) t,   theta' = theta + a,   depth' = n.
// With theta = 0 this is exactly "previous pose plus the centre of the cell".
// Model point m (relative to the reference point) then lies at
//   (x, y) + R(theta') m   in image axes (y down).
//
// State. kLost when the best cell has no vote; kUncertain when the runner-up
// has the same normalised score (the motion is ambiguous); kTracking
// otherwise. A TrackingSession (tracking_session.hpp) grades it further with
// the motion filter's confidence.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "gabarit/features.hpp"
#include "gabarit/image_view.hpp"
#include "gabarit/pose.hpp"
#include "gabarit/roi_point.hpp"
#include "gabarit/status.hpp"
#include "gabarit/table_view.hpp"
#include "gabarit/voter.hpp"

namespace gabarit {

// kAmbiguous: a verifying session saw two distinct placements correlate
// alike (tracking_session.hpp); track_step itself never reports it.
enum class TrackState : std::uint8_t { kTracking = 0, kUncertain = 1, kLost = 2, kAmbiguous = 3 };
const char* track_state_name(TrackState state) noexcept;

// Side of the square image window that contains the ROI rotated by any angle
// (table_format::roi_window_side; at most kMaxRoiWindowSide in a valid table).
constexpr std::uint32_t tracker_window_side(std::uint16_t roi_width, std::uint16_t roi_height,
                                            std::int16_t roi_origin_x, std::int16_t roi_origin_y) noexcept {
  return table_format::roi_window_side(roi_width, roi_height, roi_origin_x, roi_origin_y);
}

// Scratch sizes for track_step; use them to size static buffers and
// static_assert against them on an MCU.
constexpr std::size_t tracker_feature_capacity(std::uint16_t roi_width, std::uint16_t roi_height,
                                               std::int16_t roi_origin_x, std::int16_t roi_origin_y) noexcept {
  const std::size_t side = tracker_window_side(roi_width, roi_height, roi_origin_x, roi_origin_y);
  const std::size_t roi = std::size_t{roi_width} * roi_height;
  return side * side > roi ? side * side : roi;
}
// One bit per ROI pixel: de-duplicates features after rotation into the table frame.
constexpr std::size_t tracker_mask_bytes(std::uint16_t roi_width, std::uint16_t roi_height) noexcept {
  return (std::size_t{roi_width} * roi_height + 7) / 8;
}
// Optional: the Canny detector's rows of gradient magnitudes over the widest
// window track_step scans (the rotated ROI's square, or the ROI).
constexpr std::size_t tracker_magnitude_entries(std::uint16_t roi_width, std::uint16_t roi_height,
                                                std::int16_t roi_origin_x, std::int16_t roi_origin_y) noexcept {
  const std::uint32_t side = tracker_window_side(roi_width, roi_height, roi_origin_x, roi_origin_y);
  const std::uint32_t widest = side > roi_width ? side : roi_width;
  return canny_scratch_entries(static_cast<std::uint16_t>(widest > 0xFFFFu ? 0xFFFFu : widest));
}
inline std::size_t tracker_magnitude_entries(const TableView& t) noexcept {
  return tracker_magnitude_entries(t.roi_width(), t.roi_height(), t.roi_origin_x(), t.roi_origin_y());
}
inline std::size_t tracker_feature_capacity(const TableView& t) noexcept {
  return tracker_feature_capacity(t.roi_width(), t.roi_height(), t.roi_origin_x(), t.roi_origin_y());
}
inline std::size_t tracker_mask_bytes(const TableView& t) noexcept {
  return tracker_mask_bytes(t.roi_width(), t.roi_height());
}

struct TrackerScratch {
  std::span<RoiPoint> features;      // >= tracker_feature_capacity(table) avoids dropped features
  std::span<VoteCounter> counters;   // == voter_counter_count(table.cell_count())
  std::span<std::uint8_t> roi_mask;  // >= tracker_mask_bytes(table); only used when theta != 0
  // Optional word-parallel voting (dense_voter.hpp), for tables of at most
  // kDenseMaxCells cells: masks prepared once by build_dense_masks, and
  // dense_scratch_words(cells) words. Empty: the CSR voter. Results are
  // bit-identical either way.
  std::span<const std::uint64_t> dense_masks = {};
  std::span<std::uint64_t> dense_scratch = {};
  // Optional, without dense masks: a compact table's offsets expanded once
  // (voter.hpp, expand_offsets), so the CSR voter skips their decode. Empty:
  // the table's own offsets. Results are bit-identical either way.
  std::span<const std::uint32_t> expanded_offsets = {};
  // Optional, >= tracker_magnitude_entries(table): the Canny detector computes
  // each pixel's gradient once (features.hpp). Same features either way.
  std::span<std::uint16_t> magnitudes = {};
};

struct StepResult {
  Pose pose;
  CellScore best;
  CellScore runner_up;     // cell == kNoCell when the table has one cell
  float score = 0.0f;      // normalised score of the best cell, votes / stencil size
  TrackState state = TrackState::kLost;
  std::int32_t roi_centre_x = 0;
  std::int32_t roi_centre_y = 0;
  std::uint32_t features = 0;          // feature pixels that voted
  std::uint32_t features_dropped = 0;  // lost to a too-small feature buffer
  std::uint64_t votes = 0;             // counter increments this frame
};

// The feature detector frames go through; a table records the one its model
// was built with, and a caller may override it (e.g. binary synthetic frames).
struct Detector {
  table_format::DetectorKind kind = table_format::DetectorKind::kBinary;
  std::uint16_t threshold = 0;
};
inline Detector detector_of(const TableView& t) noexcept { return {t.detector_kind(), t.detector_threshold()}; }

// track_step in two halves, for a caller that votes its own way in between
// (gabarit track --threads votes on several cores):
//   prepare_frame  the features of the frame, in the table frame, written to
//                  scratch.features[0, features);
//   (vote)         clear the counters, vote those features into them;
//   finish_frame   the best cells and the pose update.
// track_step is exactly prepare_frame, vote_prepared and finish_frame.
struct PreparedFrame {
  std::int32_t roi_centre_x = 0;
  std::int32_t roi_centre_y = 0;
  std::uint32_t features = 0;          // valid entries at the start of scratch.features
  std::uint32_t features_dropped = 0;
  // The pixels the detector examined (the cost of extraction,
  // frame_ledger.hpp): the ROI's, or at an angle (binary, Canny) the rotated ROI's
  // columns of each row of the square that holds it.
  std::uint32_t pixels_scanned = 0;
};
Status prepare_frame(const TableView& table, const Detector& detector, const ImageView& image, const Pose& previous,
                     TrackerScratch scratch, PreparedFrame& out) noexcept;
// The vote between the halves: clears the counters and votes the prepared
// frame's features with the voter the scratch selects (dense masks, expanded
// offsets, or the table's own offsets; bit-identical either way).
Status vote_prepared(const TableView& table, const PreparedFrame& frame, TrackerScratch scratch, VoteTally& tally) noexcept;
Status finish_frame(const TableView& table, const Pose& previous, const PreparedFrame& frame,
                    std::span<const VoteCounter> counters, const VoteTally& tally, StepResult& result) noexcept;
// prepare_frame from features already detected over a larger window (in
// that window's coordinates, raster order, as extract_features writes them):
// a search that places the ROI many times in one frame detects once. The
// features kept are prepare_frame's, in the same order, wherever the
// detector's result does not depend on the window (binary: everywhere;
// gradient rows: except runs that cross prepare_frame's window edge, which
// prepare_frame cuts). scratch.roi_mask is needed whatever the angle. Errors: kInvalidArgument for a non-finite pose,
// kBufferTooSmall for short counters or mask; features beyond
// scratch.features are counted as dropped.
// `image` is the frame the features were detected in (with orientation
// channels their gradients give the channels; unused otherwise).
Status map_features(const TableView& table, const ImageView& image, std::span<const RoiPoint> detected, const ImageWindow& window,
                    const Pose& previous, TrackerScratch scratch, PreparedFrame& out) noexcept;

// The pose update for cell `cell` measured from `previous` with the ROI centred
// on (cx, cy): (x, y) = c + R(theta) (t + offset), theta' = theta + a + offset,
// depth' = n (see the geometry above). track_step uses it with no offset; the
// motion filter for its candidates and refinement for the sub-cell offset.
Pose pose_of_cell(const TableView& table, std::uint32_t cell, const Pose& previous, std::int32_t cx, std::int32_t cy,
                  float offset_x = 0.0f, float offset_y = 0.0f, float offset_theta_deg = 0.0f) noexcept;

// Precondition: `table` was opened successfully. Errors: kInvalidArgument for
// an invalid image, a non-finite pose or a bad detector threshold,
// kBufferTooSmall for short scratch.
Status track_step(const TableView& table, const Detector& detector, const ImageView& image, const Pose& previous,
                  TrackerScratch scratch, StepResult& result) noexcept;
inline Status track_step(const TableView& table, const ImageView& image, const Pose& previous,
                         TrackerScratch scratch, StepResult& result) noexcept {
  return track_step(table, detector_of(table), image, previous, scratch, result);
}

}  // namespace gabarit
