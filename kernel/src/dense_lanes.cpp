// The dense voter's eight-mask step (dense_lanes.hpp), with vector bodies
// through Google Highway where the build has it (GABARIT_HIGHWAY; the same
// targets as canny_rows.cpp, and the same header-only use).
#include "dense_lanes.hpp"

#if defined(GABARIT_HIGHWAY)
#include "highway_targets.hpp"
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "dense_lanes.cpp"
#include <hwy/foreach_target.h>  // re-includes this file once per target
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace gabarit::dense_lanes {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// Carry-save adder: (high, low) = a + b + c, bitwise.
template <class V>
HWY_INLINE void csa(V& high, V& low, V a, V b, V c) {
  const V u = hn::Xor(a, b);
  high = hn::Or(hn::And(a, b), hn::And(u, c));
  low = hn::Xor(u, c);
}

// The scalar body's step (dense_voter.cpp's order of adders) for the
// Lanes(d) words from w: the adders' state loaded, updated and stored, and
// the eights rippled into the planes until no lane carries.
template <class D>
HWY_INLINE void add8_at(D d, const SlicedWords& s, const std::uint64_t* const m[8], std::size_t w) {
  auto ones = hn::LoadU(d, s.ones + w), twos = hn::LoadU(d, s.twos + w), fours = hn::LoadU(d, s.fours + w);
  hn::Vec<D> twos_a, twos_b, fours_a, fours_b, eights;
  csa(twos_a, ones, ones, hn::LoadU(d, m[0] + w), hn::LoadU(d, m[1] + w));
  csa(twos_b, ones, ones, hn::LoadU(d, m[2] + w), hn::LoadU(d, m[3] + w));
  csa(fours_a, twos, twos, twos_a, twos_b);
  csa(twos_a, ones, ones, hn::LoadU(d, m[4] + w), hn::LoadU(d, m[5] + w));
  csa(twos_b, ones, ones, hn::LoadU(d, m[6] + w), hn::LoadU(d, m[7] + w));
  csa(fours_b, twos, twos, twos_a, twos_b);
  csa(eights, fours, fours, fours_a, fours_b);
  hn::StoreU(ones, d, s.ones + w);
  hn::StoreU(twos, d, s.twos + w);
  hn::StoreU(fours, d, s.fours + w);
  // A plane past the last lane's carry is left as it is: adding zeros
  // changes nothing, so stopping when every lane is zero is the scalar
  // body's per-word stop.
  const auto zero = hn::Zero(d);
  auto carry = eights;
  for (std::size_t b = 3; b < kPlanes && !hn::AllTrue(d, hn::Eq(carry, zero)); ++b) {
    std::uint64_t* plane = s.planes + b * s.words + w;
    const auto p = hn::LoadU(d, plane);
    hn::StoreU(hn::Xor(p, carry), d, plane);
    carry = hn::And(p, carry);
  }
}

// The words done: whole vectors, then (AVX2) a half vector of two words.
std::size_t add8_vector(const SlicedWords& s, const std::uint64_t* const m[8]) {
  const hn::ScalableTag<std::uint64_t> d;
  const std::size_t lanes = hn::Lanes(d);
  std::size_t w = 0;
  for (; w + lanes <= s.words; w += lanes) add8_at(d, s, m, w);
  if (lanes > 2) {
    const hn::CappedTag<std::uint64_t, 2> half;
    for (; w + 2 <= s.words; w += 2) add8_at(half, s, m, w);
  }
  return w;
}

}  // namespace HWY_NAMESPACE
}  // namespace gabarit::dense_lanes
HWY_AFTER_NAMESPACE();
#endif  // GABARIT_HIGHWAY

#if !defined(GABARIT_HIGHWAY) || HWY_ONCE
namespace gabarit::dense_lanes {
namespace {

// Carry-save adder: (high, low) = a + b + c, bitwise.
inline void csa(std::uint64_t& high, std::uint64_t& low, std::uint64_t a, std::uint64_t b, std::uint64_t c) noexcept {
  const std::uint64_t u = a ^ b;
  high = (a & b) | (u & c);
  low = u ^ c;
}

// The scalar body, words [from, s.words): eight masks through the adders
// (Harley-Seal), then their eights rippled into the planes from plane 3.
void add8_scalar(const SlicedWords& s, const std::uint64_t* const m[8], std::size_t from) noexcept {
  for (std::size_t w = from; w < s.words; ++w) {
    std::uint64_t twos_a, twos_b, fours_a, fours_b, eights;
    csa(twos_a, s.ones[w], s.ones[w], m[0][w], m[1][w]);
    csa(twos_b, s.ones[w], s.ones[w], m[2][w], m[3][w]);
    csa(fours_a, s.twos[w], s.twos[w], twos_a, twos_b);
    csa(twos_a, s.ones[w], s.ones[w], m[4][w], m[5][w]);
    csa(twos_b, s.ones[w], s.ones[w], m[6][w], m[7][w]);
    csa(fours_b, s.twos[w], s.twos[w], twos_a, twos_b);
    csa(eights, s.fours[w], s.fours[w], fours_a, fours_b);
    for (std::size_t b = 3; eights != 0 && b < kPlanes; ++b) {
      std::uint64_t& plane = s.planes[b * s.words + w];
      const std::uint64_t next = plane & eights;
      plane ^= eights;
      eights = next;
    }
  }
}

}  // namespace

void add8(const SlicedWords& s, const std::uint64_t* const masks[8], [[maybe_unused]] VectorBody body) noexcept {
  std::size_t done = 0;
  switch (body) {
#if defined(GABARIT_HIGHWAY) && defined(__x86_64__)
    case VectorBody::kAvx2: done = N_AVX2::add8_vector(s, masks); break;
    case VectorBody::kSse4: done = N_SSE4::add8_vector(s, masks); break;
#elif defined(GABARIT_HIGHWAY) && HWY_TARGET == HWY_NEON
    case VectorBody::kNeon: done = N_NEON::add8_vector(s, masks); break;
#endif
    default: break;
  }
  add8_scalar(s, masks, done);
}

}  // namespace gabarit::dense_lanes
#endif
