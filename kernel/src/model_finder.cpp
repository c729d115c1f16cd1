#include "gabarit/model_finder.hpp"

#include "gabarit/deterministic_math.hpp"
#include "gabarit/refinement.hpp"

namespace gabarit {
namespace {

constexpr std::uint32_t kChannels = kOrientationChannels;
constexpr std::uint32_t kFineVotes = 4;  // track_steps per candidate, at most
constexpr float kConvergeShare = 0.8f;  // of the best first verified score: the candidates converged
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

// A shortlist of coarse peaks in the caller's candidates, one per place: a
// peak within `distance2` (squared, coarse pixels) of a kept one replaces it
// if stronger, else is dropped.
struct Shortlist {
  FinderCandidate* peaks = nullptr;
  std::uint32_t size = 0, capacity = 0;
  std::int64_t distance2 = 0;
  std::uint32_t floor_votes = 0;  // what a peak must beat once the list is full

  std::uint32_t floor() const noexcept { return floor_votes; }
  void offer(std::int32_t x, std::int32_t y, std::uint32_t rotation, std::uint32_t votes) noexcept {
    insert(x, y, rotation, votes);
    if (size < capacity) return;
    floor_votes = peaks[0].votes;
    for (std::uint32_t i = 1; i < size; ++i) floor_votes = peaks[i].votes < floor_votes ? peaks[i].votes : floor_votes;
  }
  void insert(std::int32_t x, std::int32_t y, std::uint32_t rotation, std::uint32_t votes) noexcept {
    FinderCandidate p;
    p.x = x, p.y = y, p.rotation = rotation, p.votes = votes;
    for (std::uint32_t i = 0; i < size; ++i) {
      const std::int64_t dx = x - peaks[i].x, dy = y - peaks[i].y;
      if (dx * dx + dy * dy < distance2) {
        if (votes > peaks[i].votes) peaks[i] = p;
        return;
      }
    }
    if (size < capacity) {
      peaks[size++] = p;
      return;
    }
    std::uint32_t w = 0;
    for (std::uint32_t i = 1; i < size; ++i)
      if (peaks[i].votes < peaks[w].votes) w = i;
    if (votes > peaks[w].votes) peaks[w] = p;
  }
};

// Found candidates first, then by score, then by the coarse peak's; ties keep their order.
bool ranks_above(const FinderCandidate& a, const FinderCandidate& b) noexcept {
  if (a.found != b.found) return a.found;
  if (a.result.score != b.result.score) return a.result.score > b.result.score;
  return a.result.coarse_score > b.result.coarse_score;
}

float wrap_degrees(float deg) noexcept {
  while (deg > 180.0f) deg -= 360.0f;
  while (deg <= -180.0f) deg += 360.0f;
  return deg;
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

namespace {

// Step 1 of ModelFinder::find: the coarse frame (block means; binary: block
// maxima, so a thin outline survives), its features, and their indices in
// the padded accumulator sorted by orientation channel (channel_begin[c] is
// channel c's first).
Status coarse_features(const ImageView& image, const FinderGeometry& g, const Detector& detector, const FinderScratchSizes& need,
                       FinderScratch& scratch, std::uint32_t (&channel_begin)[kChannels + 1]) noexcept {
  const bool binary = detector.kind == table_format::DetectorKind::kBinary;
  const std::uint32_t f = g.factor, cw = g.coarse_width, ch = g.coarse_height;
  for (std::uint32_t cy = 0; cy < ch; ++cy)
    for (std::uint32_t cx = 0; cx < cw; ++cx) {
      const std::uint32_t x0 = cx * f, y0 = cy * f;
      const std::uint32_t x1 = x0 + f < image.width ? x0 + f : image.width;
      const std::uint32_t y1 = y0 + f < image.height ? y0 + f : image.height;
      std::uint32_t sum = 0, max = 0;
      for (std::uint32_t y = y0; y < y1; ++y)
        for (std::uint32_t x = x0; x < x1; ++x) {
          const std::uint32_t v = image.at(x, y);
          sum += v;
          max = v > max ? v : max;
        }
      const std::uint32_t area = (x1 - x0) * (y1 - y0);
      scratch.coarse_image[std::size_t{cy} * cw + cx] =
          static_cast<std::uint8_t>(binary ? max : (sum + area / 2) / area);
    }
  const ImageView coarse{scratch.coarse_image.data(), cw, ch, cw};
  FeatureCount fc;
  GABARIT_TRY(extract_features(coarse, {0, 0, static_cast<std::uint16_t>(cw), static_cast<std::uint16_t>(ch)}, detector.kind,
                               detector.threshold, scratch.coarse_features.first(need.coarse_pixels), fc));
  const std::size_t astride = std::size_t{cw} + 2 * g.pad;
  auto channel_of = [&](const RoiPoint& p) -> std::uint32_t {
    if (!g.orientation) return 0;
    const SobelGradient s = sobel_gradient(coarse, p.col, p.row);
    return orientation_channel(orientation_256(s.gx, s.gy));
  };
  for (std::uint32_t i = 0; i < fc.written; ++i) ++channel_begin[channel_of(scratch.coarse_features[i]) + 1];
  for (std::uint32_t c = 0; c < kChannels; ++c) channel_begin[c + 1] += channel_begin[c];
  {
    std::uint32_t fill[kChannels];
    for (std::uint32_t c = 0; c < kChannels; ++c) fill[c] = channel_begin[c];
    for (std::uint32_t i = 0; i < fc.written; ++i) {
      const RoiPoint& p = scratch.coarse_features[i];
      scratch.feature_index[fill[channel_of(p)]++] =
          static_cast<std::int32_t>((std::size_t{p.row} + g.pad) * astride + p.col + g.pad);
    }
  }

  return Status::kOk;
}

// Step 2: every rotation of the coarse model voted by the coarse features of
// its channels into one accumulator, whose 3 x 3 peaks go to the shortlist.
void vote_rotations(const FinderOptions& options, const FinderGeometry& g, const FinderScratchSizes& need, std::uint32_t model_n,
                    const std::uint32_t (&channel_begin)[kChannels + 1], FinderScratch& scratch, Shortlist& shortlist) noexcept {
  const std::uint32_t cw = g.coarse_width, ch = g.coarse_height;
  const std::size_t astride = std::size_t{cw} + 2 * g.pad;
  const std::size_t acc_cells = need.accumulator;
  const std::uint32_t channels = g.orientation ? kChannels : 1u;
  for (std::uint32_t k = 0; k < g.rotations; ++k) {
    const float theta = options.theta_min_deg + static_cast<float>(k) * g.theta_step_deg;
    const SinCos sc = sin_cos_deg(theta);
    const std::int32_t turn = round_to_int(wrap_degrees(theta) * (256.0f / 180.0f));
    // Lists per channel: counts, then each point's index delta in one or two lists.
    std::uint32_t list_begin[kChannels + 1] = {};
    auto lists_of = [&](const OrientedPoint& p, std::uint32_t& a, std::uint32_t& b) {
      if (!g.orientation) {
        a = b = 0;
        return;
      }
      const std::uint32_t rotated = static_cast<std::uint32_t>(p.orientation + turn) & 255u;
      a = rotated >> 4;
      b = ((rotated & 15u) < 8u ? a + kChannels - 1 : a + 1) % kChannels;
    };
    for (std::uint32_t i = 0; i < model_n; ++i) {
      std::uint32_t a, b;
      lists_of(scratch.model[i], a, b);
      ++list_begin[a + 1];
      if (b != a) ++list_begin[b + 1];
    }
    for (std::uint32_t c = 0; c < kChannels; ++c) list_begin[c + 1] += list_begin[c];
    std::uint32_t fill[kChannels];
    for (std::uint32_t c = 0; c < kChannels; ++c) fill[c] = list_begin[c];
    for (std::uint32_t i = 0; i < model_n; ++i) {
      const OrientedPoint& p = scratch.model[i];
      const float mx = static_cast<float>(p.x), my = static_cast<float>(p.y);
      const std::int32_t rx = round_to_int(sc.cos * mx - sc.sin * my);
      const std::int32_t ry = round_to_int(sc.sin * mx + sc.cos * my);
      const auto delta = static_cast<std::int32_t>(ry * static_cast<std::int64_t>(astride) + rx);
      std::uint32_t a, b;
      lists_of(p, a, b);
      scratch.rotated[fill[a]++] = delta;
      if (b != a) scratch.rotated[fill[b]++] = delta;
    }
    for (std::size_t i = 0; i < acc_cells; ++i) scratch.accumulator[i] = 0;
    std::uint16_t* acc = scratch.accumulator.data();
    for (std::uint32_t c = 0; c < channels; ++c) {
      const std::int32_t* deltas = scratch.rotated.data() + list_begin[c];
      const std::uint32_t nd = list_begin[c + 1] - list_begin[c];
      if (nd == 0) continue;
      for (std::uint32_t fi = channel_begin[c]; fi < channel_begin[c + 1]; ++fi) {
        std::uint16_t* at = acc + scratch.feature_index[fi];
        for (std::uint32_t d = 0; d < nd; ++d) ++at[-deltas[d]];
      }
    }
    // Peaks: local maxima whose 3 x 3 sum could enter the shortlist.
    for (std::uint32_t y = 0; y < ch; ++y) {
      const std::uint16_t* row = acc + (std::size_t{y} + g.pad) * astride + g.pad;
      for (std::uint32_t x = 0; x < cw; ++x) {
        const std::uint32_t v = row[x];
        if (v < 2 || 9 * v <= shortlist.floor()) continue;
        const std::uint16_t* c = row + x;
        const auto s = static_cast<std::ptrdiff_t>(astride);  // signed: the row above is at -s
        const std::uint32_t up[3] = {c[-s - 1], c[-s], c[-s + 1]};
        const std::uint32_t mid[2] = {c[-1], c[1]};
        const std::uint32_t down[3] = {c[s - 1], c[s], c[s + 1]};
        if (up[0] > v || up[1] > v || up[2] > v || mid[0] > v || mid[1] > v || down[0] > v || down[1] > v || down[2] > v)
          continue;
        const std::uint32_t sum = v + up[0] + up[1] + up[2] + mid[0] + mid[1] + down[0] + down[1] + down[2];
        if (sum <= shortlist.floor()) continue;
        shortlist.offer(static_cast<std::int32_t>(x), static_cast<std::int32_t>(y), k, sum);
      }
    }
  }

}

// Step 4: the candidates ranked (a stable insertion sort), then duplicates
// dropped (two peaks the table moved to one place) into `out`.
void rank_detections(const FinderOptions& options, const FinderGeometry& g, FinderScratch& scratch, std::uint32_t shortlist_size,
                     std::span<Detection> out, std::uint32_t& count) noexcept {
  const std::uint32_t size = shortlist_size;
  for (std::uint32_t i = 1; i < size; ++i) {
    const FinderCandidate c = scratch.candidates[i];
    std::uint32_t at = i;
    while (at > 0 && ranks_above(c, scratch.candidates[at - 1])) {
      scratch.candidates[at] = scratch.candidates[at - 1];
      --at;
    }
    scratch.candidates[at] = c;
  }
  const float d2 = g.min_distance_px * g.min_distance_px;
  for (std::uint32_t i = 0; i < size && scratch.candidates[i].found && count < options.max_count; ++i) {
    const Detection& d = scratch.candidates[i].result;
    bool duplicate = false;
    for (std::uint32_t j = 0; j < count && !duplicate; ++j) {
      const float dx = d.pose.x - out[j].pose.x, dy = d.pose.y - out[j].pose.y;
      duplicate = dx * dx + dy * dy < d2;
    }
    if (!duplicate) out[count++] = d;
  }
}

}  // namespace

Status ModelFinder::find(const ImageView& image, const FinderOptions& options, FinderScratch scratch,
                         std::span<Detection> out, std::uint32_t& count) noexcept {
  count = 0;
  if (!valid(options) || !image.valid() || image.width > 65535u * kMaxPyramidFactor ||
      image.height > 65535u * kMaxPyramidFactor)
    return Status::kInvalidArgument;
  if (options.coarse_depth >= static_cast<std::int32_t>(table_.depth_count())) return Status::kInvalidArgument;
  if (out.size() < options.max_count) return Status::kBufferTooSmall;
  const FinderGeometry g = finder_geometry(table_, detector_, options, image.width, image.height);
  const FinderScratchSizes need = finder_scratch_sizes(g, table_);
  // Coarse windows are addressed in 16 bits, accumulator cells in 31.
  if (g.coarse_width > 65535u || g.coarse_height > 65535u || need.accumulator > 0x7FFFFFFFu) return Status::kInvalidArgument;
  if (scratch.coarse_image.size() < need.coarse_pixels || scratch.coarse_features.size() < need.coarse_pixels ||
      scratch.feature_index.size() < need.coarse_pixels || scratch.accumulator.size() < need.accumulator ||
      scratch.model.size() < need.model_points || scratch.rotated.size() < 2 * need.model_points ||
      scratch.candidates.size() < options.candidates)
    return Status::kBufferTooSmall;
  const std::uint32_t f = g.factor;

  // 1. The coarse frame, its features and their channels.
  std::uint32_t channel_begin[kChannels + 1] = {};
  GABARIT_TRY(coarse_features(image, g, detector_, need, scratch, channel_begin));

  // 2. The coarse model, and the vote of every rotation.
  const std::uint32_t model_n = load_model(g.coarse_depth, f, g.orientation, scratch.model);
  if (model_n == 0) return Status::kOk;
  Shortlist shortlist;
  shortlist.peaks = scratch.candidates.data();
  shortlist.capacity = options.candidates;
  const float min_distance_coarse = g.min_distance_px / static_cast<float>(f);
  shortlist.distance2 = static_cast<std::int64_t>(min_distance_coarse * min_distance_coarse) + 1;
  vote_rotations(options, g, need, model_n, channel_begin, scratch, shortlist);

  // 3. The fine level. Each peak is voted with the table once and the
  // result verified; those within kConvergeShare of the best verified score
  // are voted again from each result until it stays in place (at most
  // kFineVotes votes, as tracking frames would converge), refined within
  // the cell and verified again.
  const float half = static_cast<float>(f - 1) * 0.5f;
  float best_first = 0.0f;
  for (std::uint32_t i = 0; i < shortlist.size; ++i) {
    FinderCandidate& c = scratch.candidates[i];
    const Pose start{static_cast<float>(c.x * static_cast<std::int32_t>(f)) + half,
                     static_cast<float>(c.y * static_cast<std::int32_t>(f)) + half,
                     wrap_degrees(options.theta_min_deg + static_cast<float>(c.rotation) * g.theta_step_deg), g.coarse_depth};
    c.result = Detection{};
    c.result.coarse_score = static_cast<float>(c.votes) / static_cast<float>(model_n);
    c.result.score = -1.0f;  // lost at the first vote
    c.found = false;
    StepResult step;
    GABARIT_TRY(track_step(table_, detector_, image, start, scratch.fine, step));
    if (step.state == TrackState::kLost) continue;
    c.result.pose = step.pose;
    c.result.pose.theta_deg = wrap_degrees(c.result.pose.theta_deg);
    GABARIT_TRY(verify(image, c.result.pose, scratch, c.result.score));
    best_first = c.result.score > best_first ? c.result.score : best_first;
  }
  for (std::uint32_t i = 0; i < shortlist.size; ++i) {
    FinderCandidate& c = scratch.candidates[i];
    if (c.result.score < 0.0f) continue;
    if (c.result.score < kConvergeShare * best_first) {  // reported as voted once, if at all
      c.found = c.result.score >= options.min_score;
      continue;
    }
    StepResult step;
    Pose from = c.result.pose;
    GABARIT_TRY(track_step(table_, detector_, image, from, scratch.fine, step));
    if (step.state == TrackState::kLost) {
      c.result.score = -1.0f;
      continue;
    }
    for (std::uint32_t v = 2; v < kFineVotes; ++v) {
      const float dx = step.pose.x - from.x, dy = step.pose.y - from.y;
      const float dt = step.pose.theta_deg - from.theta_deg;
      if (dx * dx + dy * dy < 0.25f && dt < 0.3f && dt > -0.3f) break;
      StepResult next;
      GABARIT_TRY(track_step(table_, detector_, image, step.pose, scratch.fine, next));
      if (next.state == TrackState::kLost) break;
      from = step.pose;
      step = next;
    }
    // The last vote's counters are still in the scratch: the sub-cell
    // offset from its neighbouring cells (refinement.hpp).
    const SubCellOffset sub = refine_within_cell(table_, scratch.fine.counters, step.best.cell);
    Detection& d = c.result;
    d.pose = pose_of_cell(table_, step.best.cell, from, step.roi_centre_x, step.roi_centre_y, sub.x, sub.y, sub.theta_deg);
    if (stack_ != nullptr) {
      GABARIT_TRY(depth_by_intensity(image, d.pose, *stack_, d.pose.depth));
      for (int k = 0; k < 2; ++k) GABARIT_TRY(angle_by_intensity(image, d.pose, *stack_, d.pose.theta_deg));
    }
    d.pose.theta_deg = wrap_degrees(d.pose.theta_deg);
    d.vote_score = step.score;
    GABARIT_TRY(verify(image, d.pose, scratch, d.score));
    c.found = d.score >= options.min_score;
  }
  rank_detections(options, g, scratch, shortlist.size, out, count);
  return Status::kOk;
}

}  // namespace gabarit
