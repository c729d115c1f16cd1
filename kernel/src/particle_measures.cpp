#include "gabarit/particle_measures.hpp"

#include "gabarit/assert.hpp"
#include "gabarit/deterministic_math.hpp"
#include "gabarit/features.hpp"
#include "gabarit/finder_search.hpp"
#include "gabarit/verification.hpp"
#include "intensity_samples.hpp"

namespace gabarit {

bool EdgeMap::near(std::int32_t x, std::int32_t y, std::uint32_t t) const noexcept {
  if (t == 0) return at(x, y);
  const auto ti = static_cast<std::int32_t>(t);
  // Columns c0..c1 of the window (clipped), rows r0..r1.
  std::int32_t c0 = x - ti - window.x0, c1 = x + ti - window.x0;
  std::int32_t r0 = y - ti - window.y0, r1 = y + ti - window.y0;
  if (c0 < 0) c0 = 0;
  if (r0 < 0) r0 = 0;
  if (c1 >= window.width) c1 = window.width - 1;
  if (r1 >= window.height) r1 = window.height - 1;
  if (c0 > c1 || r0 > r1) return false;
  const auto w0 = static_cast<std::uint32_t>(c0) / 64, w1 = static_cast<std::uint32_t>(c1) / 64;
  const std::uint32_t b0 = static_cast<std::uint32_t>(c0) & 63u, b1 = static_cast<std::uint32_t>(c1) & 63u;
  // At most 7 columns: one word, or the tail of one and the head of the next.
  const std::uint64_t head = ~std::uint64_t{0} << b0;
  const std::uint64_t tail = b1 == 63 ? ~std::uint64_t{0} : (std::uint64_t{1} << (b1 + 1)) - 1;
  for (std::int32_t r = r0; r <= r1; ++r) {
    const std::uint64_t* row = bits.data() + static_cast<std::size_t>(r) * words_per_row;
    if (w0 == w1) {
      if ((row[w0] & head & tail) != 0) return true;
    } else if ((row[w0] & head) != 0 || (row[w1] & tail) != 0) {
      return true;
    }
  }
  return false;
}

Status EdgeMapLoader::load(const ImageView& image, const ImageWindow& requested) noexcept {
  if (!image.valid()) return Status::kInvalidArgument;
  // Clip to the image, then to the bitmap's largest window around the request's centre.
  std::int64_t x0 = requested.x0, y0 = requested.y0;
  std::int64_t x1 = x0 + requested.width, y1 = y0 + requested.height;
  if (x0 < 0) x0 = 0;
  if (y0 < 0) y0 = 0;
  if (x1 > image.width) x1 = image.width;
  if (y1 > image.height) y1 = image.height;
  if (x1 < x0) x1 = x0;
  if (y1 < y0) y1 = y0;
  if (x1 - x0 > max_width_) {
    const std::int64_t cut = (x1 - x0 - max_width_) / 2;
    x0 += cut, x1 = x0 + max_width_;
  }
  if (y1 - y0 > max_height_) {
    const std::int64_t cut = (y1 - y0 - max_height_) / 2;
    y0 += cut, y1 = y0 + max_height_;
  }
  ImageWindow window{static_cast<std::int32_t>(x0), static_cast<std::int32_t>(y0), static_cast<std::uint16_t>(x1 - x0),
                     static_cast<std::uint16_t>(y1 - y0)};
  const std::size_t words = edge_map_words(window.width, window.height);
  if (bits_.size() < edge_map_words(max_width_, max_height_) || features_.size() < max_width_ || words > bits_.size())
    return Status::kBufferTooSmall;
  map_ = {};
  map_.window = window;
  map_.words_per_row = static_cast<std::uint32_t>((std::size_t{window.width} + 63) / 64);
  for (std::size_t i = 0; i < words; ++i) bits_[i] = 0;
  map_.bits = bits_.first(words);
  if (window.width == 0 || window.height == 0) return Status::kOk;
  // Detect in strips of as many rows as the feature scratch holds (the
  // detectors read the image around a pixel, not the window, so strips give
  // the features one window would).
  const std::uint32_t strip_rows = static_cast<std::uint32_t>(features_.size() / window.width);
  for (std::uint32_t r = 0; r < window.height; r += strip_rows) {
    const std::uint32_t rows = window.height - r < strip_rows ? window.height - r : strip_rows;
    const ImageWindow strip{window.x0, window.y0 + static_cast<std::int32_t>(r), window.width, static_cast<std::uint16_t>(rows)};
    FeatureCount count;
    GABARIT_TRY(extract_features(image, strip, detector_.kind, detector_.threshold, features_, count));
    for (std::uint32_t i = 0; i < count.written; ++i) {
      const RoiPoint p = features_[i];
      bits_[std::size_t{r + p.row} * map_.words_per_row + p.col / 64u] |= std::uint64_t{1} << (p.col & 63u);
    }
    map_.features += count.written;
    map_.dropped += count.dropped;
  }
  return Status::kOk;
}

namespace {

// The first model point of `depth` (points are stored depth after depth).
std::uint32_t first_point(const TableView& table, std::uint16_t depth) noexcept {
  std::uint32_t first = 0;
  for (std::uint16_t d = 0; d < depth; ++d) first += table.model_point_count(d);
  return first;
}

}  // namespace

float EdgeCorrelationMeasure::score(const Pose& pose) noexcept {
  if (!pose_in_range(pose)) return 0.0f;
  const std::uint16_t depth = pose.depth < table_.depth_count() ? pose.depth : static_cast<std::uint16_t>(table_.depth_count() - 1);
  const std::uint32_t first = first_point(table_, depth), count = table_.model_point_count(depth);
  if (count == 0) return 0.0f;
  const EdgeMap& map = edges_.map();
  const SinCos sc = sin_cos_deg(pose.theta_deg);
  std::uint32_t hits = 0, taken = 0;
  for (std::uint32_t k = 0; k < count; k += stride_) {
    const ModelPoint m = table_.model_point(first + k);
    const float mx = static_cast<float>(m.x), my = static_cast<float>(m.y);
    const std::int32_t px = round_to_int(pose.x + (sc.cos * mx - sc.sin * my));
    const std::int32_t py = round_to_int(pose.y + (sc.sin * mx + sc.cos * my));
    hits += map.near(px, py, tolerance_) ? 1u : 0u;
    ++taken;
  }
  return static_cast<float>(hits) / static_cast<float>(taken);
}

void EdgeCorrelationMeasure::weigh(std::span<Particle> particles) noexcept {
  for (Particle& p : particles) p.weight = score(p.pose);
}

EdgeCorrelationMeasure::EdgeCorrelationMeasure(const TableView& table, const EdgeMapLoader& edges, std::uint32_t stride,
                                               std::uint32_t tolerance) noexcept
    : table_(table), edges_(edges), stride_(stride < 1 ? 1 : stride), tolerance_(tolerance > 3 ? 3 : tolerance) {
  std::uint32_t reach = 0;
  for (std::uint32_t i = 0; i < table_.model_point_count(); ++i) {
    const ModelPoint m = table_.model_point(i);
    const auto ax = static_cast<std::uint32_t>(m.x < 0 ? -m.x : m.x), ay = static_cast<std::uint32_t>(m.y < 0 ? -m.y : m.y);
    if (ax + ay > reach) reach = ax + ay;  // the L1 norm bounds the rotated point's distance
  }
  reach_ = reach + tolerance_ + 1;
}

std::uint32_t EdgeCorrelationMeasure::reach_px() const noexcept { return reach_; }

Status StencilVoteMeasure::prepare(const ImageView& image, const Pose& predicted) noexcept {
  prepared_ = false;
  GABARIT_TRY(prepare_frame(table_, detector_, image, predicted, scratch_, frame_));
  GABARIT_TRY(vote_prepared(table_, frame_, scratch_, tally_));
  predicted_ = predicted;
  rotation_ = sin_cos_deg(predicted.theta_deg);
  prepared_ = true;
  return Status::kOk;
}

namespace {

// The index of the cell of `a` whose centre is nearest v, or -1 outside the axis.
std::int32_t axis_index(const Axis& a, float v) noexcept {
  if (a.cells <= 1) {
    const float d = v - a.min;
    return d >= -0.5f && d <= 0.5f ? 0 : -1;
  }
  const float spacing = (a.max - a.min) / static_cast<float>(a.cells - 1);
  const float f = (v - a.min) / spacing;
  if (!(f > -0.5f && f < static_cast<float>(a.cells) - 0.5f)) return -1;
  const std::int32_t i = round_to_int(f);
  return i < 0 ? 0 : i >= static_cast<std::int32_t>(a.cells) ? static_cast<std::int32_t>(a.cells) - 1 : i;
}

}  // namespace

std::uint32_t StencilVoteMeasure::cell_of(const Pose& pose) const noexcept {
  if (!prepared_ || !pose_in_range(pose) || pose.depth >= table_.depth_count()) return kNoCell;
  const float dx = pose.x - static_cast<float>(frame_.roi_centre_x), dy = pose.y - static_cast<float>(frame_.roi_centre_y);
  const float tx = rotation_.cos * dx + rotation_.sin * dy, ty = -rotation_.sin * dx + rotation_.cos * dy;
  const Axis ax = table_.axis_x(), ay = table_.axis_y(), at = table_.axis_theta();
  const std::int32_t ix = axis_index(ax, tx), iy = axis_index(ay, ty), it = axis_index(at, pose.theta_deg - predicted_.theta_deg);
  if (ix < 0 || iy < 0 || it < 0) return kNoCell;
  return ((std::uint32_t{pose.depth} * at.cells + static_cast<std::uint32_t>(it)) * ay.cells + static_cast<std::uint32_t>(iy)) *
             ax.cells +
         static_cast<std::uint32_t>(ix);
}

float StencilVoteMeasure::score(const Pose& pose) noexcept {
  const std::uint32_t cell = cell_of(pose);
  if (cell == kNoCell) return 0.0f;
  return normalised_score({cell, scratch_.counters[cell], table_.stencil_size(cell)});
}

void StencilVoteMeasure::weigh(std::span<Particle> particles) noexcept {
  for (Particle& p : particles) p.weight = score(p.pose);
}

StencilVoteProposer::StencilVoteProposer(const TableView& table, const Detector& detector, TrackerScratch scratch,
                                         std::uint32_t count) noexcept
    : table_(table),
      detector_(detector),
      scratch_(scratch),
      count_(count < 1 ? 1 : count > kMaxParticleProposals ? kMaxParticleProposals : count) {}

Status StencilVoteProposer::propose(const ImageView& image, const Pose& predicted, ParticleProposals& out) noexcept {
  out.count = 0;
  GABARIT_TRY(prepare_frame(table_, detector_, image, predicted, scratch_, frame_));
  GABARIT_TRY(vote_prepared(table_, frame_, scratch_, tally_));
  CellScore top[kMaxParticleProposals];
  const std::uint32_t k = count_ < table_.cell_count() ? count_ : table_.cell_count();
  GABARIT_TRY(select_top_cells(table_, scratch_.counters, std::span<CellScore>(top, k)));
  for (std::uint32_t i = 0; i < k && top[i].votes > 0; ++i)
    out.poses[out.count++] = pose_of_cell(table_, top[i].cell, predicted, frame_.roi_centre_x, frame_.roi_centre_y);
  // An axis's spacing, and its extent with half a cell either side (one
  // unit, a pixel or a degree, for an axis of one cell).
  const auto spacing = [](const Axis& a) { return a.cells > 1 ? (a.max - a.min) / static_cast<float>(a.cells - 1) : 1.0f; };
  const auto extent = [&](const Axis& a) { return a.cells > 1 ? (a.max - a.min) + spacing(a) : 1.0f; };
  const Axis ax = table_.axis_x(), ay = table_.axis_y(), at = table_.axis_theta();
  const float px = 0.5f * (spacing(ax) + spacing(ay)), deg = at.cells > 1 ? spacing(at) : 0.25f;
  out.sigma_px = px > 0.5f ? px : 0.5f;
  out.sigma_deg = deg > 0.25f ? deg : 0.25f;
  out.region_volume = extent(ax) * extent(ay) * extent(at) * static_cast<float>(table_.depth_count());
  return Status::kOk;
}

void StencilVoteProposer::account(FrameLedger& ledger) const noexcept {
  ledger.add(FramePhase::kVote, track_features_work(table_) + tally_.votes, 0);
  ledger.pixels_scanned += frame_.pixels_scanned;
  ledger.features += tally_.features;
  ledger.votes += tally_.votes;
}

void IntensityCorrelationMeasure::reset(const FocusStack& stack, std::uint32_t samples) noexcept {
  stack_ = stack;
  frame_ = {};
  ring_ = OutlineRing::kWhereItAgrees;
  surround_ = 0;
  count_ = 0;
  object_count_ = 0;
  grid_columns_ = grid_rows_ = 0;
  for (auto& depth : model_sums_) depth[0] = depth[1] = {};
  if (samples == 0 || !valid_focus_stack(stack)) return;
  const std::uint32_t want = samples < 16 ? 16 : (samples > kMaxIntensityMeasureSamples ? kMaxIntensityMeasureSamples : samples);
  const ImageView& m = stack.images[0];
  const intensity::ObjectSupport outline(stack.images.first(1), intensity::ObjectSupport::kOutline);
  surround_ = outline.surround();
  const auto listed = [&](std::uint32_t u, std::uint32_t v) { return !outline.flat() || outline.contains(u, v); };
  // A regular grid over the object: the smallest step (at least the
  // stack's) that keeps `want` or fewer. The pixels with the most structure
  // instead (the strongest gradients) made the likelihood as narrow as the
  // edges are, and on the pipette scenes the cloud lost the tip twice as
  // often (docs/particle-filter.md, "The measures").
  std::uint32_t step = stack.step;
  for (;; ++step) {
    std::uint32_t n = 0;
    for (std::uint32_t v = 0; v < m.height && n <= want; v += step)
      for (std::uint32_t u = 0; u < m.width && n <= want; u += step) n += listed(u, v) ? 1u : 0u;
    if (n <= want || step >= kMaxStackStep) break;
  }
  stack_.step = step;
  // The object's samples first, then the ring's, each part in row order:
  // each part's sums then run in registers without a choice per sample, and
  // a row's neighbours follow one another (the runs below). The sums are
  // exact integers, so the order changes no score.
  for (const bool object : {true, false}) {
    for (std::uint32_t v = 0; v < m.height; v += step)
      for (std::uint32_t u = 0; u < m.width && count_ < kMaxIntensityMeasureSamples; u += step) {
        const bool on_object = !outline.flat() || outline.on_object(u, v);
        if (listed(u, v) && on_object == object) list_[count_++] = {static_cast<std::uint16_t>(u), static_cast<std::uint16_t>(v), on_object};
      }
    if (object) object_count_ = count_;
  }
  // The list's bounding box in the model, and each part's model sums at
  // each depth (they do not depend on the frame when every sample lands in it).
  sample_box_[0] = sample_box_[2] = list_[0].u;
  sample_box_[1] = sample_box_[3] = list_[0].v;
  for (std::uint32_t i = 0; i < count_; ++i) {
    const Sample& s = list_[i];
    if (s.u < sample_box_[0]) sample_box_[0] = s.u;
    if (s.v < sample_box_[1]) sample_box_[1] = s.v;
    if (s.u > sample_box_[2]) sample_box_[2] = s.u;
    if (s.v > sample_box_[3]) sample_box_[3] = s.v;
  }
  // The grid's lines over the box: a particle places each column's and each
  // row's rotated offset once, and each sample adds its column's and row's.
  grid_columns_ = (sample_box_[2] - sample_box_[0]) / step + 1u;
  grid_rows_ = (sample_box_[3] - sample_box_[1]) / step + 1u;
  if (grid_columns_ > kGridLines || grid_rows_ > kGridLines) {
    grid_columns_ = grid_rows_ = 0;
  } else {
    for (std::uint32_t i = 0; i < count_; ++i) {
      list_[i].column = static_cast<std::uint8_t>((list_[i].u - sample_box_[0]) / step);
      list_[i].row = static_cast<std::uint8_t>((list_[i].v - sample_box_[1]) / step);
    }
    for (std::uint32_t i = 0; i < count_;) {
      std::uint32_t n = 1;
      while (i + n < count_ && n < 255 && i + n != object_count_ && list_[i + n].v == list_[i].v &&
             list_[i + n].u == list_[i].u + n * step)
        ++n;
      list_[i].run = static_cast<std::uint8_t>(n);
      i += n;
    }
  }
  for (std::size_t d = 0; d < stack.images.size() && d < kSummedDepths; ++d) {
    for (std::uint32_t i = 0; i < count_; ++i) {
      const std::uint64_t a = stack.images[d].at(list_[i].u, list_[i].v);
      ModelSums& part = model_sums_[d][i < object_count_ ? 0 : 1];
      part.a += a;
      part.aa += a * a;
    }
  }
}

// The samples placed as walk_samples places them (16.16 positions, a 2.30
// rotation), each from its own offset rather than by stepping along a row;
// exact integer sums, so the same on every target.
bool IntensityCorrelationMeasure::listed_correlation(const Pose& pose, OutlineRing ring, float& score,
                                                     bool& ring_compared) const noexcept {
  using namespace intensity;
  const SinCos r = sin_cos_deg(pose.theta_deg);
  const std::int64_t c = round_scaled(r.cos, 30), sn = round_scaled(r.sin, 30);
  const std::int64_t x0 = round_scaled(pose.x, 16), y0 = round_scaled(pose.y, 16);
  const std::int64_t ref_x = round_scaled(stack_.ref_x, 16), ref_y = round_scaled(stack_.ref_y, 16);
  const std::int64_t x_limit = (std::int64_t{frame_.width} - 1) * 65536, y_limit = (std::int64_t{frame_.height} - 1) * 65536;
  const ImageView& m = stack_.images[pose.depth];
  // One part's samples, list_[begin, end), summed in locals.
  const auto sum_part = [&](std::uint32_t begin, std::uint32_t end, FrameSums& frame_sums, ImageSums& model_sums) {
    FrameSums fs;
    ImageSums ms;
    for (std::uint32_t i = begin; i < end; ++i) {
      const Sample& s = list_[i];
      const std::int64_t du = (std::int64_t{s.u} << 16) - ref_x, dv = (std::int64_t{s.v} << 16) - ref_y;
      const std::int64_t px = x0 + mul_shift(c, du, 30) - mul_shift(sn, dv, 30);
      const std::int64_t py = y0 + mul_shift(sn, du, 30) + mul_shift(c, dv, 30);
      if (px < 0 || py < 0 || px >= x_limit || py >= y_limit) continue;
      FrameSample at;
      at.row0 = frame_.pixels + static_cast<std::size_t>(py >> 16) * frame_.stride + static_cast<std::size_t>(px >> 16);
      at.row1 = at.row0 + frame_.stride;
      at.wx = static_cast<std::uint32_t>(px >> 8) & 255u;
      at.wy = static_cast<std::uint32_t>(py >> 8) & 255u;
      add_sample(fs, ms, m.at(s.u, s.v), at.value());
    }
    frame_sums = fs;
    model_sums = ms;
  };
  // Where every sample lands in the frame (the box's corners do: a sample's
  // position is a monotone function of its column plus one of its row, so
  // over the box it is extreme at a corner), the same sums without a bounds
  // check per sample, the model's from the list's precomputed ones.
  const auto inside = [&](std::uint16_t u, std::uint16_t v) {
    const std::int64_t du = (std::int64_t{u} << 16) - ref_x, dv = (std::int64_t{v} << 16) - ref_y;
    const std::int64_t px = x0 + mul_shift(c, du, 30) - mul_shift(sn, dv, 30);
    const std::int64_t py = y0 + mul_shift(sn, du, 30) + mul_shift(c, dv, 30);
    return px >= 0 && py >= 0 && px < x_limit && py < y_limit;
  };
  // The grid's columns' and rows' rotated offsets (a sample's position is
  // its column's plus its row's, the very sums it would compute itself),
  // the pose's position added to the columns' (integers: the same sums).
  struct Offset {
    std::int64_t x, y;
  };
  Offset columns[kGridLines], rows[kGridLines];
  const auto place_grid = [&] {
    const std::uint32_t step = stack_.step;
    for (std::uint32_t k = 0; k < grid_columns_; ++k) {
      const std::int64_t du = (std::int64_t{sample_box_[0] + k * step} << 16) - ref_x;
      columns[k] = {x0 + mul_shift(c, du, 30), y0 + mul_shift(sn, du, 30)};
    }
    for (std::uint32_t k = 0; k < grid_rows_; ++k) {
      const std::int64_t dv = (std::int64_t{sample_box_[1] + k * step} << 16) - ref_y;
      rows[k] = {mul_shift(sn, dv, 30), mul_shift(c, dv, 30)};
    }
  };
  // Run by run: a run's row offsets and its first model pixel once, then
  // each sample its column's offsets and the model pixel a step on. The
  // samples' pixels are gathered into arrays and blended and summed there
  // (GatheredSamples), a loop the compiler vectorises.
  const auto sum_inside = [&](std::uint32_t begin, std::uint32_t end, const ModelSums& model, FrameSums& frame_sums,
                              ImageSums& model_sums) {
    const std::size_t model_step = stack_.step;
    const std::size_t stride = frame_.stride;
    const std::uint8_t* const pixels = frame_.pixels;
    GatheredSamples gathered;
    for (std::uint32_t i = begin; i < end;) {
      const Sample& first = list_[i];
      const Offset row = rows[first.row];
      const std::uint8_t* model_pixel = m.pixels + std::size_t{first.v} * m.stride + first.u;
      const Offset* column = columns + first.column;
      for (std::uint32_t left = first.run; left > 0;) {
        // Locals throughout: the arrays' bytes may alias anything, so a
        // member read in the loop would be read again after every store.
        const std::uint32_t filled = gathered.count, room = GatheredSamples::kCapacity - filled;
        const std::uint32_t take = left < room ? left : room;
        for (std::uint32_t k = filled; k < filled + take; ++k, ++column, model_pixel += model_step) {
          const std::int64_t px = column->x - row.x, py = column->y + row.y;
          const std::uint8_t* const p = pixels + static_cast<std::size_t>(py >> 16) * stride + static_cast<std::size_t>(px >> 16);
          gathered.top_pair[k] = GatheredSamples::pair(p);
          gathered.bottom_pair[k] = GatheredSamples::pair(p + stride);
          gathered.wx[k] = static_cast<std::uint8_t>(px >> 8);
          gathered.wy[k] = static_cast<std::uint8_t>(py >> 8);
          gathered.model[k] = *model_pixel;
        }
        gathered.count = filled + take;
        left -= take;
        if (gathered.count == GatheredSamples::kCapacity) gathered.flush();
      }
      i += first.run;
    }
    gathered.flush();
    frame_sums = {end - begin, gathered.b_sum, gathered.bb};
    model_sums = {model.a, model.aa, gathered.ab};
  };
  OutlineParts parts;
  const auto& box = sample_box_;
  if (grid_columns_ > 0 && pose.depth < kSummedDepths && inside(box[0], box[1]) && inside(box[2], box[1]) && inside(box[0], box[3]) &&
      inside(box[2], box[3])) {
    place_grid();
    sum_inside(0, object_count_, model_sums_[pose.depth][0], parts.object_frame, parts.object_model);
    sum_inside(object_count_, count_, model_sums_[pose.depth][1], parts.ring_frame, parts.ring_model);
  } else {
    sum_part(0, object_count_, parts.object_frame, parts.object_model);
    sum_part(object_count_, count_, parts.ring_frame, parts.ring_model);
  }
  FrameSums f;
  ImageSums sums;
  parts.compared(surround_, ring, f, sums);
  ring_compared = parts.ring_used(surround_, ring);
  return signed_r2(f, sums, score);
}

bool IntensityCorrelationMeasure::correlate(const Pose& pose, OutlineRing ring, float& signed_r2, bool& ring_compared) const noexcept {
  if (count_ == 0) return correlation_at(frame_, pose, stack_, pose.depth, ring, signed_r2, ring_compared);
  return listed_correlation(pose, ring, signed_r2, ring_compared);
}

Status IntensityCorrelationMeasure::prepare(const ImageView& image, const Pose& predicted) noexcept {
  if (!image.valid() || !valid_focus_stack(stack_)) return Status::kInvalidArgument;
  frame_ = image;
  ring_ = OutlineRing::kLeftOut;
  if (!pose_in_range(predicted) || !within_limit(predicted.theta_deg, 1.0e5f) || predicted.depth >= stack_.images.size())
    return Status::kOk;
  float r2 = 0.0f;
  bool ring_compared = false;
  if (correlate(predicted, OutlineRing::kWhereItAgrees, r2, ring_compared)) ring_ = ring_as_found(ring_compared);
  return Status::kOk;
}

float IntensityCorrelationMeasure::score(const Pose& pose) noexcept {
  if (frame_.pixels == nullptr || !pose_in_range(pose) || !within_limit(pose.theta_deg, 1.0e5f) || pose.depth >= stack_.images.size())
    return 0.0f;
  float r2 = 0.0f;
  bool ring_compared = false;
  if (!correlate(pose, ring_, r2, ring_compared)) return 0.0f;
  const float r = correlation_from_signed_square(r2);
  return r > 0.0f ? r : 0.0f;
}

void IntensityCorrelationMeasure::weigh(std::span<Particle> particles) noexcept {
  for (Particle& p : particles) p.weight = score(p.pose);
}

}  // namespace gabarit
