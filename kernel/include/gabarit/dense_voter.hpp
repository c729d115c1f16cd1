// Word-parallel voting for tables with few cells (the thesis's spaces have
// 121): every ROI pixel's cell list is expanded once into a bitmask of
// dense_words_per_pixel(cells) 64-bit words, and a frame's votes accumulate in
// bit-sliced counters — bit plane b holds bit b of every cell's count — fed
// through carry-save adders, eight masks at a time (Harley-Seal). There is no
// branch per feature and no read-modify-write per reference. Where the build
// has Google Highway, the adders run over 2 (SSE4, NEON) or 4 (AVX2) words
// at once (kernel/src/dense_lanes.cpp), with the same counters.
//
// Results are bit-identical to accumulate_votes (the CSR voter), including
// saturation: features are taken in blocks of at most 65535, whose counts
// cannot overflow 16 planes, and each block is added to the counters with
// saturation.
//
// Memory (caller-owned):
//   masks:   dense_mask_words(roi_slots, cells) words, filled by build_dense_masks
//   scratch: dense_scratch_words(cells) words
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "gabarit/roi_point.hpp"
#include "gabarit/status.hpp"
#include "gabarit/table_view.hpp"
#include "gabarit/voter.hpp"

namespace gabarit {

// Beyond this many cells the masks grow past the lists they replace and the
// CSR voter is the better choice.
inline constexpr std::uint32_t kDenseMaxCells = 1024;

constexpr std::size_t dense_words_per_pixel(std::uint32_t cells) noexcept { return (std::size_t{cells} + 63) / 64; }
constexpr std::size_t dense_mask_words(std::uint32_t roi_pixels, std::uint32_t cells) noexcept {
  return std::size_t{roi_pixels} * dense_words_per_pixel(cells);
}
// 16 count planes plus the carry-save adders' ones, twos and fours.
constexpr std::size_t dense_scratch_words(std::uint32_t cells) noexcept { return 19 * dense_words_per_pixel(cells); }

// The cost model that picks a voter per table (gabarit track --voter auto,
// gabarit-board). Per feature pixel with r references, the CSR voter costs
// about 1 + 0.5 r (in units of a few ns: the list's bounds, then a counter
// per reference), the dense voter about 0.5 w + 0.2 r for w mask words
// (cells / 64, rounded up; sparser masks ripple fewer carries), so dense
// pays off when w < 2 + 0.6 r. r is estimated as references / ROI pixels,
// what uniformly spread clutter votes. Fitted to the voting times of gabarit
// bench --decimation ("Voting time": 121 to 847 cells, 0.2 to 59 references
// per feature, 20% salt-and-pepper, a 2-core x86-64, CSR with u32 offsets or
// compact ones expanded once, as hosted programs do): it picks the faster
// voter in 19 of those 20 cases and costs 10% over always picking the
// faster. Both voters give the same counters: a wrong guess costs time only.
// Fitted with the scalar body: the vector bodies take about half the dense
// voter's time on the scene suite's 847-cell tables (docs/performance.md,
// "The dense voter in vector lanes"), so on those builds the model picks
// the CSR voter for some tables where dense would now be faster (few
// references per pixel, as decimated tables have); not refitted.
constexpr bool dense_voter_pays_off(std::uint32_t cells, std::uint32_t roi_pixels, std::uint32_t references) noexcept {
  if (cells == 0 || cells > kDenseMaxCells || roi_pixels == 0) return false;
  const std::uint64_t words = dense_words_per_pixel(cells);
  return 5 * words * roi_pixels < 10ull * roi_pixels + 3ull * references;
}
inline bool dense_voter_pays_off(const TableView& table) noexcept {
  return dense_voter_pays_off(table.cell_count(), table.roi_slots(), table.reference_count());
}
static_assert(dense_voter_pays_off(121, 3600, 24000) && dense_voter_pays_off(121, 3600, 100),
              "two mask words: dense whatever the references");
static_assert(!dense_voter_pays_off(605, 3600, 14000) && dense_voter_pays_off(605, 3600, 150000),
              "ten words: CSR for a decimated table, dense at full stencils");

// Expands the table's lists into masks. kInvalidArgument when the table has
// more than kDenseMaxCells cells, kBufferTooSmall for a short buffer.
Status build_dense_masks(const TableView& table, std::span<std::uint64_t> masks) noexcept;

// Adds the votes of `features` to `counters` (one per cell), like accumulate_votes.
Status accumulate_votes_dense(const TableView& table, std::span<const std::uint64_t> masks,
                              std::span<const RoiPoint> features, std::span<VoteCounter> counters,
                              std::span<std::uint64_t> scratch, VoteTally& tally) noexcept;

}  // namespace gabarit
