// Stencil decimation: which references of the full stencils a table keeps.
//
// Notation (the thesis's ch. 5): S is a cell's stencil (a set of ROI
// pixels), array(p) the cells whose stencils still reference pixel p, and
// |array(p)| its overlap. The more stencils cover a pixel, the less it tells
// them apart, so the references that go are drawn where overlap is high.
//
// Methods:
//   kStencil  the thesis's Algorithm 2: stencil by stencil (in cell index
//             order), while the stencil is larger than its target size,
//             remove one of its references drawn with probability
//             g(|array(p)|) / sum over S of g(|array(q)|), and update
//             |array(p)|, so the stencils decimated later see the overlap
//             left by those before. Every stencil keeps keep x its size (at
//             least min_area references), so no cell is emptied.
//   kGlobal   one pass over all references, each removed with probability
//             min(1, alpha * n(p)) where n(p) is the undecimated overlap and
//             alpha is set by bisection so (1 - keep) of them go. Removes
//             much more from the central, crowded stencils of a small shape
//             (the project's method before Algorithm 2; kept for comparison).
//   kUniform  every reference removed with probability 1 - keep.
//
// Policies of kStencil (the thesis's proposed improvements, each optional):
//   weight            g: identity (g(n) = n), power (n^k, k = 2 or 3), or
//                     greedy (always the most overlapped pixel, ties drawn),
//                     or rival (the project's: a pixel weighs by how alike
//                     to S the full stencils sharing it are, 1 + sum of
//                     (|S n S'| / |S|)^2 over them, so removals go where S
//                     is hard to tell from its near rivals; static, not
//                     updated as references go);
//   most_overlapping  remove first the pixels S shares with the full stencil
//                     that overlaps it most: the pixels that tell S from its
//                     nearest rival (S minus that stencil) stay;
//   spread            a neighbourhood map: a pixel's removal weight grows
//                     4-fold with each reference its stencil still keeps
//                     within 2 px of it (up to 6), so removals thin crowded
//                     neighbourhoods first and what stays spreads evenly,
//                     leaving no hole a local occlusion could fill;
//   min_area          no stencil decimated below this many references.
//
// Every draw comes from the project's integer RNG and weights are integers,
// so a seed gives the same table on every machine.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace gabarit::host {

enum class Decimation { kStencil, kGlobal, kUniform };
enum class RemovalWeight { kIdentity, kPower, kGreedy, kRival };

// The default is Algorithm 2 as the thesis states it, identity weights and
// no improvement switched on: within 1.5% of the best policy on the
// held-out shapes of gabarit bench --decimation, and, unlike the spread
// policy (best there), never far worse on the 4-DOF grayscale tables tried
// (docs/experiments.md, "Decimation").
struct DecimationPolicy {
  Decimation method = Decimation::kStencil;
  RemovalWeight weight = RemovalWeight::kIdentity;
  std::uint32_t power = 2;  // kPower: 2 or 3
  bool most_overlapping = false;
  bool spread = false;
  std::uint32_t min_area = 0;
};

// Parses "stencil", "global" (also "overlap", its former name) or "uniform".
// Throws app::UsageError.
Decimation parse_decimation(const std::string& text);
// Parses "identity", "power:K" (K = 2 or 3) or "greedy" into policy.weight/power.
void parse_removal_weight(const std::string& text, DecimationPolicy& policy);
// A one-line description, e.g. "stencil, power:2, most-overlapping, min-area 8".
std::string describe(const DecimationPolicy& policy);

// The stencils to decimate: per cell (in cell order) its ROI pixel indices,
// distinct, in the order the builder lists them.
struct StencilPixels {
  std::vector<std::vector<std::uint32_t>> cells;
  std::uint32_t roi_width = 0, roi_height = 0;
};

// Keep flags, one per reference in (cell, pixel) order. keep in (0, 1];
// keep == 1 keeps everything whatever the policy. Throws app::Error for a
// keep outside (0, 1].
std::vector<bool> decimate(const StencilPixels& stencils, double keep, std::uint64_t seed, const DecimationPolicy& policy);

// kGlobal's alpha, exposed for tests: overlap[i] = n(p) of reference i.
double decimation_alpha(const std::vector<std::uint32_t>& overlap, double keep);

}  // namespace gabarit::host
