#include "gabarit/voter.hpp"

#include "gabarit/assert.hpp"

#include <type_traits>

namespace gabarit {
namespace {

Status check_counters(const TableView& table, std::span<const VoteCounter> counters) noexcept {
  if (table.cell_count() == 0) return Status::kInvalidArgument;  // a default (unopened) view
  return counters.size() == voter_counter_count(table.cell_count()) ? Status::kOk : Status::kBufferTooSmall;
}

Status check_features(const TableView& table, std::span<const RoiPoint> features) noexcept {
  const std::uint32_t w = table.roi_width();
  const std::uint32_t h = table.roi_height();
  const std::uint32_t bits = table.channel_bits();
  for (const RoiPoint& f : features) {
    if ((std::uint32_t{f.col} >> bits) >= w || f.row >= h) return Status::kFeatureOutOfRoi;
  }
  return Status::kOk;
}

// expand_offsets' output, read as the table's offsets.
struct ExpandedOffsets {
  const std::uint32_t* offsets;
  std::uint32_t begin(std::size_t pixel) const noexcept { return offsets[pixel]; }
  ReferenceRange range(std::size_t pixel) const noexcept { return {offsets[pixel], offsets[pixel + 1]}; }
};

inline void bump(VoteCounter* counters, std::uint32_t cell) noexcept {
  const VoteCounter c = counters[cell];
  counters[cell] = static_cast<VoteCounter>(c + (c != kVoteCounterMax));
}

// Adds `one` (0 or 1) to a counter, saturating, without a branch.
inline void bump_by(VoteCounter* counters, std::uint32_t cell, bool one) noexcept {
  const VoteCounter c = counters[cell];
  counters[cell] = static_cast<VoteCounter>(c + (one & (c != kVoteCounterMax)));
}

// Whether no counter can saturate in this call: a slot's list names a cell
// at most once (TableView::open checks that lists strictly increase), so a
// counter gains at most one vote per slot voted.
bool cannot_saturate(std::span<const VoteCounter> counters, std::size_t slots) noexcept {
  if (slots >= kVoteCounterMax) return false;
  VoteCounter most = 0;
  for (const VoteCounter c : counters) most = c > most ? c : most;  // a loop compilers vectorise
  return most <= kVoteCounterMax - slots;
}

// The first two references of every list are voted without a branch (a
// slot past the list adds 0 to whichever counter its index reads), so the
// short lists of decimated tables cost no mispredicted loop exit; longer
// lists run the loop from their third reference. Where no counter can
// reach the maximum (Saturating false) a vote is a plain increment: the
// same counts, about half the instructions.
template <class Ref, bool Saturating, class Offsets>
void vote_scalar(const TableView& table, const Offsets& offsets, std::span<const RoiPoint> features, VoteCounter* counters,
                 std::uint64_t& votes) noexcept {
  const std::byte* refs = table.references_data();
  const std::uint32_t w = table.roi_width();
  const std::uint32_t references = table.reference_count();
  if (references == 0) return;
  const auto ref_at = [refs, references](std::uint32_t i) {
    const std::uint32_t in_range = i < references ? i : references - 1;
    return static_cast<std::uint32_t>(load_le<Ref>(refs + std::size_t{in_range} * sizeof(Ref)));
  };
  const auto vote_slot = [&](std::uint32_t slot) {
    const ReferenceRange r = offsets.range(slot);
    const std::uint32_t begin = r.begin, end = r.end;
    if constexpr (Saturating) {
      bump_by(counters, ref_at(begin), begin < end);
      bump_by(counters, ref_at(begin + 1), begin + 1 < end);
      for (std::uint32_t i = begin + 2; i < end; ++i) bump(counters, load_le<Ref>(refs + std::size_t{i} * sizeof(Ref)));
    } else {
      counters[ref_at(begin)] = static_cast<VoteCounter>(counters[ref_at(begin)] + (begin < end));
      counters[ref_at(begin + 1)] = static_cast<VoteCounter>(counters[ref_at(begin + 1)] + (begin + 1 < end));
      const auto plain_vote = [&](std::uint32_t i) { ++counters[load_le<Ref>(refs + std::size_t{i} * sizeof(Ref))]; };
      std::uint32_t i = begin + 2;
      for (; i + 4 <= end; i += 4) {  // four at a time: a list names a cell once, and increments commute
        plain_vote(i);
        plain_vote(i + 1);
        plain_vote(i + 2);
        plain_vote(i + 3);
      }
      for (; i < end; ++i) plain_vote(i);
    }
    votes += end - begin;
  };
  const std::uint32_t bits = table.channel_bits();
  if (bits == 0) {
    for (const RoiPoint& f : features) vote_slot(std::uint32_t{f.row} * w + f.col);
    return;
  }
  for (const RoiPoint& f : features) {  // orientation channels: two slots per feature
    const FeatureSlots s = feature_slots(f.col, f.row, w, bits);
    vote_slot(s.first);
    vote_slot(s.second);
  }
}

// vote_scalar for the table's reference width, saturating only where a counter could.
template <class Offsets>
void vote_with(const TableView& table, const Offsets& offsets, std::span<const RoiPoint> features, std::span<VoteCounter> counters,
               std::uint64_t& votes) noexcept {
  const bool plain = cannot_saturate(counters, features.size() << (table.channel_bits() != 0 ? 1 : 0));
  const auto run = [&](auto saturating) {
    switch (table.reference_bytes()) {
      case 1: vote_scalar<std::uint8_t, saturating.value>(table, offsets, features, counters.data(), votes); break;
      case 2: vote_scalar<std::uint16_t, saturating.value>(table, offsets, features, counters.data(), votes); break;
      default: vote_scalar<std::uint32_t, saturating.value>(table, offsets, features, counters.data(), votes); break;
    }
  };
  if (plain) run(std::false_type{});
  else run(std::true_type{});
}

template <class Ref, class Offsets>
void vote_cell_range(const TableView& table, const Offsets& offsets, std::span<const RoiPoint> features, VoteCounter* counters,
                     std::uint32_t cell_begin, std::uint32_t cell_end, std::uint64_t& votes) noexcept {
  const std::byte* refs = table.references_data();
  const std::uint32_t w = table.roi_width();
  const auto ref_at = [refs](std::uint32_t i) { return static_cast<std::uint32_t>(load_le<Ref>(refs + std::size_t{i} * sizeof(Ref))); };
  const std::uint32_t bits = table.channel_bits();
  const auto vote_slot = [&](std::uint32_t slot) {
    const ReferenceRange r = offsets.range(slot);
    std::uint32_t lo = r.begin;
    const std::uint32_t end = r.end;
    // First reference >= cell_begin (lists are strictly increasing).
    std::uint32_t hi = end;
    while (lo < hi) {
      const std::uint32_t mid = lo + (hi - lo) / 2;
      if (ref_at(mid) < cell_begin) lo = mid + 1;
      else hi = mid;
    }
    std::uint32_t i = lo;
    for (; i < end; ++i) {
      const std::uint32_t cell = ref_at(i);
      if (cell >= cell_end) break;
      bump(counters, cell);
    }
    votes += i - lo;
  };
  for (const RoiPoint& f : features) {
    const FeatureSlots s = feature_slots(f.col, f.row, w, bits);
    vote_slot(s.first);
    if (s.two) vote_slot(s.second);
  }
}

}  // namespace

Status accumulate_votes_for_cells(const TableView& table, std::span<const RoiPoint> features, std::span<VoteCounter> counters,
                                  std::uint32_t cell_begin, std::uint32_t cell_end, VoteTally& tally) noexcept {
  GABARIT_TRY(check_counters(table, counters));
  GABARIT_TRY(check_features(table, features));
  if (cell_begin > cell_end || cell_end > table.cell_count()) return Status::kInvalidArgument;
  table.with_offsets([&](const auto& offsets) {
    switch (table.reference_bytes()) {
      case 1: vote_cell_range<std::uint8_t>(table, offsets, features, counters.data(), cell_begin, cell_end, tally.votes); break;
      case 2: vote_cell_range<std::uint16_t>(table, offsets, features, counters.data(), cell_begin, cell_end, tally.votes); break;
      default: vote_cell_range<std::uint32_t>(table, offsets, features, counters.data(), cell_begin, cell_end, tally.votes); break;
    }
  });
  return Status::kOk;
}

Status clear_counters(const TableView& table, std::span<VoteCounter> counters) noexcept {
  GABARIT_TRY(check_counters(table, counters));
  for (VoteCounter& c : counters) c = 0;
  return Status::kOk;
}

Status accumulate_votes(const TableView& table, std::span<const RoiPoint> features,
                        std::span<VoteCounter> counters, VoteTally& tally) noexcept {
  GABARIT_TRY(check_counters(table, counters));
  GABARIT_TRY(check_features(table, features));
  table.with_offsets([&](const auto& offsets) { vote_with(table, offsets, features, counters, tally.votes); });
  tally.features += static_cast<std::uint32_t>(features.size());
  return Status::kOk;
}

Status expand_offsets(const TableView& table, std::span<std::uint32_t> expanded) noexcept {
  if (table.cell_count() == 0) return Status::kInvalidArgument;
  if (expanded.size() != expanded_offsets_count(table)) return Status::kBufferTooSmall;
  table.with_offsets([&](const auto& offsets) {
    for (std::uint32_t p = 0; p <= table.roi_slots(); ++p) expanded[p] = offsets.begin(p);
  });
  return Status::kOk;
}

Status accumulate_votes_expanded(const TableView& table, std::span<const std::uint32_t> expanded, std::span<const RoiPoint> features,
                                 std::span<VoteCounter> counters, VoteTally& tally) noexcept {
  GABARIT_TRY(check_counters(table, counters));
  GABARIT_TRY(check_features(table, features));
  if (expanded.size() != expanded_offsets_count(table)) return Status::kBufferTooSmall;
  GABARIT_ASSERT(expanded.front() == 0 && expanded.back() == table.reference_count());
  vote_with(table, ExpandedOffsets{expanded.data()}, features, counters, tally.votes);
  tally.features += static_cast<std::uint32_t>(features.size());
  return Status::kOk;
}

Status select_top_cells(const TableView& table, std::span<const VoteCounter> counters,
                        std::span<CellScore> top) noexcept {
  GABARIT_TRY(check_counters(table, counters));
  if (top.empty() || top.size() > table.cell_count()) return Status::kInvalidArgument;
  // Cells arrive in increasing index order, so a cell equal to one already
  // held never displaces it: ties keep the lowest index.
  std::size_t filled = 0;
  const auto insert = [&](const CellScore& s) {
    std::size_t at = filled < top.size() ? filled++ : filled - 1;
    while (at > 0 && ranks_before(s, top[at - 1])) {
      top[at] = top[at - 1];
      --at;
    }
    top[at] = s;
  };
  const std::uint32_t cells = table.cell_count();
  std::uint32_t cell = 0;
  for (; cell < cells && filled < top.size(); ++cell) insert({cell, counters[cell], table.stencil_size(cell)});
  // Then most cells rank below the last held one, and ranks_before(s, last)
  // is s.votes * last's size > last's votes * s's size (sizes guarded as
  // ranks_before guards them): its two terms kept in registers.
  const auto guarded = [](std::uint32_t size) { return std::uint64_t{size == 0 ? 1u : size}; };
  std::uint64_t last_votes = top[filled - 1].votes, last_size = guarded(top[filled - 1].stencil_size);
  for (; cell < cells; ++cell) {
    const CellScore s{cell, counters[cell], table.stencil_size(cell)};
    if (std::uint64_t{s.votes} * last_size <= last_votes * guarded(s.stencil_size)) continue;
    insert(s);
    last_votes = top[filled - 1].votes;
    last_size = guarded(top[filled - 1].stencil_size);
  }
  return Status::kOk;
}

CellScore best_cell_in(const TableView& table, std::span<const VoteCounter> counters, CellRange range) noexcept {
  GABARIT_ASSERT(range.begin <= range.end && range.end <= table.cell_count() && counters.size() >= range.end);
  if (range.begin == range.end) return {kNoCell, 0, 0};
  CellScore best{range.begin, counters[range.begin], table.stencil_size(range.begin)};
  // Cells in increasing index order: ranks_before(s, best) is s.votes *
  // best's size > best's votes * s's size (a tie keeps the lower index),
  // its two terms kept in registers.
  const auto guarded = [](std::uint32_t size) { return std::uint64_t{size == 0 ? 1u : size}; };
  std::uint64_t best_votes = best.votes, best_size = guarded(best.stencil_size);
  for (std::uint32_t c = range.begin + 1; c < range.end; ++c) {
    const CellScore s{c, counters[c], table.stencil_size(c)};
    if (std::uint64_t{s.votes} * best_size <= best_votes * guarded(s.stencil_size)) continue;
    best = s;
    best_votes = s.votes;
    best_size = guarded(s.stencil_size);
  }
  return best;
}

}  // namespace gabarit
