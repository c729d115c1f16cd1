#include "gabarit/host/tables/decimation.hpp"

#include <algorithm>
#include <cmath>
#include <queue>
#include <tuple>

#include "gabarit/app/args.hpp"
#include "gabarit/app/error.hpp"
#include "gabarit/app/rng.hpp"

namespace gabarit::host {
namespace {

// Overlap counts above this weigh as this: a weight is then below 2^24
// (n^3), times the spread factor (4^kSpreadCap) below 2^36, and the sum
// over a stencil of at most kMaxSpreadStencil references below 2^62.
constexpr std::uint64_t kWeightOverlapCap = 255;
// The spread policy's neighbourhood: the pixels within this Chebyshev distance.
constexpr std::int64_t kSpreadRadius = 2;
constexpr std::uint32_t kSpreadCap = 6;
constexpr std::size_t kMaxSpreadStencil = std::size_t{1} << 26;

std::uint64_t removal_weight(std::uint32_t overlap, const DecimationPolicy& p) {
  const std::uint64_t n = std::min<std::uint64_t>(overlap, kWeightOverlapCap);
  switch (p.weight) {
    case RemovalWeight::kPower: return p.power == 3 ? n * n * n : n * n;
    default: return n;  // identity; greedy ranks by the same n
  }
}

// Draws items with probability proportional to integer weights that change
// as the draw goes (a Fenwick tree of the weights).
class WeightedDraw {
 public:
  void reset(std::size_t n) {
    tree_.assign(n + 1, 0);
    weight_.assign(n, 0);
    total_ = 0;
  }
  void set(std::size_t i, std::uint64_t w) {
    const std::uint64_t old = weight_[i];
    weight_[i] = w;
    total_ += w - old;  // modular; the true total is never negative
    for (std::size_t k = i + 1; k < tree_.size(); k += k & (~k + 1)) tree_[k] += w - old;
  }
  std::uint64_t total() const { return total_; }
  // Precondition: total() > 0. The item whose weight interval holds a
  // uniform draw in [0, total).
  std::size_t draw(app::Rng& rng) const {
    std::uint64_t r = uniform_below(rng, total_);
    std::size_t at = 0;
    std::size_t step = 1;
    while (step * 2 < tree_.size()) step *= 2;
    for (; step > 0; step /= 2) {
      if (at + step < tree_.size() && tree_[at + step] <= r) {
        at += step;
        r -= tree_[at];
      }
    }
    return at;  // items are 0-based: tree index at + 1
  }

 private:
  static std::uint64_t uniform_below(app::Rng& rng, std::uint64_t bound) {
    // Rejection keeps the draw exact for any bound.
    const std::uint64_t limit = ~std::uint64_t{0} - (~std::uint64_t{0} % bound);
    std::uint64_t x = rng.next_u64();
    while (x >= limit) x = rng.next_u64();
    return x % bound;
  }
  std::vector<std::uint64_t> tree_, weight_;
  std::uint64_t total_ = 0;
};

// The item of largest weight, ties broken by a per-item random key fixed at
// the start (greedy removal), with weights that only change by set().
class GreedyDraw {
 public:
  void reset(std::size_t n, app::Rng& rng) {
    weight_.assign(n, 0);
    tie_.resize(n);
    for (auto& t : tie_) t = rng.next_u64();
    heap_ = {};
    live_ = 0;
  }
  void set(std::size_t i, std::uint64_t w) {
    live_ += (w > 0) - (weight_[i] > 0);
    weight_[i] = w;
    if (w > 0) heap_.emplace(w, tie_[i], i);
  }
  std::uint64_t total() const { return live_; }
  std::size_t draw() {
    for (;;) {
      const auto [w, tie, i] = heap_.top();
      heap_.pop();
      if (weight_[i] == w) return i;  // an entry left behind by a later set() is stale
    }
  }

