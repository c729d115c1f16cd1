#include "gabarit/host/decimation.hpp"

#include <algorithm>

#include "gabarit/app/error.hpp"
#include "gabarit/host/rng.hpp"

namespace gabarit::host {

double decimation_alpha(const std::vector<std::uint32_t>& overlap, double keep) {
  // Histogram of n(p) per reference makes each bisection step O(max n).
  std::uint32_t max_n = 0;
  for (std::uint32_t n : overlap) max_n = std::max(max_n, n);
  std::vector<double> refs_with(max_n + 1, 0.0);
  for (std::uint32_t n : overlap) refs_with[n] += 1;
  const double target = (1.0 - keep) * static_cast<double>(overlap.size());
  const auto removed = [&](double alpha) {
    double sum = 0;
    for (std::uint32_t n = 1; n <= max_n; ++n) sum += refs_with[n] * std::min(1.0, alpha * n);
    return sum;
  };
  double lo = 0, hi = 1;  // alpha = 1 removes everything (n >= 1)
  for (int i = 0; i < 100; ++i) {
    const double mid = (lo + hi) / 2;
    (removed(mid) < target ? lo : hi) = mid;
  }
  return hi;
}

std::vector<bool> decimate(const std::vector<std::uint32_t>& overlap, double keep, std::uint64_t seed, Decimation mode) {
  if (!(keep > 0.0) || keep > 1.0) throw app::Error("--keep must be in (0, 1]");
  std::vector<bool> kept(overlap.size(), true);
  if (keep == 1.0 || overlap.empty()) return kept;
  if (mode == Decimation::kUniform) {
    Rng rng(seed);
    for (std::size_t i = 0; i < overlap.size(); ++i)
      if (rng.bernoulli(1.0 - keep)) kept[i] = false;
    return kept;
  }
  const double alpha = decimation_alpha(overlap, keep);
  Rng rng(seed);
  for (std::size_t i = 0; i < overlap.size(); ++i) {
    if (rng.bernoulli(std::min(1.0, alpha * overlap[i]))) kept[i] = false;
  }
  return kept;
}

}  // namespace gabarit::host
