#include "gabarit/tracker.hpp"

#include "gabarit/dense_voter.hpp"
#include "gabarit/deterministic_math.hpp"

namespace gabarit {
namespace {

bool finite_and_bounded(float v) noexcept { return v == v && v > -1.0e6f && v < 1.0e6f; }

// Rotate features found in `window` into the table frame, keep those that
// land inside the ROI, once each, compacting them in place (an output index
// never passes its input index).
std::uint32_t rotate_into_roi(const TableView& table, std::span<RoiPoint> features, std::uint32_t count,
                              const ImageWindow& window, std::int32_t cx, std::int32_t cy, SinCos sc,
                              std::span<std::uint8_t> mask) noexcept {
  for (std::size_t i = 0; i < tracker_mask_bytes(table); ++i) mask[i] = 0;
  const std::int32_t w = table.roi_width();
  const std::int32_t h = table.roi_height();
  std::uint32_t kept = 0;
  for (std::uint32_t i = 0; i < count; ++i) {
    const float dx = static_cast<float>(window.x0 + features[i].col - cx);
    const float dy = static_cast<float>(window.y0 + features[i].row - cy);
    // R(-theta) d
    const std::int32_t col = round_to_int(sc.cos * dx + sc.sin * dy) - table.roi_origin_x();
    const std::int32_t row = round_to_int(-sc.sin * dx + sc.cos * dy) - table.roi_origin_y();
    if (col < 0 || row < 0 || col >= w || row >= h) continue;
    const std::uint32_t bit = static_cast<std::uint32_t>(row * w + col);
    const std::uint8_t m = static_cast<std::uint8_t>(1u << (bit & 7u));
    if (mask[bit >> 3] & m) continue;
    mask[bit >> 3] = static_cast<std::uint8_t>(mask[bit >> 3] | m);
    features[kept++] = {static_cast<std::uint16_t>(col), static_cast<std::uint16_t>(row)};
  }
  return kept;
}

}  // namespace

const char* track_state_name(TrackState state) noexcept {
  switch (state) {
    case TrackState::kTracking: return "tracking";
    case TrackState::kUncertain: return "uncertain";
    case TrackState::kLost: return "lost";
  }
  return "unknown";
}

Pose pose_of_cell(const TableView& table, std::uint32_t cell_index, const Pose& previous, std::int32_t cx, std::int32_t cy,
                  float offset_x, float offset_y, float offset_theta_deg) noexcept {
  const SinCos sc = sin_cos_deg(previous.theta_deg);
  const CellBounds cell = table.cell(cell_index);
  const float tx = cell.x_centre() + offset_x;
  const float ty = cell.y_centre() + offset_y;
  Pose pose;
  pose.x = static_cast<float>(cx) + (sc.cos * tx - sc.sin * ty);
  pose.y = static_cast<float>(cy) + (sc.sin * tx + sc.cos * ty);
  pose.theta_deg = previous.theta_deg + cell.theta_centre_deg() + offset_theta_deg;
  pose.depth = cell.depth;
  return pose;
}

Status prepare_frame(const TableView& table, const Detector& detector, const ImageView& image, const Pose& previous,
                     TrackerScratch scratch, PreparedFrame& out) noexcept {
  if (!image.valid() || !finite_and_bounded(previous.x) || !finite_and_bounded(previous.y) ||
      !finite_and_bounded(previous.theta_deg)) {
    return Status::kInvalidArgument;
  }
  if (scratch.counters.size() != voter_counter_count(table.cell_count())) return Status::kBufferTooSmall;

  const std::int32_t cx = round_to_int(previous.x);
  const std::int32_t cy = round_to_int(previous.y);
  const bool rotated = previous.theta_deg != 0.0f;
  if (rotated && scratch.roi_mask.size() < tracker_mask_bytes(table)) return Status::kBufferTooSmall;

  ImageWindow window;
  if (!rotated) {
    window = {cx + table.roi_origin_x(), cy + table.roi_origin_y(), table.roi_width(), table.roi_height()};
  } else {
    const std::uint32_t side =
        tracker_window_side(table.roi_width(), table.roi_height(), table.roi_origin_x(), table.roi_origin_y());
    if (side > 0xFFFFu) return Status::kInvalidArgument;  // a window this large cannot be addressed
    const auto half = static_cast<std::int32_t>(side / 2);
    window = {cx - half, cy - half, static_cast<std::uint16_t>(side), static_cast<std::uint16_t>(side)};
  }

  FeatureCount found;
  GABARIT_TRY(extract_features(image, window, detector.kind, detector.threshold, scratch.features, found));
  std::uint32_t n = found.written;
  if (rotated) n = rotate_into_roi(table, scratch.features, n, window, cx, cy, sin_cos_deg(previous.theta_deg), scratch.roi_mask);
  out = {cx, cy, n, found.dropped};
  return Status::kOk;
}

Status finish_frame(const TableView& table, const Pose& previous, const PreparedFrame& frame,
                    std::span<const VoteCounter> counters, const VoteTally& tally, StepResult& result) noexcept {
  CellScore top[2];
  const std::size_t k = table.cell_count() >= 2 ? 2 : 1;
  GABARIT_TRY(select_top_cells(table, counters, std::span<CellScore>(top, k)));
  if (k == 1) top[1] = {kNoCell, 0, 0};

  result.pose = pose_of_cell(table, top[0].cell, previous, frame.roi_centre_x, frame.roi_centre_y);
  result.best = top[0];
  result.runner_up = top[1];
  result.score = normalised_score(top[0]);
  if (top[0].votes == 0) {
    result.state = TrackState::kLost;
  } else if (k == 2 && scores_equal(top[0], top[1])) {
    result.state = TrackState::kUncertain;
  } else {
    result.state = TrackState::kTracking;
  }
  result.roi_centre_x = frame.roi_centre_x;
  result.roi_centre_y = frame.roi_centre_y;
  result.features = tally.features;
  result.features_dropped = frame.features_dropped;
  result.votes = tally.votes;
  return Status::kOk;
}

Status track_step(const TableView& table, const Detector& detector, const ImageView& image, const Pose& previous,
                  TrackerScratch scratch, StepResult& result) noexcept {
  PreparedFrame frame;
  GABARIT_TRY(prepare_frame(table, detector, image, previous, scratch, frame));
  GABARIT_TRY(clear_counters(table, scratch.counters));
  const std::span<const RoiPoint> features = scratch.features.first(frame.features);
  VoteTally tally;
  if (!scratch.dense_masks.empty()) {
    GABARIT_TRY(accumulate_votes_dense(table, scratch.dense_masks, features, scratch.counters, scratch.dense_scratch, tally));
  } else {
    GABARIT_TRY(accumulate_votes(table, features, scratch.counters, tally));
  }
  return finish_frame(table, previous, frame, scratch.counters, tally, result);
}

}  // namespace gabarit
