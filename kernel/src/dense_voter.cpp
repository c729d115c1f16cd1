#include "gabarit/dense_voter.hpp"

#include "dense_lanes.hpp"

namespace gabarit {
namespace {

using dense_lanes::kPlanes;
constexpr std::uint32_t kBlock = 65535;  // features per block: counts fit 16 planes

// Bit-sliced counters for W words of cells. Layout of scratch:
// planes[kPlanes][W], ones[W], twos[W], fours[W].
class SlicedCounters {
 public:
  SlicedCounters(std::span<std::uint64_t> scratch, std::size_t words) noexcept
      : planes_(scratch.data()), ones_(planes_ + kPlanes * words), twos_(ones_ + words), fours_(twos_ + words), words_(words) {
    for (std::size_t i = 0; i < 19 * words; ++i) scratch[i] = 0;
  }

  // Adds eight masks (each `words_` words) with `body` (dense_lanes.hpp).
  void add8(const std::uint64_t* const m[8], VectorBody body) noexcept {
    dense_lanes::add8(dense_lanes::SlicedWords{planes_, ones_, twos_, fours_, words_}, m, body);
  }

  void add1(const std::uint64_t* m) noexcept {
    for (std::size_t w = 0; w < words_; ++w) ripple(w, m[w], 0);
  }

  // Adds the block's counts to `counters` with saturation, clears the block
  // and returns the block's total count (references read).
  std::uint64_t flush(std::span<VoteCounter> counters) noexcept {
    for (std::size_t w = 0; w < words_; ++w) {
      ripple(w, ones_[w], 0);
      ripple(w, twos_[w], 1);
      ripple(w, fours_[w], 2);
      ones_[w] = twos_[w] = fours_[w] = 0;
    }
    // Counts are usually far below 2^16: decode only the planes in use.
    std::size_t used = 0;
    for (std::size_t b = 0; b < kPlanes; ++b)
      for (std::size_t w = 0; w < words_; ++w)
        if (planes_[b * words_ + w] != 0) used = b + 1;
    std::uint64_t total = 0;
    for (std::size_t cell = 0; cell < counters.size(); ++cell) {
      const std::size_t w = cell / 64, bit = cell % 64;
      std::uint32_t value = 0;
      for (std::size_t b = 0; b < used; ++b) value |= static_cast<std::uint32_t>((planes_[b * words_ + w] >> bit) & 1u) << b;
      total += value;
      const std::uint32_t sum = counters[cell] + value;
      counters[cell] = static_cast<VoteCounter>(sum > kVoteCounterMax ? kVoteCounterMax : sum);
    }
    for (std::size_t i = 0; i < kPlanes * words_; ++i) planes_[i] = 0;
    return total;
  }

 private:
  // Adds `carry` (one bit per cell) with weight 2^from to the count planes.
  void ripple(std::size_t w, std::uint64_t carry, std::size_t from) noexcept {
    for (std::size_t b = from; carry != 0 && b < kPlanes; ++b) {
      std::uint64_t& plane = planes_[b * words_ + w];
      const std::uint64_t next = plane & carry;
      plane ^= carry;
      carry = next;
    }
  }

  std::uint64_t* planes_;
  std::uint64_t* ones_;
  std::uint64_t* twos_;
  std::uint64_t* fours_;
  std::size_t words_;
};

Status check(const TableView& table, std::span<const std::uint64_t> masks, std::span<VoteCounter> counters,
             std::span<std::uint64_t> scratch) noexcept {
  if (table.cell_count() == 0 || table.cell_count() > kDenseMaxCells) return Status::kInvalidArgument;
  if (masks.size() != dense_mask_words(table.roi_slots(), table.cell_count()) ||
      counters.size() != voter_counter_count(table.cell_count()) ||
      scratch.size() < dense_scratch_words(table.cell_count())) {
    return Status::kBufferTooSmall;
  }
  return Status::kOk;
}

}  // namespace

Status build_dense_masks(const TableView& table, std::span<std::uint64_t> masks) noexcept {
  if (table.cell_count() == 0 || table.cell_count() > kDenseMaxCells) return Status::kInvalidArgument;
  const std::size_t words = dense_words_per_pixel(table.cell_count());
  if (masks.size() != dense_mask_words(table.roi_slots(), table.cell_count())) return Status::kBufferTooSmall;
  for (std::uint64_t& m : masks) m = 0;
  for (std::uint32_t p = 0; p < table.roi_slots(); ++p) {  // one mask per slot (pixel, or pixel and channel)
    for (std::uint32_t i = table.references_begin(p); i < table.references_begin(p + 1); ++i) {
      const std::uint32_t cell = table.reference(i);
      masks[p * words + cell / 64] |= std::uint64_t{1} << (cell % 64);
    }
  }
  return Status::kOk;
}

Status accumulate_votes_dense(const TableView& table, std::span<const std::uint64_t> masks,
                              std::span<const RoiPoint> features, std::span<VoteCounter> counters,
                              std::span<std::uint64_t> scratch, VoteTally& tally) noexcept {
  GABARIT_TRY(check(table, masks, counters, scratch));
  const std::uint32_t w = table.roi_width(), h = table.roi_height(), bits = table.channel_bits();
  for (const RoiPoint& f : features) {
    if ((std::uint32_t{f.col} >> bits) >= w || f.row >= h) return Status::kFeatureOutOfRoi;
  }
  const std::size_t words = dense_words_per_pixel(table.cell_count());
  // Items: one mask per feature, or with orientation channels two (its
  // channel's slot, then the neighbour's), in the CSR voter's order.
  const std::size_t items = features.size() << (bits != 0 ? 1 : 0);
  const auto mask_of = [&](std::size_t item) {
    if (bits == 0) return masks.data() + (std::size_t{features[item].row} * w + features[item].col) * words;
    const RoiPoint& f = features[item >> 1];
    const FeatureSlots s = feature_slots(f.col, f.row, w, bits);
    return masks.data() + std::size_t{(item & 1) ? s.second : s.first} * words;
  };
  SlicedCounters sliced(scratch, words);
  const VectorBody body = vector_body();
  std::uint64_t votes = 0;
  for (std::size_t start = 0; start < items; start += kBlock) {
    const std::size_t end = start + kBlock < items ? start + kBlock : items;
    std::size_t i = start;
    for (; i + 8 <= end; i += 8) {
      const std::uint64_t* m[8];
      for (int k = 0; k < 8; ++k) m[k] = mask_of(i + static_cast<std::size_t>(k));
      sliced.add8(m, body);
    }
    for (; i < end; ++i) sliced.add1(mask_of(i));
    votes += sliced.flush(counters);
  }
  tally.features += static_cast<std::uint32_t>(features.size());
  tally.votes += votes;
  return Status::kOk;
}

}  // namespace gabarit
