#include "gabarit/host/tables/table_builder.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "gabarit/byte_order.hpp"
#include "gabarit/deterministic_math.hpp"
#include "gabarit/features.hpp"
#include "gabarit/host/tables/decimation.hpp"
#include "gabarit/app/error.hpp"
#include "gabarit/host/tables/stencil.hpp"
#include "gabarit/table_format.hpp"
#include "gabarit/table_view.hpp"

namespace gabarit::host {
namespace {

namespace tf = table_format;
namespace off = tf::offset;

void put_axis(std::byte* at, const Axis& a) {
  store_le<float>(at, a.min);
  store_le<float>(at + 4, a.max);
  store_le<std::uint32_t>(at + 8, a.cells);
}

// The compact offset encoding (format 1.2) when it is smaller than u32
// offsets: u8 deltas where every 128-pixel block lists fewer than 256
// references, else u16 where fewer than 65536, else none.
void choose_offset_encoding(const std::vector<std::uint32_t>& offsets, tf::LayoutCounts& counts) {
  const std::uint32_t pixels = counts.roi_pixels;
  std::uint32_t widest = 0, non_empty = 0;
  for (std::uint32_t first = 0; first < pixels; first += tf::kOffsetBlockPixels) {
    const std::uint32_t last = std::min(pixels, first + tf::kOffsetBlockPixels);
    widest = std::max(widest, offsets[last] - offsets[first]);
  }
  for (std::uint32_t p = 0; p < pixels; ++p) non_empty += offsets[p + 1] > offsets[p];
  if (widest > 0xFFFF) return;
  tf::LayoutCounts c = counts;
  c.offset_delta_bytes = widest <= 0xFF ? 1 : 2;
  c.offset_delta_count = non_empty;
  if (tf::pixel_offsets_bytes(c) < tf::pixel_offsets_bytes(counts)) counts = c;
}

}  // namespace

namespace {

// The ROI's reach beyond the format's window limit, as the error that says so.
app::Error roi_too_far(double reach) {
  return app::Error("the ROI reaches " + std::to_string(static_cast<long>(std::ceil(reach))) +
                    " px from the reference point; a table may reach at most " + std::to_string((tf::kMaxRoiWindowSide - 1) / 2) +
                    " px (the tracker's scratch grows with its square): put the reference point on the object (--ref) or "
                    "narrow --x/--y");
}

// The model and the space against the format's limits, before anything
// large is allocated (the exact ROI window is checked once the stencils are known).
void check_limits(const ModelStack& model, const StateSpace& space, const BuildOptions& options) {
  std::size_t model_points = 0;
  for (const auto& d : model.depths) {
    if (d.empty()) throw app::Error("a focus-stack image has no feature points");
    model_points += d.size();
    for (const Point& p : d) {
      if (p.x < INT16_MIN || p.x > INT16_MAX || p.y < INT16_MIN || p.y > INT16_MAX) throw app::Error("model point out of int16 range");
    }
  }
  if (model_points > tf::kMaxModelPoints) throw app::Error("too many model points");
  // The limits (docs/table-format.md, "Limits"). The ROI holds the model
  // moved by every translation of the space, so it reaches at least as far
  // from the reference point as the farthest model point and as the largest
  // translation: a space beyond the window limit even so is refused before
  // anything large is allocated (the exact window is checked below).
  std::int64_t model_reach2 = 0;
  for (const auto& d : model.depths)
    for (const Point& p : d) model_reach2 = std::max<std::int64_t>(model_reach2, std::int64_t{p.x} * p.x + std::int64_t{p.y} * p.y);
  const double shift = std::max({std::fabs(space.x.min), std::fabs(space.x.max), std::fabs(space.y.min),
                                 std::fabs(space.y.max)});
  const double reach_at_least = std::max(std::sqrt(static_cast<double>(model_reach2)), shift);
  if (2.0 * std::ceil(reach_at_least) + 1.0 > tf::kMaxRoiWindowSide) throw roi_too_far(reach_at_least);
  if (!(std::fabs(model.ref_x) <= tf::kMaxModelRef && std::fabs(model.ref_y) <= tf::kMaxModelRef)) {
    throw app::Error("the reference point must lie within +-" + std::to_string(static_cast<int>(tf::kMaxModelRef)) + " px");
  }
  // Every stencil holds at least about the model's points (the model moved
  // by the cell's centre), so a space that would exceed the reference limit
  // even so is refused now rather than after gigabytes of stencils.
  std::uint64_t at_least = 0;
  const std::uint64_t cells_per_depth = space.cell_count() / space.depths;
  for (const auto& d : model.depths) at_least += cells_per_depth * (d.size() / 2);
  if (at_least > tf::kMaxReferences) {
    throw app::Error("state space of " + std::to_string(space.cell_count()) + " cells x " + std::to_string(model_points) +
                     " model points would exceed " + std::to_string(tf::kMaxReferences) + " references; use fewer or larger cells");
  }
  if (!(static_cast<float>(options.keep) > 0.0f)) throw app::Error("--keep is too small to store (below 1e-38)");

}

// Each model point's edge orientation (orientation_256), per depth; empty
// without orientation channels.
std::vector<std::vector<std::uint8_t>> point_orientations(const ModelStack& model, std::uint32_t channels) {
  if (channels != 0 && !tf::valid_orientation_channels(channels)) throw app::Error("orientation channels: want 2, 4, 8 or 16");
  if (channels != 0 && model.images.size() != model.depths.size())
    throw app::Error("orientation channels need a model built from images (each point's orientation is the image's edge there)");
  if (channels != 0 && model.detector.kind == tf::DetectorKind::kBinary)
    throw app::Error("orientation channels need a gradient detector (--canny or --gradient), not --binary");
  std::vector<std::vector<std::uint8_t>> orientation(model.depths.size());
  if (channels != 0) {
    for (std::size_t d = 0; d < model.depths.size(); ++d) {
      const ImageView img{model.images[d].data(), model.image_width, model.image_height, model.image_width};
      for (const Point& p : model.depths[d])
        orientation[d].push_back(edge_orientation_at(img, round_to_int(model.ref_x + static_cast<float>(p.x)),
                                                     round_to_int(model.ref_y + static_cast<float>(p.y))));
    }
  }
  return orientation;
}

// With channels: per channel, the arcs of the points whose orientation,
// turned by any angle of the cell's theta range, lies in that channel.
std::vector<std::vector<Point>> channel_sweeps(const std::vector<Point>& points, const std::vector<std::uint8_t>& orientation,
                                               const CellBounds& u, std::uint32_t channels) {
  std::vector<std::vector<Point>> members(channels);
  const double width = 256.0 / channels;  // orientation steps per channel
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double lo = orientation[i] + u.theta_lo_deg * (256.0 / 180.0);
    const double hi = orientation[i] + u.theta_hi_deg * (256.0 / 180.0);
    const auto first = static_cast<std::int64_t>(std::floor(lo / width)), last = static_cast<std::int64_t>(std::floor(hi / width));
    for (std::int64_t k = first; k <= last && k < first + channels; ++k)
      members[static_cast<std::size_t>(((k % channels) + channels) % channels)].push_back(points[i]);
  }
  std::vector<std::vector<Point>> channel_arcs(channels);
  for (std::uint32_t k = 0; k < channels; ++k)
    if (!members[k].empty()) channel_arcs[k] = swept_arcs(members[k], u.theta_lo_deg, u.theta_hi_deg);
  return channel_arcs;
}

// A cell's stencil with channels: its points in (x, y, channel) order.
void channel_stencil(const std::vector<std::vector<Point>>& channel_arcs, const CellBounds& u, TranslationPolicy translations,
                     std::vector<Point>& points, std::vector<std::uint8_t>& point_channels) {
  std::vector<std::pair<Point, std::uint8_t>> all;
  for (std::uint32_t k = 0; k < channel_arcs.size(); ++k) {
    if (channel_arcs[k].empty()) continue;
    for (const Point& p : translate_sweep(channel_arcs[k], u, translations)) all.push_back({p, static_cast<std::uint8_t>(k)});
  }
  std::sort(all.begin(), all.end(), [](const auto& a, const auto& b) {
    return a.first.x != b.first.x ? a.first.x < b.first.x : a.first.y != b.first.y ? a.first.y < b.first.y : a.second < b.second;
  });
  points.clear();
  point_channels.clear();
  for (const auto& [p, k] : all) {
    points.push_back(p);
    point_channels.push_back(k);
  }
}

}  // namespace

