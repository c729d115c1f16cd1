// The rows path's per-pixel loops (canny_rows.hpp). With Google Highway
// (GABARIT_HIGHWAY, set by kernel/CMakeLists.txt where hwy/highway.h is found
// and the target has a SIMD unit worth it) the vector bodies are compiled:
// on x86-64 for AVX2 and SSE4, chosen at run time from the CPU (the
// baseline x86-64 has neither, and a binary must still run there: the
// scalar body then); on AArch64 for NEON, which every AArch64 core has
// (vector_body.hpp chooses). Highway is used header-only, its dispatch table
// left out, so the static library needs no libhwy at link time.
#include "canny_rows.hpp"
#include "vector_body.hpp"

#if defined(GABARIT_HIGHWAY)
#include "highway_targets.hpp"
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "canny_rows.cpp"
#include <hwy/foreach_target.h>  // re-includes this file once per target
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace gabarit::canny_rows {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// Pixels p[0 .. lanes) widened to 16-bit lanes.
template <class D>
HWY_INLINE hn::Vec<D> widened(D d, const std::uint8_t* p) {
  const hn::Rebind<std::uint8_t, D> bytes;
  return hn::PromoteTo(d, hn::LoadU(bytes, p));
}

// A Sobel component is at most 4 * 255 = 1020 in magnitude, |gx| + |gy| at
// most 2040: 16-bit lanes hold every intermediate exactly.
std::size_t sobel_magnitudes_vector(const std::uint8_t* up, const std::uint8_t* mid, const std::uint8_t* down,
                                    std::size_t count, std::uint16_t* out) {
  const hn::ScalableTag<std::int16_t> d;
  const hn::RebindToUnsigned<decltype(d)> du;
  const std::size_t lanes = hn::Lanes(d);
  std::size_t i = 0;
  for (; i + lanes <= count; i += lanes) {
    const auto ul = widened(d, up + i - 1), uc = widened(d, up + i), ur = widened(d, up + i + 1);
    const auto ml = widened(d, mid + i - 1), mr = widened(d, mid + i + 1);
    const auto dl = widened(d, down + i - 1), dc = widened(d, down + i), dr = widened(d, down + i + 1);
    const auto gx = hn::Sub(hn::Add(hn::Add(ur, dr), hn::Add(mr, mr)), hn::Add(hn::Add(ul, dl), hn::Add(ml, ml)));
    const auto gy = hn::Sub(hn::Add(hn::Add(dl, dr), hn::Add(dc, dc)), hn::Add(hn::Add(ul, ur), hn::Add(uc, uc)));
    hn::StoreU(hn::BitCast(du, hn::Add(hn::Abs(gx), hn::Abs(gy))), du, out + i);
  }
  return i;  // the columns done; the scalar body does the rest
}

// a >= b and a <= b (Highway 1.0 compares integers with < and > only).
template <class V>
HWY_INLINE auto at_least(V a, V b) {
  return hn::Not(hn::Lt(a, b));
}
template <class V>
HWY_INLINE auto at_most(V a, V b) {
  return hn::Not(hn::Gt(a, b));
}

// Magnitudes (at most 2040) as signed 16-bit lanes.
template <class D>
HWY_INLINE hn::Vec<D> magnitudes(D d, const std::uint16_t* p) {
  return hn::LoadU(d, reinterpret_cast<const std::int16_t*>(p));
}

// canny_keeps (features.cpp) lane by lane, its branches as selections; the
// direction test by horizontal_limit and vertical_limit (canny_rows.hpp).
template <class D>
HWY_INLINE hn::Mask<D> decide_lanes(D d, const DecisionRow& r, std::size_t c) {
  const hn::RebindToUnsigned<D> du;
  const auto m = magnitudes(d, r.at + c);
  const auto left = magnitudes(d, r.at + c - 1), right = magnitudes(d, r.at + c + 1);
  const auto above_left = magnitudes(d, r.above + c - 1), above = magnitudes(d, r.above + c);
  const auto above_right = magnitudes(d, r.above + c + 1);
  const auto below_left = magnitudes(d, r.below + c - 1), below = magnitudes(d, r.below + c);
  const auto below_right = magnitudes(d, r.below + c + 1);
  const auto ul = widened(d, r.up + c - 1), uc = widened(d, r.up + c), ur = widened(d, r.up + c + 1);
  const auto ml = widened(d, r.mid + c - 1), mr = widened(d, r.mid + c + 1);
  const auto dl = widened(d, r.down + c - 1), dc = widened(d, r.down + c), dr = widened(d, r.down + c + 1);
  const auto gx = hn::Sub(hn::Add(hn::Add(ur, dr), hn::Add(mr, mr)), hn::Add(hn::Add(ul, dl), hn::Add(ml, ml)));
  const auto gy = hn::Sub(hn::Add(hn::Add(dl, dr), hn::Add(dc, dc)), hn::Add(hn::Add(ul, ur), hn::Add(uc, uc)));
  const auto ax = hn::Abs(gx), ay = hn::Abs(gy);
  const auto high_part = [&](std::uint16_t k) {
    return hn::BitCast(d, hn::MulHigh(hn::BitCast(du, ax), hn::Set(du, k)));
  };
  const auto horizontal_max = hn::ShiftRight<2>(hn::Add(ax, high_part(kHorizontalMultiplier)));
  const auto vertical_part = hn::ShiftRight<2>(hn::Add(ax, high_part(kVerticalMultiplier)));
  const auto vertical_min = hn::Add(hn::Add(hn::Add(ax, ax), vertical_part), hn::Min(ax, hn::Set(d, 1)));
  // Mostly horizontal, else mostly vertical, else diagonal: down-right when
  // gx and gy have the same sign (both > 0 or both <= 0), else up-right.
  const auto horizontal = at_most(ay, horizontal_max);
  const auto vertical = at_least(ay, vertical_min);
  const auto zero = hn::Zero(d);
  const auto same_sign = hn::Not(hn::Xor(hn::Gt(gx, zero), hn::Gt(gy, zero)));
  auto ahead = hn::IfThenElse(same_sign, below_right, above_right);
  auto behind = hn::IfThenElse(same_sign, above_left, below_left);
  ahead = hn::IfThenElse(vertical, below, ahead);
  behind = hn::IfThenElse(vertical, above, behind);
  ahead = hn::IfThenElse(horizontal, right, ahead);
  behind = hn::IfThenElse(horizontal, left, behind);
  const auto neighbours = hn::Max(hn::Max(hn::Max(left, right), hn::Max(above_left, above)),
                                  hn::Max(hn::Max(above_right, below_left), hn::Max(below, below_right)));
  const auto high = hn::Set(d, static_cast<std::int16_t>(r.high > 32767 ? 32767 : r.high));
  const auto strong = hn::Or(at_least(m, high), at_least(neighbours, high));
  const auto maximum = hn::And(at_least(m, ahead), hn::Gt(m, behind));
  return hn::And(hn::And(at_least(m, hn::Set(d, static_cast<std::int16_t>(r.low > 32767 ? 32767 : r.low))), maximum),
                 strong);
}

std::uint64_t decide_vector(const DecisionRow& r, std::size_t begin, std::size_t end, std::size_t& done) {
  const hn::ScalableTag<std::int16_t> d;
  const std::size_t lanes = hn::Lanes(d);
  std::size_t n = end - begin < 64 ? end - begin : 64;
  n -= n % lanes;
  std::uint64_t kept = 0;
  const auto low = hn::Set(d, static_cast<std::int16_t>(r.low > 32767 ? 32767 : r.low));
  for (std::size_t k = 0; k < n; k += lanes) {
    // Most of a ROI is below the low threshold: such lanes need nothing more.
    if (hn::AllFalse(d, at_least(magnitudes(d, r.at + begin + k), low))) continue;
    std::uint8_t bits[8] = {};  // lanes <= 64 bits: AVX2 16, SSE4 and NEON 8
    (void)hn::StoreMaskBits(d, decide_lanes(d, r, begin + k), bits);
    std::uint64_t lane_bits = 0;
    for (std::size_t b = 0; b < (lanes + 7) / 8; ++b) lane_bits |= std::uint64_t{bits[b]} << (8 * b);
    kept |= lane_bits << k;
  }
  done = n;
  return kept;
}

}  // namespace HWY_NAMESPACE
}  // namespace gabarit::canny_rows
HWY_AFTER_NAMESPACE();
#endif  // GABARIT_HIGHWAY

