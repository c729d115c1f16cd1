#include "gabarit/tracker.hpp"

#include "gabarit/dense_voter.hpp"
#include "gabarit/deterministic_math.hpp"

namespace gabarit {
namespace {

// The image window whose features can land in the ROI centred on (cx, cy):
// the ROI itself unrotated, else the square holding it at any angle.
// Precondition: the square's side fits 16 bits.
ImageWindow frame_window(const TableView& table, std::int32_t cx, std::int32_t cy, bool rotated) noexcept {
  if (!rotated) return {cx + table.roi_origin_x(), cy + table.roi_origin_y(), table.roi_width(), table.roi_height()};
  const std::uint32_t side = tracker_window_side(table.roi_width(), table.roi_height(), table.roi_origin_x(), table.roi_origin_y());
  const auto half = static_cast<std::int32_t>(side / 2);
  return {cx - half, cy - half, static_cast<std::uint16_t>(side), static_cast<std::uint16_t>(side)};
}

// The ROI pixel a frame offset d = p - c lands on in the table frame, R(-theta) d
// rounded; false outside the ROI.
bool roi_pixel_of(const TableView& table, float dx, float dy, SinCos sc, std::uint32_t& bit, RoiPoint& at) noexcept {
  const std::int32_t col = round_to_int(sc.cos * dx + sc.sin * dy) - table.roi_origin_x();
  const std::int32_t row = round_to_int(-sc.sin * dx + sc.cos * dy) - table.roi_origin_y();
  if (col < 0 || row < 0 || col >= table.roi_width() || row >= table.roi_height()) return false;
  bit = static_cast<std::uint32_t>(row * table.roi_width() + col);
  at = {static_cast<std::uint16_t>(col), static_cast<std::uint16_t>(row)};
  return true;
}

// Sets `bit` in the de-duplication mask; false when it was already set.
bool first_visit(std::span<std::uint8_t> mask, std::uint32_t bit) noexcept {
  const std::uint8_t m = static_cast<std::uint8_t>(1u << (bit & 7u));
  if (mask[bit >> 3] & m) return false;
  mask[bit >> 3] = static_cast<std::uint8_t>(mask[bit >> 3] | m);
  return true;
}

// Orientation channels (table_view.hpp, feature_slots): the channel of the
// edge at image pixel (x, y) in the table frame (its orientation less the
// ROI's angle, `turn` in 256ths of a half turn), packed into at.col.
void add_channel(const TableView& table, const ImageView& image, std::int64_t x, std::int64_t y, std::uint32_t turn,
                 RoiPoint& at) noexcept {
  const std::uint32_t bits = table.channel_bits(), k = bits - 1;
  const SobelGradient g = sobel_gradient(image, static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y));
  const std::uint32_t o = (orientation_256(g.gx, g.gy) + 256u - turn) & 255u;
  const std::uint32_t channel = o >> (8 - k), upper = (o >> (7 - k)) & 1u;
  at.col = static_cast<std::uint16_t>((std::uint32_t{at.col} << bits) | (channel << 1) | upper);
}

// The ROI's angle in 256ths of a half turn, modulo 256.
std::uint32_t half_turn_steps(float theta_deg) noexcept {
  const float wrapped = theta_deg - 180.0f * static_cast<float>(round_to_int(theta_deg / 180.0f));  // [-90, 90]
  return static_cast<std::uint32_t>(round_to_int(wrapped * (256.0f / 180.0f)) + 256) & 255u;
}

std::uint32_t rotate_into_roi(const TableView& table, const ImageView& image, std::span<RoiPoint> features, std::uint32_t count,
                              const ImageWindow& window, std::int32_t cx, std::int32_t cy, SinCos sc, std::uint32_t turn,
                              std::span<std::uint8_t> mask) noexcept {
  for (std::size_t i = 0; i < tracker_mask_bytes(table); ++i) mask[i] = 0;
  std::uint32_t kept = 0;
  for (std::uint32_t i = 0; i < count; ++i) {
    std::uint32_t bit = 0;
    RoiPoint at;
    if (!roi_pixel_of(table, static_cast<float>(window.x0 + features[i].col - cx),
                      static_cast<float>(window.y0 + features[i].row - cy), sc, bit, at)) {
      continue;
    }
    if (!first_visit(mask, bit)) continue;
    if (table.channel_bits() != 0) add_channel(table, image, window.x0 + features[i].col, window.y0 + features[i].row, turn, at);
    features[kept++] = at;
  }
  return kept;
}

}  // namespace

