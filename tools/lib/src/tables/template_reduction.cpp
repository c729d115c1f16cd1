#include "gabarit/host/tables/template_reduction.hpp"

#include <algorithm>
#include <limits>
#include <string>

#include "gabarit/app/error.hpp"
#include "gabarit/app/rng.hpp"

namespace gabarit::host {
namespace {

// off[i * shifts + s]: point i moved by shift s lands off the model.
struct OffTable {
  std::vector<std::uint8_t> off;
  std::vector<Point> shifts;  // without the identity
};

OffTable off_table(const std::vector<Point>& model, const std::vector<Point>& all_shifts) {
  OffTable t;
  for (const Point& s : all_shifts)
    if (s.x != 0 || s.y != 0) t.shifts.push_back(s);
  std::int32_t reach = 0;
  for (const Point& s : t.shifts) reach = std::max({reach, std::abs(s.x), std::abs(s.y)});
  std::int32_t min_x = std::numeric_limits<std::int32_t>::max(), min_y = min_x, max_x = std::numeric_limits<std::int32_t>::min(), max_y = max_x;
  for (const Point& p : model) min_x = std::min(min_x, p.x), min_y = std::min(min_y, p.y), max_x = std::max(max_x, p.x), max_y = std::max(max_y, p.y);
  const std::int64_t w = max_x - min_x + 2 * reach + 1, h = max_y - min_y + 2 * reach + 1;
  std::vector<std::uint8_t> in(static_cast<std::size_t>(w * h), 0);
  const auto at = [&](std::int32_t x, std::int32_t y) {
    return static_cast<std::size_t>((std::int64_t{y} - min_y + reach) * w + (std::int64_t{x} - min_x + reach));
  };
  for (const Point& p : model) in[at(p.x, p.y)] = 1;
  t.off.resize(model.size() * t.shifts.size());
  for (std::size_t i = 0; i < model.size(); ++i)
    for (std::size_t s = 0; s < t.shifts.size(); ++s) t.off[i * t.shifts.size() + s] = !in[at(model[i].x + t.shifts[s].x, model[i].y + t.shifts[s].y)];
  return t;
}

// Drops points in `order` while every shift keeps >= min_chi points off the model.
std::vector<bool> reduce_in_order(const OffTable& t, std::size_t points, const std::vector<std::size_t>& order, std::uint32_t min_chi) {
  const std::size_t S = t.shifts.size();
  std::vector<std::uint32_t> count(S, 0);
  for (std::size_t i = 0; i < points; ++i)
    for (std::size_t s = 0; s < S; ++s) count[s] += t.off[i * S + s];
  std::vector<bool> kept(points, true);
  for (std::size_t i : order) {
    bool can = true;
    for (std::size_t s = 0; s < S && can; ++s) can = !t.off[i * S + s] || count[s] > min_chi;
    if (!can) continue;
    kept[i] = false;
    for (std::size_t s = 0; s < S; ++s) count[s] -= t.off[i * S + s];
  }
  return kept;
}

std::uint32_t value_of(const OffTable& t, const std::vector<bool>& kept) {
  const std::size_t S = t.shifts.size();
  std::uint32_t best = std::numeric_limits<std::uint32_t>::max();
  for (std::size_t s = 0; s < S; ++s) {
    std::uint32_t c = 0;
    for (std::size_t i = 0; i < kept.size(); ++i) c += kept[i] && t.off[i * S + s];
    best = std::min(best, c);
  }
  return S == 0 ? 0 : best;
}

}  // namespace

ReductionResult reduce_template(const std::vector<Point>& model, const std::vector<Point>& shifts, std::uint32_t min_chi,
                                ReductionOrder order, std::uint32_t restarts, std::uint64_t seed) {
  if (model.empty()) throw app::Error("template reduction: empty model");
  const OffTable t = off_table(model, shifts);
  const std::uint32_t full = value_of(t, std::vector<bool>(model.size(), true));
  if (min_chi > full) {
    throw app::Error("template reduction: the whole model's characterising value is " + std::to_string(full) + ", below the " +
                     std::to_string(min_chi) + " asked");
  }
  app::Rng rng(seed);
  const auto shuffled = [&] {
    std::vector<std::size_t> o(model.size());
    for (std::size_t i = 0; i < o.size(); ++i) o[i] = i;
    for (std::size_t i = o.size(); i > 1; --i) std::swap(o[i - 1], o[static_cast<std::size_t>(rng.uniform_int(0, static_cast<std::int32_t>(i - 1)))]);
    return o;
  };
  std::vector<bool> best;
  std::size_t best_size = model.size() + 1;
  const std::uint32_t tries = order == ReductionOrder::kGreedy ? 1 : std::max<std::uint32_t>(1, restarts);
  for (std::uint32_t r = 0; r < tries; ++r) {
    std::vector<std::size_t> o = shuffled();
    if (order == ReductionOrder::kGreedy) {
      // Fewest shifts told apart first; the shuffle breaks ties.
      const std::size_t S = t.shifts.size();
      std::vector<std::uint32_t> useful(model.size(), 0);
      for (std::size_t i = 0; i < model.size(); ++i)
        for (std::size_t s = 0; s < S; ++s) useful[i] += t.off[i * S + s];
      std::stable_sort(o.begin(), o.end(), [&](std::size_t a, std::size_t b) { return useful[a] < useful[b]; });
    }
    std::vector<bool> kept = reduce_in_order(t, model.size(), o, min_chi);
    const auto size = static_cast<std::size_t>(std::count(kept.begin(), kept.end(), true));
    if (size < best_size) best_size = size, best = std::move(kept);
  }
  ReductionResult out;
  for (std::size_t i = 0; i < model.size(); ++i)
    if (best[i]) out.points.push_back(model[i]);
  out.characterising_value = value_of(t, best);
  out.full_value = full;
  return out;
}

std::vector<Point> translation_differences(const std::vector<std::int32_t>& xs, const std::vector<std::int32_t>& ys) {
  std::vector<Point> out;
  std::vector<std::int32_t> dx, dy;
  for (std::int32_t a : xs)
    for (std::int32_t b : xs) dx.push_back(a - b);
  for (std::int32_t a : ys)
    for (std::int32_t b : ys) dy.push_back(a - b);
  std::sort(dx.begin(), dx.end());
  dx.erase(std::unique(dx.begin(), dx.end()), dx.end());
  std::sort(dy.begin(), dy.end());
  dy.erase(std::unique(dy.begin(), dy.end()), dy.end());
  for (std::int32_t x : dx)
    for (std::int32_t y : dy) out.push_back({x, y});
  return out;
}

}  // namespace gabarit::host
