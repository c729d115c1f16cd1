#include "gabarit/host/tables/state_space.hpp"

#include <cmath>
#include <cstdlib>

#include "gabarit/app/error.hpp"
#include "gabarit/table_format.hpp"

namespace gabarit::host {

Axis parse_axis(const std::string& text, const std::string& what) {
  const auto bad = [&](const std::string& why) { return app::Error(what + " '" + text + "': " + why + " (want MIN:MAX:CELLS)"); };
  const std::size_t a = text.find(':');
  const std::size_t b = a == std::string::npos ? a : text.find(':', a + 1);
  if (b == std::string::npos || text.find(':', b + 1) != std::string::npos) throw bad("need three fields");
  const std::string smin = text.substr(0, a), smax = text.substr(a + 1, b - a - 1), scells = text.substr(b + 1);
  char* end = nullptr;
  const double mn = std::strtod(smin.c_str(), &end);
  if (smin.empty() || *end) throw bad("MIN is not a number");
  const double mx = std::strtod(smax.c_str(), &end);
  if (smax.empty() || *end) throw bad("MAX is not a number");
  const long cells = std::strtol(scells.c_str(), &end, 10);
  if (scells.empty() || *end || cells < 1) throw bad("CELLS must be a positive integer");
  // The table format's limits (docs/table-format.md, "Limits"): pixels for
  // x and y, degrees for theta.
  const bool angle = what.find("theta") != std::string::npos;
  const double limit = angle ? table_format::kMaxAxisDegrees : table_format::kMaxAxisPixels;
  if (!std::isfinite(mn) || !std::isfinite(mx) || std::fabs(mn) > limit || std::fabs(mx) > limit) {
    throw bad("MIN and MAX must lie within +-" + std::to_string(static_cast<int>(limit)) + (angle ? " degrees" : " pixels"));
  }
  if (cells > 4096) throw bad("at most 4096 cells per axis");
  if (mn > mx) throw bad("MIN > MAX");
  // The table stores the bounds in single precision: compare them as stored.
  const auto fmin = static_cast<float>(mn), fmax = static_cast<float>(mx);
  if (cells == 1 && fmin != fmax) throw bad("one cell needs MIN == MAX (its centre)");
  if (cells > 1 && fmin == fmax) throw bad("several cells need MIN < MAX (as 32-bit floats)");
  return {fmin, fmax, static_cast<std::uint32_t>(cells)};
}

void axis_cell_bounds(const Axis& axis, std::uint32_t i, float& lo, float& hi) {
  if (axis.cells == 1) {
    lo = hi = axis.min;
    return;
  }
  const double step = (static_cast<double>(axis.max) - axis.min) / (axis.cells - 1);
  const double centre = axis.min + step * i;
  lo = static_cast<float>(centre - step / 2);
  hi = static_cast<float>(centre + step / 2);
}

std::vector<CellBounds> StateSpace::cells() const {
  std::vector<CellBounds> out;
  out.reserve(static_cast<std::size_t>(cell_count()));
  for (std::uint16_t d = 0; d < depths; ++d)
    for (std::uint32_t it = 0; it < theta.cells; ++it)
      for (std::uint32_t iy = 0; iy < y.cells; ++iy)
        for (std::uint32_t ix = 0; ix < x.cells; ++ix) {
          CellBounds c;
          axis_cell_bounds(x, ix, c.x_lo, c.x_hi);
          axis_cell_bounds(y, iy, c.y_lo, c.y_hi);
          axis_cell_bounds(theta, it, c.theta_lo_deg, c.theta_hi_deg);
          c.depth = d;
          out.push_back(c);
        }
  return out;
}

}  // namespace gabarit::host