Stencils compute_stencils(const ModelStack& model, const BuildOptions& options) {
  if (model.depths.empty()) throw app::Error("model has no depth images");
  if (model.depths.size() > tf::kMaxDepths) throw app::Error("too many focus-stack images");
  Stencils out;
  out.space = options.space;
  out.space.depths = static_cast<std::uint16_t>(model.depths.size());
  if (out.space.cell_count() > tf::kMaxCells) {
    throw app::Error("state space has " + std::to_string(out.space.cell_count()) + " cells; the format allows " +
                     std::to_string(tf::kMaxCells));
  }
  check_limits(model, out.space, options);
  const std::uint32_t channels = options.orientation_channels;
  const std::vector<std::vector<std::uint8_t>> orientation = point_orientations(model, channels);
  out.cells = out.space.cells();
  out.points.resize(out.cells.size());
  out.channel_count = channels == 0 ? 1u : channels;
  if (channels != 0) out.channels.resize(out.cells.size());
  std::vector<std::vector<Point>> channel_arcs;  // with channels: the current sweep's, per channel
  std::int64_t min_x = std::numeric_limits<std::int64_t>::max(), min_y = min_x;
  std::int64_t max_x = std::numeric_limits<std::int64_t>::min(), max_y = max_x;
  // The rotation sweep depends only on (depth, theta cell), shared by the
  // x*y cells that follow one another in index order.
  std::vector<Point> arcs;
  for (std::size_t c = 0; c < out.cells.size(); ++c) {
    const CellBounds& u = out.cells[c];
    const bool new_sweep = c == 0 || u.depth != out.cells[c - 1].depth || u.theta_lo_deg != out.cells[c - 1].theta_lo_deg ||
                           u.theta_hi_deg != out.cells[c - 1].theta_hi_deg;
    if (channels == 0) {
      if (new_sweep) arcs = swept_arcs(model.depths[u.depth], u.theta_lo_deg, u.theta_hi_deg);
      out.points[c] = translate_sweep(arcs, u, options.translations);
    } else {
      if (new_sweep) channel_arcs = channel_sweeps(model.depths[u.depth], orientation[u.depth], u, channels);
      channel_stencil(channel_arcs, u, options.translations, out.points[c], out.channels[c]);
    }
    for (const Point& p : out.points[c]) {
      min_x = std::min<std::int64_t>(min_x, p.x);
      max_x = std::max<std::int64_t>(max_x, p.x);
      min_y = std::min<std::int64_t>(min_y, p.y);
      max_y = std::max<std::int64_t>(max_y, p.y);
    }
    out.references += out.points[c].size();
    if (out.references > tf::kMaxReferences) throw app::Error("table would exceed " + std::to_string(tf::kMaxReferences) + " references; use fewer or smaller cells");
    if (options.progress && (c % 64 == 0 || c + 1 == out.cells.size())) options.progress(c + 1, out.cells.size());
  }
  const std::int64_t roi_w = max_x - min_x + 1, roi_h = max_y - min_y + 1;
  if (roi_w > 0xFFFF || roi_h > 0xFFFF || roi_w * roi_h * out.channel_count > tf::kMaxRoiPixels || min_x < INT16_MIN ||
      min_y < INT16_MIN) {
    throw app::Error("ROI " + std::to_string(roi_w) + "x" + std::to_string(roi_h) + " is too large for the table format");
  }
  const std::uint32_t window = tf::roi_window_side(static_cast<std::uint16_t>(roi_w), static_cast<std::uint16_t>(roi_h),
                                                   static_cast<std::int16_t>(min_x), static_cast<std::int16_t>(min_y));
  if (window > tf::kMaxRoiWindowSide) throw roi_too_far((window - 1) / 2.0);
  out.roi_min_x = static_cast<std::int32_t>(min_x);
  out.roi_min_y = static_cast<std::int32_t>(min_y);
  out.roi_width = static_cast<std::uint16_t>(roi_w);
  out.roi_height = static_cast<std::uint16_t>(roi_h);
  return out;
}