#if !defined(GABARIT_HIGHWAY) || HWY_ONCE
namespace gabarit::canny_rows {

void sobel_magnitudes_scalar(const std::uint8_t* up, const std::uint8_t* mid, const std::uint8_t* down,
                             std::size_t count, std::uint16_t* out) noexcept {
  for (std::size_t i = 0; i < count; ++i) {
    // Column i's neighbours through pointers at it: an index i - 1 would wrap at i = 0.
    const std::uint8_t *u = up + i, *m = mid + i, *d = down + i;
    const std::int32_t gx = (u[1] + 2 * m[1] + d[1]) - (u[-1] + 2 * m[-1] + d[-1]);
    const std::int32_t gy = (d[-1] + 2 * d[0] + d[1]) - (u[-1] + 2 * u[0] + u[1]);
    out[i] = static_cast<std::uint16_t>((gx < 0 ? -gx : gx) + (gy < 0 ? -gy : gy));
  }
}

void sobel_magnitudes(const std::uint8_t* up, const std::uint8_t* mid, const std::uint8_t* down, std::size_t count,
                      std::uint16_t* out) noexcept {
  std::size_t done = 0;
  switch (vector_body()) {
#if defined(GABARIT_HIGHWAY) && defined(__x86_64__)
    case VectorBody::kAvx2: done = N_AVX2::sobel_magnitudes_vector(up, mid, down, count, out); break;
    case VectorBody::kSse4: done = N_SSE4::sobel_magnitudes_vector(up, mid, down, count, out); break;
#elif defined(GABARIT_HIGHWAY) && HWY_TARGET == HWY_NEON
    case VectorBody::kNeon: done = N_NEON::sobel_magnitudes_vector(up, mid, down, count, out); break;
#endif
    default: break;
  }
  sobel_magnitudes_scalar(up + done, mid + done, down + done, count - done, out + done);
}

std::uint64_t decide([[maybe_unused]] const DecisionRow& row, std::size_t begin, std::size_t end,
                     std::size_t& done) noexcept {
  done = 0;
  if (begin >= end) return 0;
  switch (vector_body()) {
#if defined(GABARIT_HIGHWAY) && defined(__x86_64__)
    case VectorBody::kAvx2: return N_AVX2::decide_vector(row, begin, end, done);
    case VectorBody::kSse4: return N_SSE4::decide_vector(row, begin, end, done);
#elif defined(GABARIT_HIGHWAY) && HWY_TARGET == HWY_NEON
    case VectorBody::kNeon: return N_NEON::decide_vector(row, begin, end, done);
#endif
    default: return 0;
  }
}

const char* vector_target() noexcept { return vector_body_name(vector_body()); }

}  // namespace gabarit::canny_rows
#endif
