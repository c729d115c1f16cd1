// The bounded motion space and its cells. Each axis is "MIN:MAX:CELLS":
// CELLS equal cells whose centres run evenly from MIN to MAX, each as wide as
// the spacing of the centres (one cell needs MIN == MAX and has zero width).
// Cell index order (the tie rule depends on it):
//   index = ((depth * theta_cells + i_theta) * y_cells + i_y) * x_cells + i_x
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "gabarit/table_view.hpp"

namespace gabarit::host {

// Parses "MIN:MAX:CELLS"; throws app::Error naming `what` on bad input.
Axis parse_axis(const std::string& text, const std::string& what);

struct StateSpace {
  Axis x, y, theta;
  std::uint16_t depths = 1;

  std::uint64_t cell_count() const { return std::uint64_t{x.cells} * y.cells * theta.cells * depths; }
  // Bounds of every cell in index order (stencil_size left 0).
  std::vector<CellBounds> cells() const;
};

// [lo, hi] of cell i of an axis.
void axis_cell_bounds(const Axis& axis, std::uint32_t i, float& lo, float& hi);

}  // namespace gabarit::host
