// The voter: feature pixels in, one counter per cell out, then the best cells.
//
//   votes(U) = |P ∩ S_U|
//
// where P is the set of feature pixels (ROI coordinates) and S_U the (possibly
// decimated) stencil of cell U, read from the table's pixel -> cells lists.
// Each pixel lists a cell at most once, so votes(U) <= |S_U|.
//
// Ranking. Cells are ranked by the normalised score votes(U) / |S_U| (the
// thesis keeps "the stencil that encompasses the most features, relative to
// its size": decimated stencils differ in size). The comparison is exact
// integer arithmetic, a beats b  <=>  votes_a * |S_b| > votes_b * |S_a|, with
// |S| = 0 read as 1 (such a cell can only have 0 votes). Ties resolve to the
// lowest cell index. A hardware voter reproduces this bit for bit.
//
// Counters are 16-bit and saturate at 65535 instead of wrapping (only
// reachable if a caller passes the same feature pixel many times).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "gabarit/roi_point.hpp"
#include "gabarit/status.hpp"
#include "gabarit/table_view.hpp"

namespace gabarit {

using VoteCounter = std::uint16_t;
inline constexpr VoteCounter kVoteCounterMax = 0xFFFF;

// Counters the caller provides: one per cell.
constexpr std::size_t voter_counter_count(std::uint32_t cell_count) noexcept { return cell_count; }

struct CellScore {
  std::uint32_t cell = 0;
  VoteCounter votes = 0;
  std::uint32_t stencil_size = 0;
};

inline constexpr std::uint32_t kNoCell = 0xFFFFFFFFu;

// True if a ranks strictly before b (see the ranking rule above).
constexpr bool ranks_before(const CellScore& a, const CellScore& b) noexcept {
  const std::uint64_t sa = a.stencil_size == 0 ? 1 : a.stencil_size;
  const std::uint64_t sb = b.stencil_size == 0 ? 1 : b.stencil_size;
  const std::uint64_t lhs = std::uint64_t{a.votes} * sb;
  const std::uint64_t rhs = std::uint64_t{b.votes} * sa;
  return lhs > rhs || (lhs == rhs && a.cell < b.cell);
}

// True if a and b have the same normalised score (whatever their indices).
constexpr bool scores_equal(const CellScore& a, const CellScore& b) noexcept {
  const std::uint64_t sa = a.stencil_size == 0 ? 1 : a.stencil_size;
  const std::uint64_t sb = b.stencil_size == 0 ? 1 : b.stencil_size;
  return std::uint64_t{a.votes} * sb == std::uint64_t{b.votes} * sa;
}

inline float normalised_score(const CellScore& s) noexcept {
  return static_cast<float>(s.votes) / static_cast<float>(s.stencil_size == 0 ? 1u : s.stencil_size);
}

struct VoteTally {
  std::uint32_t features = 0;  // feature pixels that voted
  std::uint64_t votes = 0;     // counter increments (references read)
};

// accumulate_votes restricted to the cells in [cell_begin, cell_end): the
// other counters are not touched. Each pixel's list is in increasing cell
// order, so the range is found by binary search. Threads (or cores) that take
// disjoint cell ranges of one counter array never write the same counter, and
// together produce exactly accumulate_votes' counters; `tally.votes` counts
// this range's increments, `tally.features` is not changed.
Status accumulate_votes_for_cells(const TableView& table, std::span<const RoiPoint> features, std::span<VoteCounter> counters,
                                  std::uint32_t cell_begin, std::uint32_t cell_end, VoteTally& tally) noexcept;

// Sets every counter to zero. counters.size() must equal the cell count.
Status clear_counters(const TableView& table, std::span<VoteCounter> counters) noexcept;

// Adds the votes of `features` to `counters` (which must hold
// voter_counter_count(table.cell_count()) entries) and adds to `tally`.
// Every feature is checked to lie inside the ROI before any counter changes,
// so a failed call leaves the counters untouched.
//
// This plain scalar loop over the CSR lists is the reference every other
// voter (dense_voter.hpp, the hardware voter) is tested against bit for bit.
// (A 4-way unrolled variant was measured slower than it on x86-64 and was
// removed.)
Status accumulate_votes(const TableView& table, std::span<const RoiPoint> features,
                        std::span<VoteCounter> counters, VoteTally& tally) noexcept;

// A compact table's offsets (format 1.2) expanded once to one u32 per ROI
// pixel, for a host that votes the table often and has the RAM to spare:
// the CSR voter then skips the compact decode, which costs several ns a
// feature (gabarit bench --decimation, "Voting time"). expand_offsets fills
// expanded_offsets_count(table) entries (kBufferTooSmall otherwise), and
// accumulate_votes_expanded votes exactly as accumulate_votes. Precondition
// of the latter: `expanded` is expand_offsets' output for this table.
inline std::size_t expanded_offsets_count(const TableView& table) noexcept { return std::size_t{table.roi_slots()} + 1; }
Status expand_offsets(const TableView& table, std::span<std::uint32_t> expanded) noexcept;
Status accumulate_votes_expanded(const TableView& table, std::span<const std::uint32_t> expanded, std::span<const RoiPoint> features,
                                 std::span<VoteCounter> counters, VoteTally& tally) noexcept;

// Writes the best `top.size()` cells, best first (1 <= top.size() <= cell
// count). O(cells x k); k is meant to be small (best and runner-up, a few
// candidates for a motion filter).
Status select_top_cells(const TableView& table, std::span<const VoteCounter> counters,
                        std::span<CellScore> top) noexcept;

// The best cell of `range` by the ranking rule (cell kNoCell for an empty
// range). Precondition: range within the cell count, counters hold them.
CellScore best_cell_in(const TableView& table, std::span<const VoteCounter> counters, CellRange range) noexcept;

}  // namespace gabarit