const char* track_state_name(TrackState state) noexcept {
  switch (state) {
    case TrackState::kTracking: return "tracking";
    case TrackState::kUncertain: return "uncertain";
    case TrackState::kLost: return "lost";
    case TrackState::kAmbiguous: return "ambiguous";
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
  if (!image.valid() || !pose_in_range(previous)) {
    return Status::kInvalidArgument;
  }
  if (scratch.counters.size() != voter_counter_count(table.cell_count())) return Status::kBufferTooSmall;

  const std::int32_t cx = round_to_int(previous.x);
  const std::int32_t cy = round_to_int(previous.y);
  const bool rotated = previous.theta_deg != 0.0f;
  if (rotated && scratch.roi_mask.size() < tracker_mask_bytes(table)) return Status::kBufferTooSmall;

  if (rotated && tracker_window_side(table.roi_width(), table.roi_height(), table.roi_origin_x(), table.roi_origin_y()) > 0xFFFFu) {
    return Status::kInvalidArgument;  // a window this large cannot be addressed
  }
  const ImageWindow window = frame_window(table, cx, cy, rotated);

  FeatureCount found;
  // At an angle, only the pixels that can land in the ROI (roi_pixel_of:
  // a turned offset that rounds into it) need scanning, not the whole square.
  const SinCos sc = sin_cos_deg(previous.theta_deg);
  const TurnedRectangle roi{static_cast<float>(cx),
                            static_cast<float>(cy),
                            sc.cos,
                            sc.sin,
                            static_cast<float>(table.roi_origin_x()) - 0.5f,
                            static_cast<float>(table.roi_origin_x() + table.roi_width()) - 0.5f,
                            static_cast<float>(table.roi_origin_y()) - 0.5f,
                            static_cast<float>(table.roi_origin_y() + table.roi_height()) - 0.5f};
  GABARIT_TRY(extract_features(image, window, detector.kind, detector.threshold, scratch.features, found, scratch.magnitudes,
                               rotated ? &roi : nullptr));
  std::uint32_t n = found.written;
  if (rotated) {
    n = rotate_into_roi(table, image, scratch.features, n, window, cx, cy, sc, half_turn_steps(previous.theta_deg),
                        scratch.roi_mask);
  } else if (table.channel_bits() != 0) {
    for (std::uint32_t i = 0; i < n; ++i)
      add_channel(table, image, window.x0 + scratch.features[i].col, window.y0 + scratch.features[i].row, 0, scratch.features[i]);
  }
  out = {cx, cy, n, found.dropped, static_cast<std::uint32_t>(found.scanned)};
  return Status::kOk;
}

// Rotate features found in `window` into the table frame, keep those that
// land inside the ROI, once each, compacting them in place (an output index
// never passes its input index).
Status map_features(const TableView& table, const ImageView& image, std::span<const RoiPoint> detected, const ImageWindow& window,
                    const Pose& previous, TrackerScratch scratch, PreparedFrame& out) noexcept {
  if (!pose_in_range(previous) || (table.channel_bits() != 0 && !image.valid())) {
    return Status::kInvalidArgument;
  }
  if (scratch.counters.size() != voter_counter_count(table.cell_count()) ||
      scratch.roi_mask.size() < tracker_mask_bytes(table)) {
    return Status::kBufferTooSmall;
  }
  if (tracker_window_side(table.roi_width(), table.roi_height(), table.roi_origin_x(), table.roi_origin_y()) > 0xFFFFu) {
    return Status::kInvalidArgument;
  }
  const std::int32_t cx = round_to_int(previous.x);
  const std::int32_t cy = round_to_int(previous.y);
  // prepare_frame's window: only features inside it are kept, so for a
  // detector whose result does not depend on the window the features are
  // exactly prepare_frame's. Features are in raster order: the first row is
  // found by bisection and the scan stops past the last.
  const ImageWindow own = frame_window(table, cx, cy, previous.theta_deg != 0.0f);
  const std::int64_t first_row = std::int64_t{own.y0} - window.y0, last_row = first_row + own.height - 1;
  const std::int64_t first_col = std::int64_t{own.x0} - window.x0, last_col = first_col + own.width - 1;
  std::size_t lo = 0, hi = detected.size();
  while (lo < hi) {
    const std::size_t mid = lo + (hi - lo) / 2;
    if (detected[mid].row < first_row) lo = mid + 1;
    else hi = mid;
  }
  for (std::size_t i = 0; i < tracker_mask_bytes(table); ++i) scratch.roi_mask[i] = 0;
  const SinCos sc = sin_cos_deg(previous.theta_deg);
  const std::uint32_t turn = half_turn_steps(previous.theta_deg);
  std::uint32_t kept = 0, dropped = 0;
  for (std::size_t i = lo; i < detected.size() && detected[i].row <= last_row; ++i) {
    if (detected[i].col < first_col || detected[i].col > last_col) continue;
    std::uint32_t bit = 0;
    RoiPoint at;
    if (!roi_pixel_of(table, static_cast<float>(window.x0 + detected[i].col - cx),
                      static_cast<float>(window.y0 + detected[i].row - cy), sc, bit, at)) {
      continue;
    }
    if (!first_visit(scratch.roi_mask, bit)) continue;
    if (table.channel_bits() != 0) add_channel(table, image, window.x0 + detected[i].col, window.y0 + detected[i].row, turn, at);
    if (kept < scratch.features.size()) scratch.features[kept++] = at;
    else ++dropped;
  }
  out = {cx, cy, kept, dropped};
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
  VoteTally tally;
  GABARIT_TRY(vote_prepared(table, frame, scratch, tally));
  return finish_frame(table, previous, frame, scratch.counters, tally, result);
}

Status vote_prepared(const TableView& table, const PreparedFrame& frame, TrackerScratch scratch, VoteTally& tally) noexcept {
  GABARIT_TRY(clear_counters(table, scratch.counters));
  if (frame.features > scratch.features.size()) return Status::kBufferTooSmall;
  const std::span<const RoiPoint> features = scratch.features.first(frame.features);
  tally = {};
  if (!scratch.dense_masks.empty()) return accumulate_votes_dense(table, scratch.dense_masks, features, scratch.counters, scratch.dense_scratch, tally);
  if (!scratch.expanded_offsets.empty()) return accumulate_votes_expanded(table, scratch.expanded_offsets, features, scratch.counters, tally);
  return accumulate_votes(table, features, scratch.counters, tally);
}

}  // namespace gabarit