CsrLists assemble_csr(Stencils& stencils, const BuildOptions& options) {
  const std::uint32_t pixels = stencils.slots();
  // Decimation, in (cell, slot) order. With orientation channels a row of
  // the ROI is roi_width x channels slots wide (decimation's neighbourhoods
  // then run along the slots of a row).
  StencilPixels pixel_lists;
  pixel_lists.roi_width = static_cast<std::uint32_t>(stencils.roi_width) * stencils.channel_count;
  pixel_lists.roi_height = stencils.roi_height;
  pixel_lists.cells.resize(stencils.points.size());
  for (std::size_t c = 0; c < stencils.points.size(); ++c) {
    pixel_lists.cells[c].reserve(stencils.points[c].size());
    for (std::size_t k = 0; k < stencils.points[c].size(); ++k) pixel_lists.cells[c].push_back(stencils.slot_of(c, k));
  }
  const std::vector<bool> kept = decimate(pixel_lists, options.keep, options.seed, options.decimation);

  // CSR: count per pixel, prefix sums, then fill in increasing cell order so
  // each pixel's list is strictly increasing.
  CsrLists csr;
  csr.offsets.assign(pixels + 1, 0);
  std::size_t i = 0;
  for (std::size_t c = 0; c < stencils.points.size(); ++c) {
    std::uint32_t size = 0;
    for (std::size_t k = 0; k < stencils.points[c].size(); ++k) {
      if (kept[i++]) {
        ++csr.offsets[stencils.slot_of(c, k) + 1];
        ++size;
      }
    }
    stencils.cells[c].stencil_size = size;
  }
  for (std::uint32_t p = 0; p < pixels; ++p) csr.offsets[p + 1] += csr.offsets[p];
  csr.cells.resize(csr.offsets[pixels]);
  std::vector<std::uint32_t> fill(csr.offsets.begin(), csr.offsets.end() - 1);
  i = 0;
  for (std::size_t c = 0; c < stencils.points.size(); ++c)
    for (std::size_t k = 0; k < stencils.points[c].size(); ++k)
      if (kept[i++]) csr.cells[fill[stencils.slot_of(c, k)]++] = static_cast<std::uint32_t>(c);
  return csr;
}

