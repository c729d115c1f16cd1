// Stencils: S_U, the set of integer pixels the model's feature points cover
// when moved by every transformation of cell U = [x_lo,x_hi] x [y_lo,y_hi] x
// [theta_lo,theta_hi] x {n}.
//
//  1. Rotation: each feature point of stack image n is turned into the digital
//     arc it sweeps about the reference point over [theta_lo, theta_hi],
//     sampled so consecutive samples are <= 0.5 px apart at the model's
//     largest radius, rounded to pixels and de-duplicated.
//  2. Translation: that set is swept over the integer translations of the
//     cell. Policy for non-integer bounds ("inside, else closest"): the
//     integers k with lo <= k <= hi; when no integer lies inside (a cell
//     narrower than a pixel), the integer closest to the cell centre. So
//     1-pixel cells centred on integers use exactly that one translation and
//     neighbouring cells do not share translations unless a bound is itself
//     an integer.
#pragma once

#include <cstdint>
#include <vector>

#include "gabarit/host/tables/model.hpp"
#include "gabarit/table_view.hpp"

namespace gabarit::host {

struct IntegerRange {
  std::int32_t first = 0;
  std::int32_t last = 0;  // inclusive
};
// The two policies the thesis discusses for a cell's non-integer bounds:
//   kInsideElseClosest  the integers inside [lo, hi], else the one closest to
//                       the centre (the default: see docs/tracking.md for the
//                       measurement that chose it);
//   kEnclosing          the smallest integer range enclosing [lo, hi],
//                       floor(lo)..ceil(hi): neighbouring cells share their
//                       boundary translations, stencils grow.
enum class TranslationPolicy { kInsideElseClosest, kEnclosing };
IntegerRange integer_translations(float lo, float hi, TranslationPolicy policy = TranslationPolicy::kInsideElseClosest);

// Step 1: the de-duplicated, sorted arc pixels of all points over [lo, hi] degrees.
std::vector<Point> swept_arcs(const std::vector<Point>& points, float theta_lo_deg, float theta_hi_deg);

// Step 2: `arcs` (sorted, without duplicates) swept over the cell's integer
// translations, sorted by (x, y) and without duplicates.
std::vector<Point> translate_sweep(const std::vector<Point>& arcs, const CellBounds& cell,
                                   TranslationPolicy policy = TranslationPolicy::kInsideElseClosest);

}  // namespace gabarit::host
