#include "gabarit/host/tables/table_analysis.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "gabarit/deterministic_math.hpp"
#include "gabarit/app/rng.hpp"
#include "gabarit/voter.hpp"

namespace gabarit::host {
namespace {

constexpr std::uint32_t kUnreachable = std::numeric_limits<std::uint32_t>::max();

// Per cell, the ROI pixels whose lists hold it (the stencil, decimated).
std::vector<std::vector<std::uint32_t>> stencil_pixels(const TableView& t) {
  std::vector<std::vector<std::uint32_t>> s(t.cell_count());
  for (std::uint32_t p = 0; p < t.roi_slots(); ++p)
    for (std::uint32_t i = t.references_begin(p); i < t.references_begin(p + 1); ++i) s[t.reference(i)].push_back(p);
  return s;
}

bool list_has(const TableView& t, std::uint32_t pixel, std::uint32_t cell) {
  std::uint32_t lo = t.references_begin(pixel), hi = t.references_begin(pixel + 1);
  while (lo < hi) {
    const std::uint32_t mid = lo + (hi - lo) / 2;
    if (t.reference(mid) < cell) lo = mid + 1;
    else hi = mid;
  }
  return lo < t.references_begin(pixel + 1) && t.reference(lo) == cell;
}

// The ROI pixels the depth's model covers at the cell's centre pose (the
// tracker's geometry, the ROI centred on the previous pose at the origin).
std::vector<std::uint32_t> model_pixels_at(const TableView& t, const CellBounds& c) {
  std::uint32_t first = 0;
  for (std::uint16_t d = 0; d < c.depth; ++d) first += t.model_point_count(d);
  const SinCos sc = sin_cos_deg(c.theta_centre_deg());
  std::vector<std::uint32_t> out;
  for (std::uint32_t i = 0; i < t.model_point_count(c.depth); ++i) {
    const ModelPoint p = t.model_point(first + i);
    const std::int32_t x = round_to_int(c.x_centre() + sc.cos * static_cast<float>(p.x) - sc.sin * static_cast<float>(p.y));
    const std::int32_t y = round_to_int(c.y_centre() + sc.sin * static_cast<float>(p.x) + sc.cos * static_cast<float>(p.y));
    const std::int32_t col = x - t.roi_origin_x(), row = y - t.roi_origin_y();
    if (col < 0 || row < 0 || col >= t.roi_width() || row >= t.roi_height()) continue;
    out.push_back(static_cast<std::uint32_t>(row) * t.roi_width() + static_cast<std::uint32_t>(col));
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

// Fewest flips that take D = vT b - vC a to at most 0 (C of lower index wins
// ties) or below 0, with the flip kinds of the header comment.
std::uint32_t flips_to_lose(std::int64_t a, std::int64_t b, std::int64_t vt, std::int64_t vc, std::int64_t shared,
                            std::int64_t both, bool rival_wins_ties) {
  std::int64_t need = vt * b - vc * a + (rival_wins_ties ? 0 : 1);
  if (need <= 0) return 0;
  struct Kind {
    std::int64_t gain, count;
  };
  Kind kinds[4] = {
      {a, (b - vc) - (both - shared)},  // add a feature in S_C \ S_T
      {b, vt - shared},                  // remove one in S_T \ S_C
      {b - a, shared},                   // remove one in both
      {a - b, both - shared},            // add one in both
  };
  std::sort(std::begin(kinds), std::end(kinds), [](const Kind& x, const Kind& y) { return x.gain > y.gain; });
  std::int64_t flips = 0;
  for (const Kind& k : kinds) {
    if (k.gain <= 0 || k.count <= 0) break;
    const std::int64_t take = std::min(k.count, (need + k.gain - 1) / k.gain);
    flips += take;
    need -= take * k.gain;
    if (need <= 0) return static_cast<std::uint32_t>(std::min<std::int64_t>(flips, kUnreachable - 1));
  }
  return kUnreachable;
}

bool translation_cells(const TableView& t) {
  const Axis th = t.axis_theta();
  if (th.cells != 1 || th.min != 0.0f) return false;
  for (std::uint32_t c = 0; c < t.cell_count(); ++c) {
    const CellBounds b = t.cell(c);
    if (b.x_hi - b.x_lo > 1.0f || b.y_hi - b.y_lo > 1.0f) return false;
    if (b.x_centre() != std::round(b.x_centre()) || b.y_centre() != std::round(b.y_centre())) return false;
  }
  return true;
}

}  // namespace

std::vector<std::uint64_t> refs_per_pixel(const TableView& t) {
  std::vector<std::uint64_t> h;
  for (std::uint32_t p = 0; p < t.roi_slots(); ++p) {
    const std::uint32_t k = t.references_begin(p + 1) - t.references_begin(p);
    if (h.size() <= k) h.resize(k + 1, 0);
    ++h[k];
  }
  return h;
}

TableAnalysis analyse_table(const TableView& t, const std::function<void(std::size_t, std::size_t)>& progress) {
  const std::uint32_t n = t.cell_count();
  const auto stencils = stencil_pixels(t);
  TableAnalysis out;
  out.exact = translation_cells(t);
  out.pixels_with = refs_per_pixel(t);
  std::vector<std::uint32_t> votes(n), shared(n), both(n);
  double margin_sum = 0, robust_sum = 0;
  out.overall_margin = kUnreachable;
  out.robustness_min = std::numeric_limits<std::int64_t>::max();
  for (std::uint32_t T = 0; T < n; ++T) {
    std::fill(votes.begin(), votes.end(), 0);
    std::fill(shared.begin(), shared.end(), 0);
    std::fill(both.begin(), both.end(), 0);
    const std::vector<std::uint32_t> model = model_pixels_at(t, t.cell(T));
    for (std::uint32_t p : model) {
      const bool has_t = list_has(t, p, T);
      for (std::uint32_t i = t.references_begin(p); i < t.references_begin(p + 1); ++i) {
        ++votes[t.reference(i)];
        shared[t.reference(i)] += has_t;
      }
    }
    for (std::uint32_t p : stencils[T])
      for (std::uint32_t i = t.references_begin(p); i < t.references_begin(p + 1); ++i) ++both[t.reference(i)];
    StencilMargin m;
    m.cell = T;
    m.stencil_size = t.stencil_size(T);
    m.margin = kUnreachable;
    std::uint32_t widest = 0;
    const std::int64_t a = std::max<std::uint32_t>(1, m.stencil_size);
    for (std::uint32_t C = 0; C < n; ++C) {
      if (C == T) continue;
      widest = std::max(widest, both[C]);
      const std::int64_t b = std::max<std::uint32_t>(1, t.stencil_size(C));
      const std::uint32_t f = flips_to_lose(a, b, votes[T], votes[C], shared[C], both[C], C < T);
      if (f < m.margin) m.margin = f, m.rival = C;
    }
    if (n == 1) m.margin = 0;
    m.robustness = static_cast<std::int64_t>(m.stencil_size) - widest;
    margin_sum += m.margin == kUnreachable ? 0 : m.margin;
    robust_sum += static_cast<double>(m.robustness);
    if (m.margin < out.overall_margin) out.overall_margin = m.margin, out.weakest_cell = T;
    out.robustness_min = std::min(out.robustness_min, m.robustness);
    out.stencils.push_back(m);
    if (progress && (T % 64 == 0 || T + 1 == n)) progress(T + 1, n);
  }
  out.mean_margin = margin_sum / n;
  out.robustness_mean = robust_sum / n;
  return out;
}

std::uint32_t overall_margin(const TableView& table) { return analyse_table(table).overall_margin; }

namespace {

// Membership of model points in a bitmap over their bounding box grown by
// the largest shift, so a shifted point is looked up without a search.
class PointSet {
 public:
  PointSet(const std::vector<Point>& points, const std::vector<Point>& shifts) {
    std::int32_t reach = 0;
    for (const Point& s : shifts) reach = std::max({reach, std::abs(s.x), std::abs(s.y)});
    min_x_ = min_y_ = std::numeric_limits<std::int32_t>::max();
    std::int32_t max_x = std::numeric_limits<std::int32_t>::min(), max_y = max_x;
    for (const Point& p : points) {
      min_x_ = std::min(min_x_, p.x), min_y_ = std::min(min_y_, p.y);
      max_x = std::max(max_x, p.x), max_y = std::max(max_y, p.y);
    }
    min_x_ -= reach, min_y_ -= reach;
    width_ = max_x + reach - min_x_ + 1;
    bits_.assign(static_cast<std::size_t>(width_) * static_cast<std::size_t>(max_y + reach - min_y_ + 1), 0);
    for (const Point& p : points) bits_[index(p.x, p.y)] = 1;
  }
  // Precondition: (x, y) is a point moved by one of the shifts.
  bool has(std::int32_t x, std::int32_t y) const { return bits_[index(x, y)] != 0; }

 private:
  std::size_t index(std::int32_t x, std::int32_t y) const {
    return static_cast<std::size_t>(y - min_y_) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x - min_x_);
  }
  std::int32_t min_x_ = 0, min_y_ = 0, width_ = 0;
  std::vector<std::uint8_t> bits_;
};

std::uint32_t chi_of(const PointSet& m, const std::vector<Point>& subset, const std::vector<Point>& shifts) {
  std::uint32_t chi = kUnreachable;
  for (const Point& s : shifts) {
    if (s.x == 0 && s.y == 0) continue;
    std::uint32_t off = 0;
    for (const Point& p : subset) off += !m.has(p.x + s.x, p.y + s.y);
    chi = std::min(chi, off);
  }
  return chi == kUnreachable ? static_cast<std::uint32_t>(subset.size()) : chi;
}

}  // namespace

std::uint32_t characterising_value(const std::vector<Point>& model, const std::vector<Point>& subset, const std::vector<Point>& shifts) {
  if (model.empty()) return 0;
  return chi_of(PointSet(model, shifts), subset, shifts);
}

std::vector<Point> table_shifts(const TableView& t) {
  std::vector<Point> out;
  const CellRange first = t.depth_cells(0);
  for (std::uint32_t c = first.begin; c < first.end; ++c) {
    const CellBounds b = t.cell(c);
    const Point p{round_to_int(b.x_centre()), round_to_int(b.y_centre())};
    if (std::find_if(out.begin(), out.end(), [&](const Point& q) { return q.x == p.x && q.y == p.y; }) == out.end()) out.push_back(p);
  }
  return out;
}

std::vector<Characterisation> characterise(const std::vector<Point>& model, const std::vector<Point>& shifts,
                                           const std::vector<std::uint32_t>& sizes, std::uint32_t samples, std::uint64_t seed) {
  std::vector<Characterisation> out;
  if (model.empty()) return out;
  const PointSet members(model, shifts);
  app::Rng rng(seed);
  std::vector<Point> pool = model, subset;
  for (std::uint32_t k : sizes) {
    if (k == 0 || k > model.size()) continue;
    Characterisation c;
    c.size = k;
    c.samples = samples;
    c.min_chi = kUnreachable;
    double sum = 0;
    std::uint32_t unambiguous = 0;
    for (std::uint32_t s = 0; s < samples; ++s) {
      // A partial Fisher-Yates shuffle draws k distinct points.
      for (std::uint32_t i = 0; i < k; ++i) {
        const auto j = static_cast<std::size_t>(rng.uniform_int(static_cast<std::int32_t>(i), static_cast<std::int32_t>(pool.size() - 1)));
        std::swap(pool[i], pool[j]);
      }
      subset.assign(pool.begin(), pool.begin() + k);
      const std::uint32_t chi = chi_of(members, subset, shifts);
      sum += chi;
      unambiguous += chi >= 1;
      c.min_chi = std::min(c.min_chi, chi);
      c.max_chi = std::max(c.max_chi, chi);
    }
    c.unambiguous = static_cast<double>(unambiguous) / samples;
    c.mean_chi = sum / samples;
    out.push_back(c);
  }
  return out;
}

std::string analysis_json(const TableView& t, const TableAnalysis& a, const std::vector<Characterisation>& chars) {
  std::ostringstream o;
  o << "{\n  \"cells\": " << t.cell_count() << ",\n  \"references\": " << t.reference_count() << ",\n  \"table_bytes\": " << t.size_bytes()
    << ",\n  \"model_points\": " << t.model_point_count() << ",\n  \"roi_pixels\": " << t.roi_pixels()
    << ",\n  \"margins_exact\": " << (a.exact ? "true" : "false") << ",\n  \"overall_margin\": " << a.overall_margin
    << ",\n  \"weakest_cell\": " << a.weakest_cell << ",\n  \"mean_margin\": " << a.mean_margin
    << ",\n  \"robustness\": {\"mean\": " << a.robustness_mean << ", \"min\": " << a.robustness_min << "},\n";
  o << "  \"refs_per_pixel\": [\n";
  std::uint64_t pixels = 0, refs = 0;
  for (std::size_t k = 0; k < a.pixels_with.size(); ++k) pixels += a.pixels_with[k], refs += k * a.pixels_with[k];
  std::uint64_t cum_pixels = 0, cum_refs = 0;
  bool first = true;
  for (std::size_t k = 0; k < a.pixels_with.size(); ++k) {
    if (a.pixels_with[k] == 0) continue;
    cum_pixels += a.pixels_with[k];
    cum_refs += k * a.pixels_with[k];
    o << (first ? "" : ",\n") << "    {\"refs\": " << k << ", \"pixels\": " << a.pixels_with[k]
      << ", \"cumulative_pixels\": " << static_cast<double>(cum_pixels) / std::max<std::uint64_t>(1, pixels)
      << ", \"vote_weighted\": " << static_cast<double>(k * a.pixels_with[k]) / std::max<std::uint64_t>(1, refs)
      << ", \"cumulative_vote_weighted\": " << static_cast<double>(cum_refs) / std::max<std::uint64_t>(1, refs) << "}";
    first = false;
  }
  o << "\n  ],\n  \"characterising_value\": [\n";
  for (std::size_t i = 0; i < chars.size(); ++i) {
    const Characterisation& c = chars[i];
    o << "    {\"size\": " << c.size << ", \"samples\": " << c.samples << ", \"unambiguous\": " << c.unambiguous << ", \"mean_chi\": " << c.mean_chi
      << ", \"min_chi\": " << c.min_chi << ", \"max_chi\": " << c.max_chi << "}" << (i + 1 < chars.size() ? ",\n" : "\n");
  }
  o << "  ],\n  \"stencils\": [\n";
  for (std::size_t i = 0; i < a.stencils.size(); ++i) {
    const StencilMargin& s = a.stencils[i];
    o << "    {\"cell\": " << s.cell << ", \"size\": " << s.stencil_size << ", \"margin\": " << s.margin << ", \"rival\": " << s.rival
      << ", \"robustness\": " << s.robustness << "}" << (i + 1 < a.stencils.size() ? ",\n" : "\n");
  }
  o << "  ]\n}\n";
  return o.str();
}

std::string overlap_map_svg(const TableView& t, std::uint32_t cell) {
  const int scale = std::max(1, std::min(8, 640 / std::max<int>(t.roi_width(), t.roi_height())));
  const int w = t.roi_width() * scale + 20, h = t.roi_height() * scale + 50;
  std::uint32_t widest = 1;
  for (std::uint32_t p = 0; p < t.roi_slots(); ++p) widest = std::max(widest, t.references_begin(p + 1) - t.references_begin(p));
  std::ostringstream o;
  o << "<svg xmlns='http://www.w3.org/2000/svg' width='" << w << "' height='" << h << "' font-family='sans-serif' font-size='12'>\n"
    << "<rect width='100%' height='100%' fill='white'/>\n<text x='10' y='18'>stencil of cell " << cell
    << ": its pixels by overlap (white 1 stencil, dark " << widest << "); grey: other stencils' pixels</text>\n";
  for (std::uint32_t p = 0; p < t.roi_slots(); ++p) {
    const std::uint32_t k = t.references_begin(p + 1) - t.references_begin(p);
    if (k == 0) continue;
    const int x = 10 + static_cast<int>(p % t.roi_width()) * scale, y = 30 + static_cast<int>(p / t.roi_width()) * scale;
    if (list_has(t, p, cell)) {
      const int shade = 255 - static_cast<int>(200.0 * (k - 1) / std::max<std::uint32_t>(1, widest - 1));
      o << "<rect x='" << x << "' y='" << y << "' width='" << scale << "' height='" << scale << "' fill='rgb(255," << shade << "," << shade / 2
        << ")' stroke='#900' stroke-width='0.2'/>\n";
    } else {
      o << "<rect x='" << x << "' y='" << y << "' width='" << scale << "' height='" << scale << "' fill='#eee'/>\n";
    }
  }
  o << "</svg>\n";
  return o.str();
}

std::string margins_svg(const TableAnalysis& a) {
  const int n = static_cast<int>(a.stencils.size());
  const int w = 60 + std::max(200, std::min(1200, 4 * n)), h = 260;
  std::uint32_t top = 1;
  for (const auto& s : a.stencils) top = std::max(top, std::max(s.margin == kUnreachable ? 0 : s.margin, s.stencil_size));
  const double bar = static_cast<double>(w - 60) / std::max(1, n);
  std::ostringstream o;
  o << "<svg xmlns='http://www.w3.org/2000/svg' width='" << w << "' height='" << h << "' font-family='sans-serif' font-size='12'>\n"
    << "<rect width='100%' height='100%' fill='white'/>\n<text x='10' y='18'>per stencil (cell order): size (grey) and margin of error (red); max "
    << top << "</text>\n";
  for (int i = 0; i < n; ++i) {
    const auto& s = a.stencils[static_cast<std::size_t>(i)];
    const double x = 50 + bar * i;
    const double hs = 200.0 * s.stencil_size / top, hm = 200.0 * (s.margin == kUnreachable ? 0 : s.margin) / top;
    o << "<rect x='" << x << "' y='" << 230 - hs << "' width='" << std::max(1.0, bar * 0.9) << "' height='" << hs << "' fill='#ccc'/>"
      << "<rect x='" << x << "' y='" << 230 - hm << "' width='" << std::max(1.0, bar * 0.9) << "' height='" << hm << "' fill='#c33'/>\n";
  }
  o << "<line x1='50' y1='230' x2='" << w - 10 << "' y2='230' stroke='black'/>\n</svg>\n";
  return o.str();
}

}  // namespace gabarit::host