namespace {

// The cell descriptors (docs/table-format.md), in cell index order.
void write_cells(std::byte* at, const std::vector<CellBounds>& cells) {
  namespace co = tf::cell_offset;
  for (std::size_t c = 0; c < cells.size(); ++c) {
    std::byte* d = at + c * tf::kCellDescriptorBytes;
    store_le<float>(d + co::kXLo, cells[c].x_lo);
    store_le<float>(d + co::kXHi, cells[c].x_hi);
    store_le<float>(d + co::kYLo, cells[c].y_lo);
    store_le<float>(d + co::kYHi, cells[c].y_hi);
    store_le<float>(d + co::kThetaLo, cells[c].theta_lo_deg);
    store_le<float>(d + co::kThetaHi, cells[c].theta_hi_deg);
    store_le<std::uint16_t>(d + co::kDepth, cells[c].depth);
    store_le<std::uint32_t>(d + co::kStencilSize, cells[c].stencil_size);
  }
}

// The CSR offsets: wide (one u32 per slot, delta_bytes 0) or compact (per
// 128-slot block: base, rank, mask; then each non-empty slot's end less its
// block's base, in delta_bytes).
void write_offsets(std::byte* at, const std::vector<std::uint32_t>& offsets, std::uint32_t pixels, std::uint8_t delta_bytes) {
  if (delta_bytes == 0) {
    for (std::uint32_t p = 0; p <= pixels; ++p) store_le<std::uint32_t>(at + std::size_t{p} * 4, offsets[p]);
    return;
  }
  std::byte* blocks = at;
  std::byte* deltas = blocks + std::size_t{tf::offset_block_count(pixels)} * tf::kOffsetBlockHeaderBytes;
  std::uint32_t rank = 0;
  for (std::uint32_t block = 0; block < tf::offset_block_count(pixels); ++block) {
    const std::uint32_t first = block * tf::kOffsetBlockPixels, base = offsets[first];
    std::uint64_t mask[2] = {0, 0};
    const std::uint32_t block_rank = rank;
    for (std::uint32_t p = first; p < std::min(pixels, first + tf::kOffsetBlockPixels); ++p) {
      if (offsets[p + 1] == offsets[p]) continue;
      mask[(p - first) / 64] |= std::uint64_t{1} << ((p - first) % 64);
      const std::uint32_t end = offsets[p + 1] - base;
      if (delta_bytes == 1) store_le<std::uint8_t>(deltas + rank, static_cast<std::uint8_t>(end));
      else store_le<std::uint16_t>(deltas + std::size_t{rank} * 2, static_cast<std::uint16_t>(end));
      ++rank;
    }
    std::byte* h = blocks + std::size_t{block} * tf::kOffsetBlockHeaderBytes;
    store_le<std::uint32_t>(h, base);
    store_le<std::uint32_t>(h + 4, block_rank);
    store_le<std::uint64_t>(h + 8, mask[0]);
    store_le<std::uint64_t>(h + 16, mask[1]);
  }
}

// The reference lists' cells, each in ref_bytes.
void write_references(std::byte* at, const std::vector<std::uint32_t>& cells, std::uint8_t ref_bytes) {
  for (std::size_t r = 0; r < cells.size(); ++r) {
    std::byte* d = at + r * ref_bytes;
    switch (ref_bytes) {
      case 1: store_le<std::uint8_t>(d, static_cast<std::uint8_t>(cells[r])); break;
      case 2: store_le<std::uint16_t>(d, static_cast<std::uint16_t>(cells[r])); break;
      default: store_le<std::uint32_t>(d, cells[r]); break;
    }
  }
}

// Per depth its point count, then every depth's points as int16 pairs.
void write_model_points(std::byte* counts_at, std::byte* points_at, const ModelStack& model) {
  std::size_t k = 0;
  for (std::size_t d = 0; d < model.depths.size(); ++d) {
    store_le<std::uint32_t>(counts_at + d * 4, static_cast<std::uint32_t>(model.depths[d].size()));
    for (const Point& p : model.depths[d]) {
      store_le<std::int16_t>(points_at + k * 4, static_cast<std::int16_t>(p.x));
      store_le<std::int16_t>(points_at + k * 4 + 2, static_cast<std::int16_t>(p.y));
      ++k;
    }
  }
}

}  // namespace

