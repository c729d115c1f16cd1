// Stencil decimation: removes references at random, each with probability
// proportional to how many stencils cover its pixel (the more overlapped a
// pixel, the less it tells cells apart, the more likely its references go).
//
// With n(p) the number of stencils covering pixel p and R the total number of
// references, every reference at p is removed with probability
// min(1, alpha * n(p)), alpha chosen (by bisection) so the expected number
// removed is (1 - keep) * R. Draws come from the project's integer RNG in a
// fixed order (cell index, then pixel order), so a seed gives the same table
// on every machine.
//
// Uniform decimation removes every reference with probability 1 - keep,
// whatever its overlap. At a few percent kept, overlap decimation can leave a
// cell whose stencil lies in crowded pixels with one or two references, and
// such a cell then wins with a full normalised score on a single vote; uniform
// keeps each stencil near `keep` of its size, which is what a coarse search
// table needs.
#pragma once

#include <cstdint>
#include <vector>

namespace gabarit::host {

// overlap[i] = n(p) of the pixel of reference i (references in table order).
// Returns keep flags, one per reference. keep in (0, 1]; keep == 1 keeps all.
enum class Decimation { kOverlap, kUniform };
std::vector<bool> decimate(const std::vector<std::uint32_t>& overlap, double keep, std::uint64_t seed,
                           Decimation mode = Decimation::kOverlap);

// The alpha above, exposed for tests.
double decimation_alpha(const std::vector<std::uint32_t>& overlap, double keep);

}  // namespace gabarit::host