 private:
  std::vector<std::uint64_t> weight_, tie_;
  std::priority_queue<std::tuple<std::uint64_t, std::uint64_t, std::size_t>> heap_;
  std::uint64_t live_ = 0;
};

// The rival of stencil `c` (its pixels S): the other full stencil sharing
// most pixels with S (lowest index on ties). With `mark`, rival[i] says
// whether S[i] is one of the rival's pixels; with `weigh`, rival_w[i] is
// 1 + the sum over the other full stencils holding S[i] of
// (256 |S n S'| / |S|)^2 / 256: a pixel weighs by how alike the stencils that
// share it are to S. `shared` (one per cell, all zero) is scratch, left zero.
void mark_rival(const std::vector<std::uint32_t>& S, std::size_t c, const std::vector<std::uint32_t>& first,
                const std::vector<std::uint32_t>& cells_of, bool mark, bool weigh, std::vector<std::uint32_t>& shared,
                std::vector<std::uint64_t>& rival_w, std::vector<std::uint8_t>& rival) {
  const std::size_t n = S.size();
  for (std::uint32_t px : S)
    for (std::uint32_t k = first[px]; k < first[px + 1]; ++k) ++shared[cells_of[k]];
  shared[c] = 0;
  if (weigh) {
    rival_w.assign(n, 1);
    for (std::size_t i = 0; i < n; ++i) {
      for (std::uint32_t k = first[S[i]]; k < first[S[i] + 1]; ++k) {
        const std::uint64_t sim = std::uint64_t{shared[cells_of[k]]} * 256 / n;
        rival_w[i] += sim * sim / 256;
      }
    }
  }
  std::size_t best = c;
  for (std::size_t o = 0; o < shared.size(); ++o) {
    if (shared[o] > (best == c ? 0 : shared[best])) best = o;
  }
  for (std::uint32_t px : S)
    for (std::uint32_t k = first[px]; k < first[px + 1]; ++k) shared[cells_of[k]] = 0;
  if (best != c && mark) {
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t px = S[i];
      rival[i] = std::binary_search(cells_of.begin() + first[px], cells_of.begin() + first[px + 1], static_cast<std::uint32_t>(best));
    }
  }
}

std::vector<bool> decimate_per_stencil(const StencilPixels& s, double keep, std::uint64_t seed, const DecimationPolicy& p) {
  const std::uint32_t pixels = s.roi_width * s.roi_height;
  const std::size_t cell_count = s.cells.size();
  std::vector<std::uint32_t> overlap(pixels, 0);
  std::size_t references = 0;
  for (const auto& cell : s.cells) {
    for (std::uint32_t px : cell) ++overlap[px];
    references += cell.size();
  }
  // The full stencils' pixel -> cells lists, for the most overlapping rival.
  std::vector<std::uint32_t> first, cells_of;
  const bool rival_weight = p.weight == RemovalWeight::kRival;
  if (p.most_overlapping || rival_weight) {
    first.assign(pixels + 1, 0);
    for (std::uint32_t px = 0; px < pixels; ++px) first[px + 1] = first[px] + overlap[px];
    cells_of.resize(references);
    std::vector<std::uint32_t> fill(first.begin(), first.end() - 1);
    for (std::size_t c = 0; c < cell_count; ++c)
      for (std::uint32_t px : s.cells[c]) cells_of[fill[px]++] = static_cast<std::uint32_t>(c);
  }
  std::vector<std::uint32_t> shared(p.most_overlapping || rival_weight ? cell_count : 0, 0);
  std::vector<std::uint64_t> rival_w;  // kRival: each pixel's static weight
  std::vector<std::int32_t> item_of(p.spread ? pixels : 0, -1);
  std::vector<std::uint8_t> near, rival, alive;  // near: alive neighbours (spread)

  std::vector<bool> kept(references, true);
  app::Rng rng(seed);
  WeightedDraw weighted;
  GreedyDraw greedy;
  const bool is_greedy = p.weight == RemovalWeight::kGreedy;
  std::size_t base = 0;
  for (std::size_t c = 0; c < cell_count; base += s.cells[c].size(), ++c) {
    const std::vector<std::uint32_t>& S = s.cells[c];
    const std::size_t n = S.size();
    const auto wanted = static_cast<std::size_t>(std::llround(keep * static_cast<double>(n)));
    const std::size_t target = std::min<std::size_t>(n, std::max<std::size_t>({wanted, std::size_t{p.min_area}, std::size_t{1}}));
    if (target >= n) continue;
    if (p.spread && n > kMaxSpreadStencil) throw app::Error("decimation: a stencil too large for --spread");

    rival.assign(n, 1);
    if (p.most_overlapping || rival_weight) mark_rival(S, c, first, cells_of, p.most_overlapping, rival_weight, shared, rival_w, rival);
    near.assign(n, 0);
    alive.assign(n, 1);
    // Calls f(j) for every item j of S within kSpreadRadius of item i.
    const auto for_neighbours = [&](std::size_t i, auto&& f) {
      const std::int64_t x = S[i] % s.roi_width, y = S[i] / s.roi_width;
      for (std::int64_t dy = -kSpreadRadius; dy <= kSpreadRadius; ++dy) {
        for (std::int64_t dx = -kSpreadRadius; dx <= kSpreadRadius; ++dx) {
          if ((dx == 0 && dy == 0) || x + dx < 0 || y + dy < 0 || x + dx >= s.roi_width || y + dy >= s.roi_height) continue;
          const std::int32_t j = item_of[static_cast<std::size_t>((y + dy) * s.roi_width + x + dx)];
          if (j >= 0) f(static_cast<std::size_t>(j));
        }
      }
    };
    if (p.spread) {
      for (std::size_t i = 0; i < n; ++i) item_of[S[i]] = static_cast<std::int32_t>(i);
      for (std::size_t i = 0; i < n; ++i) for_neighbours(i, [&](std::size_t) { ++near[i]; });
    }
    if (is_greedy) greedy.reset(n, rng);
    else weighted.reset(n);
    const auto weight_of = [&](std::size_t i) -> std::uint64_t {
      // Spread: a pixel whose neighbourhood keeps k references weighs 4^k
      // times more (k capped at kSpreadCap), so removals thin crowded
      // neighbourhoods first and leave none empty while another has plenty.
      const std::uint64_t w = rival_weight ? rival_w[i] : removal_weight(overlap[S[i]], p);
      return p.spread ? w << (2 * std::min<std::uint32_t>(near[i], kSpreadCap)) : w;
    };
    const auto set = [&](std::size_t i, std::uint64_t w) { is_greedy ? greedy.set(i, w) : weighted.set(i, w); };
    const auto total = [&] { return is_greedy ? greedy.total() : weighted.total(); };
    // Phase 1: the pixels shared with the rival (all pixels without the policy).
    bool phase_two = false;
    for (std::size_t i = 0; i < n; ++i)
      if (rival[i]) set(i, weight_of(i));
    for (std::size_t removed = 0; removed < n - target; ++removed) {
      if (total() == 0 && !phase_two) {
        phase_two = true;
        for (std::size_t i = 0; i < n; ++i)
          if (alive[i] && !rival[i]) set(i, weight_of(i));
      }
      const std::size_t i = is_greedy ? greedy.draw() : weighted.draw(rng);
      alive[i] = 0;
      set(i, 0);
      kept[base + i] = false;
      --overlap[S[i]];
      if (p.spread) {
        for_neighbours(i, [&](std::size_t k) {
          if (!alive[k]) return;
          --near[k];
          if (rival[k] || phase_two) set(k, weight_of(k));
        });
      }
    }
    if (p.spread)
      for (std::uint32_t px : S) item_of[px] = -1;
  }
  return kept;
}

std::vector<std::uint32_t> undecimated_overlap(const StencilPixels& s) {
  std::vector<std::uint32_t> cover(std::size_t{s.roi_width} * s.roi_height, 0);
  for (const auto& cell : s.cells)
    for (std::uint32_t px : cell) ++cover[px];
  std::vector<std::uint32_t> overlap;
  for (const auto& cell : s.cells)
    for (std::uint32_t px : cell) overlap.push_back(cover[px]);
  return overlap;
}

}  // namespace

