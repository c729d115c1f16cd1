// Sine, cosine and rounding built from IEEE-754 single-precision +, -, * only,
// so every target (x86-64, aarch64, armhf, Cortex-M with or without an FPU)
// gets the same bits. libm's sinf differs between glibc and newlib in the last
// place, which would make poses differ across targets. The kernel is built
// with -ffp-contract=off for the same reason (no fused multiply-add).
#pragma once

#include <cstdint>

namespace gabarit {

// The kernel's one finiteness check: not NaN, not infinite.
constexpr bool is_finite(float v) noexcept { return v == v && v - v == 0.0f; }
// -limit < v < limit (false for NaN).
constexpr bool within_limit(float v, float limit) noexcept { return v > -limit && v < limit; }

// Rounds to the nearest integer, halves away from zero. Precondition: |x| < 2^30.
constexpr std::int32_t round_to_int(float x) noexcept {
  return static_cast<std::int32_t>(x >= 0.0f ? x + 0.5f : x - 0.5f);
}

struct SinCos {
  float sin = 0.0f;
  float cos = 1.0f;
};

// sin and cos of an angle in degrees (|error| < 1e-6 for |deg| <= 1e5).
constexpr SinCos sin_cos_deg(float deg) noexcept {
  const std::int32_t quadrant = round_to_int(deg / 90.0f);
  const float r = (deg - static_cast<float>(quadrant) * 90.0f) * 0.017453292519943295f;  // [-pi/4, pi/4]
  const float r2 = r * r;
  const float s = r * (1.0f + r2 * (-1.0f / 6 + r2 * (1.0f / 120 + r2 * (-1.0f / 5040 + r2 * (1.0f / 362880)))));
  const float c = 1.0f + r2 * (-0.5f + r2 * (1.0f / 24 + r2 * (-1.0f / 720 + r2 * (1.0f / 40320))));
  switch (quadrant & 3) {
    case 0: return {s, c};
    case 1: return {c, -s};
    case 2: return {-s, -c};
    default: return {-c, s};
  }
}

// An angle in degrees brought into (-180, 180].
constexpr float wrap_degrees(float deg) noexcept {
  while (deg > 180.0f) deg -= 360.0f;
  while (deg <= -180.0f) deg += 360.0f;
  return deg;
}

}  // namespace gabarit