std::vector<std::byte> serialise_table(const ModelStack& model, const BuildOptions& options, const Stencils& stencils,
                                       const CsrLists& csr) {
  const std::vector<CellBounds>& cells = stencils.cells;
  const auto cell_count = static_cast<std::uint32_t>(cells.size());
  const std::uint32_t pixels = stencils.slots();
  const bool channels = stencils.channel_count > 1;
  const auto references = static_cast<std::uint32_t>(csr.cells.size());
  std::uint32_t model_points = 0;
  for (const auto& d : model.depths) model_points += static_cast<std::uint32_t>(d.size());
  const std::uint8_t ref_bytes = tf::narrowest_reference_bytes(cell_count);
  const bool images = options.store_model_images && !model.images.empty();
  std::uint64_t image_bytes = 0;
  if (images) {
    if (model.images.size() != model.depths.size()) throw app::Error("table: one model image per depth expected");
    image_bytes = std::uint64_t{model.image_width} * model.image_height * model.images.size();
    for (const auto& image : model.images)
      if (image.size() != std::size_t{model.image_width} * model.image_height) throw app::Error("table: model image of the wrong size");
    if (image_bytes > tf::kMaxModelImageBytes)
      throw app::Error("table: the model images take " + std::to_string(image_bytes) + " bytes, above the format's " +
                       std::to_string(tf::kMaxModelImageBytes) + "; build with --no-model-images");
  }
  tf::LayoutCounts counts{cell_count, pixels, references, ref_bytes, static_cast<std::uint16_t>(model.depths.size()),
                          model_points, static_cast<std::uint32_t>(image_bytes)};
  if (options.compact_offsets) choose_offset_encoding(csr.offsets, counts);
  const bool compact = counts.offset_delta_bytes != 0;
  const tf::Layout layout = tf::layout_of(counts);

  std::vector<std::byte> out(layout.file_bytes, std::byte{0});
  std::byte* b = out.data();
  std::memcpy(b + off::kMagic, tf::kMagic, sizeof tf::kMagic);
  store_le<std::uint16_t>(b + off::kVersionMajor, tf::kVersionMajor);
  // The lowest minor version that holds what the table uses.
  store_le<std::uint16_t>(b + off::kVersionMinor,
                          channels ? std::uint16_t{3} : compact ? std::uint16_t{2} : images ? std::uint16_t{1} : std::uint16_t{0});
  store_le<std::uint32_t>(b + off::kHeaderBytes, tf::kHeaderBytes);
  store_le<std::uint32_t>(b + off::kFileBytes, layout.file_bytes);
  store_le<std::uint32_t>(b + off::kCellCount, cell_count);
  store_le<std::uint32_t>(b + off::kReferenceCount, references);
  store_le<std::uint16_t>(b + off::kRoiWidth, stencils.roi_width);
  store_le<std::uint16_t>(b + off::kRoiHeight, stencils.roi_height);
  store_le<std::int16_t>(b + off::kRoiOriginX, static_cast<std::int16_t>(stencils.roi_min_x));
  store_le<std::int16_t>(b + off::kRoiOriginY, static_cast<std::int16_t>(stencils.roi_min_y));
  store_le<std::uint8_t>(b + off::kReferenceBytes, ref_bytes);
  store_le<std::uint8_t>(b + off::kDetectorKind, static_cast<std::uint8_t>(model.detector.kind));
  store_le<std::uint16_t>(b + off::kDetectorThreshold, model.detector.threshold);
  std::uint32_t max_stencil = 0;
  for (const CellBounds& c : cells) max_stencil = std::max(max_stencil, c.stencil_size);
  store_le<std::uint32_t>(b + off::kMaxStencilSize, max_stencil);
  store_le<std::uint32_t>(b + off::kModelPointCount, model_points);
  store_le<std::uint16_t>(b + off::kDepthCount, static_cast<std::uint16_t>(model.depths.size()));
  put_axis(b + off::kAxisX, stencils.space.x);
  put_axis(b + off::kAxisY, stencils.space.y);
  put_axis(b + off::kAxisTheta, stencils.space.theta);
  store_le<float>(b + off::kKeepRatio, static_cast<float>(options.keep));
  store_le<float>(b + off::kModelRefX, model.ref_x);
  store_le<float>(b + off::kModelRefY, model.ref_y);
  store_le<std::uint16_t>(b + off::kModelWidth, model.image_width);
  store_le<std::uint16_t>(b + off::kModelHeight, model.image_height);
  store_le<std::uint64_t>(b + off::kSeed, options.seed);
  store_le<std::uint32_t>(b + off::kCellsOffset, layout.cells);
  store_le<std::uint32_t>(b + off::kPixelOffsetsOffset, layout.pixel_offsets);
  store_le<std::uint32_t>(b + off::kReferencesOffset, layout.references);
  store_le<std::uint32_t>(b + off::kModelCountsOffset, layout.model_counts);
  store_le<std::uint32_t>(b + off::kModelPointsOffset, layout.model_points);
  store_le<std::uint32_t>(b + off::kFlags, (images ? tf::kFlagModelImages : 0u) | (compact ? tf::kFlagCompactOffsets : 0u) |
                                               (channels ? tf::kFlagOrientationChannels : 0u));
  if (channels) store_le<std::uint8_t>(b + off::kOrientationChannels, static_cast<std::uint8_t>(stencils.channel_count));
  if (compact) {
    store_le<std::uint8_t>(b + off::kOffsetDeltaBytes, counts.offset_delta_bytes);
    store_le<std::uint8_t>(b + off::kOffsetBlockLog2, tf::kOffsetBlockLog2);
    store_le<std::uint32_t>(b + off::kOffsetDeltaCount, counts.offset_delta_count);
  }
  if (images) {
    store_le<std::uint32_t>(b + off::kModelImagesOffset, layout.model_images);
    for (std::size_t d = 0; d < model.images.size(); ++d)
      std::memcpy(b + layout.model_images + d * model.images[d].size(), model.images[d].data(), model.images[d].size());
  }

  write_cells(b + layout.cells, cells);
  write_offsets(b + layout.pixel_offsets, csr.offsets, pixels, counts.offset_delta_bytes);
  write_references(b + layout.references, csr.cells, ref_bytes);
  write_model_points(b + layout.model_counts, b + layout.model_points, model);
  store_le<std::uint32_t>(b + off::kCrc32, table_checksum(out));
  return out;
}

std::vector<std::byte> build_table(const ModelStack& model, const BuildOptions& options) {
  Stencils stencils = compute_stencils(model, options);
  const CsrLists csr = assemble_csr(stencils, options);
  if (csr.cells.empty()) {
    throw app::Error("decimation kept none of the " + std::to_string(stencils.references) + " references; use a larger --keep");
  }
  return serialise_table(model, options, stencils, csr);
}

}  // namespace gabarit::host