Decimation parse_decimation(const std::string& text) {
  if (text == "stencil") return Decimation::kStencil;
  if (text == "global" || text == "overlap") return Decimation::kGlobal;
  if (text == "uniform") return Decimation::kUniform;
  throw app::UsageError("--decimation '" + text + "': want stencil, global or uniform");
}

void parse_removal_weight(const std::string& text, DecimationPolicy& policy) {
  if (text == "identity") {
    policy.weight = RemovalWeight::kIdentity;
  } else if (text == "rival") {
    policy.weight = RemovalWeight::kRival;
  } else if (text == "greedy") {
    policy.weight = RemovalWeight::kGreedy;
  } else if (text == "power:2" || text == "power:3" || text == "power") {
    policy.weight = RemovalWeight::kPower;
    policy.power = text == "power:3" ? 3 : 2;
  } else {
    throw app::UsageError("--weight '" + text + "': want identity, power:2, power:3, greedy or rival");
  }
}

std::string describe(const DecimationPolicy& p) {
  switch (p.method) {
    case Decimation::kGlobal: return "global";
    case Decimation::kUniform: return "uniform";
    case Decimation::kStencil: break;
  }
  std::string out = "stencil, ";
  out += p.weight == RemovalWeight::kIdentity ? "identity"
         : p.weight == RemovalWeight::kGreedy ? "greedy"
         : p.weight == RemovalWeight::kRival  ? "rival"
                                              : "power:" + std::to_string(p.power);
  if (p.most_overlapping) out += ", most-overlapping";
  if (p.spread) out += ", spread";
  if (p.min_area > 0) out += ", min-area " + std::to_string(p.min_area);
  return out;
}

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

std::vector<bool> decimate(const StencilPixels& stencils, double keep, std::uint64_t seed, const DecimationPolicy& policy) {
  if (!(keep > 0.0) || keep > 1.0) throw app::Error("--keep must be in (0, 1]");
  if (policy.method == Decimation::kStencil && policy.weight == RemovalWeight::kPower && policy.power != 2 && policy.power != 3)
    throw app::Error("decimation: the power weight takes 2 or 3");
  std::size_t references = 0;
  for (const auto& cell : stencils.cells) references += cell.size();
  if (keep == 1.0 || references == 0) return std::vector<bool>(references, true);
  if (policy.method == Decimation::kStencil) return decimate_per_stencil(stencils, keep, seed, policy);
  std::vector<bool> kept(references, true);
  app::Rng rng(seed);
  if (policy.method == Decimation::kUniform) {
    for (std::size_t i = 0; i < references; ++i)
      if (rng.bernoulli(1.0 - keep)) kept[i] = false;
    return kept;
  }
  const std::vector<std::uint32_t> overlap = undecimated_overlap(stencils);
  const double alpha = decimation_alpha(overlap, keep);
  for (std::size_t i = 0; i < references; ++i)
    if (rng.bernoulli(std::min(1.0, alpha * overlap[i]))) kept[i] = false;
  return kept;
}

}  // namespace gabarit::host
