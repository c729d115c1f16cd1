// Internal to the kernel: the dense voter's inner loop (dense_voter.cpp),
// eight masks added to the bit-sliced counters over every word of cells,
// with a scalar body and, where the build has Google Highway and the CPU a
// SIMD unit (vector_body.hpp), vector bodies that take 2 (SSE4, NEON) or 4
// (AVX2) words at once. Not installed.
//
// The counters are bitwise and a word's carries never reach another word,
// so every body gives the same bits (the test
// DenseVoter.EveryBodyAddsMasksLikeTheScalarBody compares them on every
// width).
#pragma once

#include <cstddef>
#include <cstdint>

#include "vector_body.hpp"

namespace gabarit::dense_lanes {

inline constexpr std::size_t kPlanes = 16;  // count planes: 16-bit counts

// Bit-sliced counters over `words` words of cells: plane b of word w is
// planes[b * words + w], and ones, twos and fours hold the carry-save
// adders' pending bits of weight 1, 2 and 4.
struct SlicedWords {
  std::uint64_t* planes;
  std::uint64_t* ones;
  std::uint64_t* twos;
  std::uint64_t* fours;
  std::size_t words;
};

// Adds masks[0..8) (each `words` words) to the counters with `body`
// (vector_body() in the voter; a body this CPU does not run is not asked).
void add8(const SlicedWords& s, const std::uint64_t* const masks[8], VectorBody body) noexcept;

}  // namespace gabarit::dense_lanes
