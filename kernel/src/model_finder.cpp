#include "gabarit/model_finder.hpp"

#include "gabarit/deterministic_math.hpp"
#include "gabarit/finder_search.hpp"

namespace gabarit {
namespace {

// The coarse accumulator counts in 16 bits: a cell's votes for one rotation
// are at most one per coarse model point, which are capped at this.
constexpr std::uint32_t kMaxCoarsePoints = 65535;

std::uint32_t ceil_sqrt(std::uint64_t v) noexcept {
  std::uint32_t lo = 0, hi = 1u << 17;  // model coordinates are i16: v < 2^31
  while (lo < hi) {
    const std::uint32_t mid = (lo + hi) / 2;
    if (std::uint64_t{mid} * mid >= v) hi = mid; else lo = mid + 1;
  }
  return lo;
}

std::uint32_t first_point(const TableView& table, std::uint16_t depth) noexcept {
  std::uint32_t first = 0;
  for (std::uint16_t d = 0; d < depth; ++d) first += table.model_point_count(d);
  return first;
}

// The orientation of the model image's edge at model point m.
std::uint8_t model_orientation(const TableView& table, std::uint16_t depth, const ModelPoint& m) noexcept {
  return edge_orientation_at(table.model_image(depth), round_to_int(table.model_ref_x() + static_cast<float>(m.x)),
                             round_to_int(table.model_ref_y() + static_cast<float>(m.y)));
}

bool point_before(const OrientedPoint& a, const OrientedPoint& b, bool orientation) noexcept {
  const std::uint32_t ca = orientation ? orientation_channel(a.orientation) : 0;
  const std::uint32_t cb = orientation ? orientation_channel(b.orientation) : 0;
  if (ca != cb) return ca < cb;
  if (a.y != b.y) return a.y < b.y;
  return a.x < b.x;
}

// In-place heap sort (no recursion, no buffer).
void sort_points(std::span<OrientedPoint> p, bool orientation) noexcept {
  const std::size_t n = p.size();
  auto sift = [&](std::size_t root, std::size_t end) {
    while (2 * root + 1 < end) {
      std::size_t child = 2 * root + 1;
      if (child + 1 < end && point_before(p[child], p[child + 1], orientation)) ++child;
      if (!point_before(p[root], p[child], orientation)) return;
      const OrientedPoint t = p[root];
      p[root] = p[child];
      p[child] = t;
      root = child;
    }
  };
  for (std::size_t i = n / 2; i-- > 0;) sift(i, n);
  for (std::size_t end = n; end > 1; --end) {
    const OrientedPoint t = p[0];
    p[0] = p[end - 1];
    p[end - 1] = t;
    sift(0, end - 1);
  }
}

bool full_turn(const FinderOptions& o) noexcept { return o.theta_max_deg - o.theta_min_deg >= 360.0f; }

}  // namespace

bool valid(const FinderOptions& o) noexcept {
  return within_limit(o.theta_min_deg, 1.0e4f) && within_limit(o.theta_max_deg, 1.0e4f) && o.theta_max_deg >= o.theta_min_deg &&
         is_finite(o.theta_step_deg) && o.theta_step_deg >= 0.0f && o.theta_step_deg <= 360.0f &&
         o.pyramid_factor <= kMaxPyramidFactor && o.candidates >= 1 && o.candidates <= kMaxFinderCandidates &&
         o.max_count >= 1 && o.max_count <= o.candidates && is_finite(o.min_score) && o.min_score >= 0.0f &&
         o.min_score <= 1.0f && is_finite(o.min_distance_px) && o.min_distance_px >= 0.0f && o.min_distance_px < 1.0e5f &&
         o.coarse_depth >= -1;
}

FinderGeometry finder_geometry(const TableView& table, const Detector& detector, const FinderOptions& options,
                               std::uint32_t width, std::uint32_t height) noexcept {
  FinderGeometry g;
  g.coarse_depth = options.coarse_depth < 0 ? static_cast<std::uint16_t>(table.depth_count() / 2)
                                            : static_cast<std::uint16_t>(options.coarse_depth);
  std::uint64_t r2 = 0;
  if (g.coarse_depth < table.depth_count()) {
    const std::uint32_t first = first_point(table, g.coarse_depth), n = table.model_point_count(g.coarse_depth);
    for (std::uint32_t i = 0; i < n; ++i) {
      const ModelPoint m = table.model_point(first + i);
      const std::uint64_t d2 = std::uint64_t(std::int64_t{m.x} * m.x + std::int64_t{m.y} * m.y);
      r2 = d2 > r2 ? d2 : r2;
    }
  }
  const std::uint32_t radius = ceil_sqrt(r2);
  g.model_radius_px = static_cast<float>(radius);
  if (options.pyramid_factor != 0) {
    g.factor = options.pyramid_factor;
  } else {
    const std::uint32_t f = radius / 12;
    g.factor = f < 2 ? 2 : (f > 4 ? 4 : f);
  }
  g.coarse_width = (width + g.factor - 1) / g.factor;
  g.coarse_height = (height + g.factor - 1) / g.factor;
  const std::uint32_t coarse_radius = (radius + g.factor - 1) / g.factor + 1;
  g.pad = coarse_radius + 1;
  // The step: one fine vote's theta reach, and at most a radian over the
  // coarse radius (the farthest point then moves about a coarse pixel).
  float step = options.theta_step_deg;
  if (step <= 0.0f) {
    const Axis t = table.axis_theta();
    const float cell = t.cells > 1 ? (t.max - t.min) / static_cast<float>(t.cells - 1) : 0.0f;
    const float reach = t.max - t.min + cell;
    const float bound = 2.0f * 57.29578f / static_cast<float>(coarse_radius > 1 ? coarse_radius - 1 : 1);
    step = reach > 0.0f && reach < bound ? reach : bound;
    if (step < 0.25f) step = 0.25f;
  }
  const float range = options.theta_max_deg - options.theta_min_deg;
  std::uint32_t n = 1;
  if (full_turn(options)) {
    const float k = 360.0f / step;
    n = static_cast<std::uint32_t>(k) + (static_cast<float>(static_cast<std::uint32_t>(k)) < k ? 1u : 0u);
    if (n > kMaxFinderRotations) n = kMaxFinderRotations;
    step = 360.0f / static_cast<float>(n);
  } else if (range > 0.0f) {
    const float k = range / step;
    n = static_cast<std::uint32_t>(k) + (static_cast<float>(static_cast<std::uint32_t>(k)) < k ? 1u : 0u) + 1u;
    if (n > kMaxFinderRotations) n = kMaxFinderRotations;
    step = range / static_cast<float>(n - 1);
  }
  g.rotations = n;
  g.theta_step_deg = step;
  g.min_distance_px = options.min_distance_px > 0.0f ? options.min_distance_px
                                                     : (g.model_radius_px / 2.0f > 2.0f ? g.model_radius_px / 2.0f : 2.0f);
  g.orientation = options.orientation && detector.kind != table_format::DetectorKind::kBinary && table.has_model_images();
  return g;
}

FinderScratchSizes finder_scratch_sizes(const FinderGeometry& g, const TableView& table) noexcept {
  FinderScratchSizes s;
  s.coarse_pixels = std::size_t{g.coarse_width} * g.coarse_height;
  s.accumulator = (std::size_t{g.coarse_width} + 2 * g.pad) * (std::size_t{g.coarse_height} + 2 * g.pad);
  for (std::uint16_t d = 0; d < table.depth_count(); ++d)
    s.model_points = table.model_point_count(d) > s.model_points ? table.model_point_count(d) : s.model_points;
  return s;
}

std::uint32_t ModelFinder::load_model(std::uint16_t depth, std::uint32_t factor, bool orientation,
                                      std::span<OrientedPoint> out) const noexcept {
  const std::uint32_t first = first_point(table_, depth), n = table_.model_point_count(depth);
  const float inv = 1.0f / static_cast<float>(factor);
  for (std::uint32_t i = 0; i < n; ++i) {
    const ModelPoint m = table_.model_point(first + i);
    out[i] = {static_cast<std::int16_t>(round_to_int(static_cast<float>(m.x) * inv)),
              static_cast<std::int16_t>(round_to_int(static_cast<float>(m.y) * inv)),
              orientation ? model_orientation(table_, depth, m) : std::uint8_t{0}};
  }
  if (factor == 1 && n <= kMaxCoarsePoints) return n;
  // Points that fall on one coarse pixel and channel are one coarse point.
  sort_points(out.first(n), orientation);
  std::uint32_t kept = 0;
  for (std::uint32_t i = 0; i < n; ++i) {
    if (kept > 0 && !point_before(out[kept - 1], out[i], orientation)) continue;  // equal key
    out[kept++] = out[i];
  }
  if (kept > kMaxCoarsePoints) {  // keep an even subset
    const std::uint32_t stride = (kept + kMaxCoarsePoints - 1) / kMaxCoarsePoints;
    std::uint32_t j = 0;
    for (std::uint32_t i = 0; i < kept; i += stride) out[j++] = out[i];
    kept = j;
  }
  return kept;
}

Status ModelFinder::verify(const ImageView& image, const Pose& pose, FinderScratch, float& score) const noexcept {
  score = 0.0f;
  if (!image.valid() || !pose_in_range(pose) || pose.depth >= table_.depth_count()) return Status::kInvalidArgument;
  const bool binary = detector_.kind == table_format::DetectorKind::kBinary;
  const bool orientation = !binary && table_.has_model_images();
  const std::int32_t low = detector_.threshold / 2 > 0 ? detector_.threshold / 2 : 1;
  const std::uint32_t first = first_point(table_, pose.depth), n = table_.model_point_count(pose.depth);
  if (n == 0) return Status::kOk;
  const std::uint32_t stride = n > 512 ? (n + 511) / 512 : 1;  // at most 512 points checked
  const SinCos sc = sin_cos_deg(pose.theta_deg);
  const std::int32_t turn = round_to_int(wrap_degrees(pose.theta_deg) * (256.0f / 180.0f));
  std::uint32_t checked = 0, matched = 0;
  for (std::uint32_t i = 0; i < n; i += stride) {
    const ModelPoint m = table_.model_point(first + i);
    const float mx = static_cast<float>(m.x), my = static_cast<float>(m.y);
    const std::int32_t px = round_to_int(pose.x + sc.cos * mx - sc.sin * my);
    const std::int32_t py = round_to_int(pose.y + sc.sin * mx + sc.cos * my);
    ++checked;
    const std::uint8_t want =
        orientation ? static_cast<std::uint8_t>((model_orientation(table_, pose.depth, m) + turn) & 255) : std::uint8_t{0};
    bool hit = false;
    for (std::int32_t oy = -1; oy <= 1 && !hit; ++oy)
      for (std::int32_t ox = -1; ox <= 1 && !hit; ++ox) {
        const std::int32_t x = px + ox, y = py + oy;
        if (x < 0 || y < 0 || static_cast<std::uint32_t>(x) >= image.width || static_cast<std::uint32_t>(y) >= image.height) continue;
        const auto ux = static_cast<std::uint32_t>(x), uy = static_cast<std::uint32_t>(y);
        if (binary) {
          hit = image.at(ux, uy) != 0;
          continue;
        }
        const SobelGradient g = sobel_gradient(image, ux, uy);
        if ((g.gx < 0 ? -g.gx : g.gx) + (g.gy < 0 ? -g.gy : g.gy) < low) continue;
        if (!orientation) {
          hit = true;
          continue;
        }
        const std::uint8_t diff = static_cast<std::uint8_t>(orientation_256(g.gx, g.gy) - want);
        hit = diff <= 16 || diff >= 240;  // within a channel, modulo a half turn
      }
    matched += hit ? 1u : 0u;
  }
  score = static_cast<float>(matched) / static_cast<float>(checked);
  return Status::kOk;
}

Status ModelFinder::find(const ImageView& image, const FinderOptions& options, FinderScratch scratch,
                         std::span<Detection> out, std::uint32_t& count) noexcept {
  count = 0;
  if (!valid(options) || !image.valid()) return Status::kInvalidArgument;
  if (options.coarse_depth >= static_cast<std::int32_t>(table_.depth_count())) return Status::kInvalidArgument;
  if (out.size() < options.max_count) return Status::kBufferTooSmall;
  FinderSearch search(*this);
  GABARIT_TRY(search.begin(image.width, image.height, options, scratch));
  GABARIT_TRY(search.advance(image, scratch, kUnlimitedWork));
  return search.results(scratch, out, count);
}

}  // namespace gabarit
