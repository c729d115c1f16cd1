// Template reduction (the thesis's chapter 4, and its hindsight: "reduce the
// template first"): a subset R of the model's points that still tells every
// translation of the space from the true one by at least a stated
// characterising value (table_analysis.hpp: chi(R) = min over shifts tau != 0
// of |(R + tau) \ M|, the points of R that land off the model M under the
// worst other translation). A table built from R has |R| / |M| of the full
// table's references without decimating a stencil.
//
// Search: the points are taken in an order and each is dropped when every
// shift it tells apart (its moved position off the model) still keeps at
// least min_chi such points without it, so the result is minimal (no single
// point more can go). Orders:
//   greedy     the points that tell the fewest shifts apart go first (ties
//              in a seeded random order);
//   random     `restarts` seeded random orders, the smallest result kept
//              (the randomised search the thesis sketches).
// Deterministic per seed. Translations only: a space with rotation would
// need the rotated, rasterised template, which this does not model.
#pragma once

#include <cstdint>
#include <vector>

#include "gabarit/host/tables/model.hpp"

namespace gabarit::host {

enum class ReductionOrder { kGreedy, kRandom };

struct ReductionResult {
  std::vector<Point> points;           // R, in the model's order
  std::uint32_t characterising_value;  // chi(R) over the shifts
  std::uint32_t full_value;            // chi(M), the most any subset can have
};

// shifts: the translations to tell apart (the identity, if present, is
// ignored). Throws app::Error when min_chi exceeds chi(M).
ReductionResult reduce_template(const std::vector<Point>& model, const std::vector<Point>& shifts, std::uint32_t min_chi,
                                ReductionOrder order, std::uint32_t restarts, std::uint64_t seed);

// Every difference of two cell centres of a translation space (x and y
// axes): the relative moves a frame's estimate can be wrong by.
std::vector<Point> translation_differences(const std::vector<std::int32_t>& x_centres, const std::vector<std::int32_t>& y_centres);

}  // namespace gabarit::host
