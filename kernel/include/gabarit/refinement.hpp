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

}  // namespace gabarit
