// Sub-cell accuracy: the thesis's estimate is the winning cell's centre; this
// refines it by fitting a parabola through the normalised scores of the
// winning cell and its two neighbours along each axis (x, y, theta), the
// standard sub-sample peak interpolation of correlation methods. Depth stays
// the winning index (it is a discrete choice).
//
// The offset along an axis is 0.5 (s- - s+) / (s- - 2 s0 + s+) cell spacings,
// used only when the three scores form a peak (negative curvature) and clamped
// to half a spacing, so a refined pose never leaves its cell. Axes with one
// cell, and cells on the border of the state space, are not refined.
#pragma once

#include <cstdint>
#include <span>

#include "gabarit/roi_point.hpp"
#include "gabarit/table_view.hpp"
#include "gabarit/voter.hpp"

namespace gabarit {

struct SubCellOffset {
  float x = 0.0f;      // pixels in the table frame, added to the cell centre
  float y = 0.0f;
  float theta_deg = 0.0f;
};

// Precondition: counters hold this frame's votes (voter_counter_count cells), cell < cell_count.
SubCellOffset refine_within_cell(const TableView& table, std::span<const VoteCounter> counters, std::uint32_t cell) noexcept;

// The other way: a least-squares alignment of the frame's features to the
// model. The model points of the cell's depth, placed by the cell's centre
// (rotated by its angle, translated by its x, y), are each matched to the
// nearest feature within kAlignRadius pixels; the offset (x, y, theta about
// the reference point) minimising the matched pairs' squared distances, by
// two Gauss-Newton steps of the 3x3 normal equations (fixed-size Eigen), is
// clamped to half a cell spacing like the parabola's. `features` are this
// frame's (track_step's scratch.features, ROI coordinates); `occupancy` is
// scratch of at least tracker_mask_bytes(table) bytes, overwritten (the
// tracker's roi_mask, free once the frame is voted). False, with a zero
// offset, when fewer than kAlignMinMatches points find a feature, when the
// scratch is short, or when the pairs do not fix the three unknowns.
inline constexpr int kAlignRadius = 1;
inline constexpr std::uint32_t kAlignMinMatches = 8;
[[nodiscard]] bool refine_by_alignment(const TableView& table, std::span<const RoiPoint> features,
                                       std::span<std::uint8_t> occupancy, std::uint32_t cell, SubCellOffset& out) noexcept;

}  // namespace gabarit
