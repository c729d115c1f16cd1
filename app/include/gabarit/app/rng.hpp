// The project's one pseudo-random generator: SplitMix64 (Steele, Lea, Flood
// 2014). Integer-only, so every target and compiler produces the same stream
// for a seed — the determinism tables and synthetic sequences promise.
#pragma once

#include <cstdint>

namespace gabarit::app {

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(seed) {}

  std::uint64_t next_u64() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  std::uint32_t next_u32() { return static_cast<std::uint32_t>(next_u64() >> 32); }
  // Uniform in [0, 1) with 53 random bits.
  double next_unit() { return static_cast<double>(next_u64() >> 11) * 0x1.0p-53; }
  // Uniform integer in [lo, hi] (inclusive); lo <= hi. Lemire's multiply-shift
  // (the bias for spans far below 2^32 is negligible and, above all, fixed).
  std::int32_t uniform_int(std::int32_t lo, std::int32_t hi) {
    const std::uint64_t span = static_cast<std::uint64_t>(static_cast<std::int64_t>(hi) - lo) + 1;
    return static_cast<std::int32_t>(lo + static_cast<std::int64_t>((next_u32() * span) >> 32));
  }
  // True with probability p (p in [0, 1]), decided on an integer threshold.
  bool bernoulli(double p) {
    const auto threshold = static_cast<std::uint64_t>(p * 4294967296.0);
    return next_u32() < threshold;
  }

 private:
  std::uint64_t state_;
};

}  // namespace gabarit::app
