#include "gabarit/host/table_builder.hpp"

#include <algorithm>
#include <cstring>
#include <limits>

#include "gabarit/byte_order.hpp"
#include "gabarit/host/decimation.hpp"
#include "gabarit/host/error.hpp"
#include "gabarit/host/stencil.hpp"
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

}  // namespace

std::vector<std::byte> build_table(const ModelStack& model, const BuildOptions& options) {
  if (model.depths.empty()) throw Error("model has no depth images");
  if (model.depths.size() > tf::kMaxDepths) throw Error("too many focus-stack images");
  StateSpace space = options.space;
  space.depths = static_cast<std::uint16_t>(model.depths.size());
  if (space.cell_count() > tf::kMaxCells) {
    throw Error("state space has " + std::to_string(space.cell_count()) + " cells; the format allows " +
                std::to_string(tf::kMaxCells));
  }
  std::size_t model_points = 0;
  for (const auto& d : model.depths) {
    if (d.empty()) throw Error("a focus-stack image has no feature points");
    model_points += d.size();
    for (const Point& p : d) {
      if (p.x < INT16_MIN || p.x > INT16_MAX || p.y < INT16_MIN || p.y > INT16_MAX) throw Error("model point out of int16 range");
    }
  }
  if (model_points > tf::kMaxModelPoints) throw Error("too many model points");

  // Stencils, cell by cell, and the ROI that holds them all.
  std::vector<CellBounds> cells = space.cells();
  std::vector<std::vector<Point>> stencils(cells.size());
  std::int64_t min_x = std::numeric_limits<std::int64_t>::max(), min_y = min_x;
  std::int64_t max_x = std::numeric_limits<std::int64_t>::min(), max_y = max_x;
  std::uint64_t total = 0;
  // The rotation sweep depends only on (depth, theta cell), shared by the
  // x*y cells that follow one another in index order.
  std::vector<Point> arcs;
  for (std::size_t c = 0; c < cells.size(); ++c) {
    const CellBounds& u = cells[c];
    if (c == 0 || u.depth != cells[c - 1].depth || u.theta_lo_deg != cells[c - 1].theta_lo_deg ||
        u.theta_hi_deg != cells[c - 1].theta_hi_deg) {
      arcs = swept_arcs(model.depths[u.depth], u.theta_lo_deg, u.theta_hi_deg);
    }
    stencils[c] = translate_sweep(arcs, u, options.translations);
    for (const Point& p : stencils[c]) {
      min_x = std::min<std::int64_t>(min_x, p.x);
      max_x = std::max<std::int64_t>(max_x, p.x);
      min_y = std::min<std::int64_t>(min_y, p.y);
      max_y = std::max<std::int64_t>(max_y, p.y);
    }
    total += stencils[c].size();
    if (total > tf::kMaxReferences) throw Error("table would exceed " + std::to_string(tf::kMaxReferences) + " references; use fewer or smaller cells");
    if (options.progress && (c % 64 == 0 || c + 1 == cells.size())) options.progress(c + 1, cells.size());
  }
  const std::int64_t roi_w = max_x - min_x + 1, roi_h = max_y - min_y + 1;
  if (roi_w > 0xFFFF || roi_h > 0xFFFF || roi_w * roi_h > tf::kMaxRoiPixels || min_x < INT16_MIN || min_y < INT16_MIN) {
    throw Error("ROI " + std::to_string(roi_w) + "x" + std::to_string(roi_h) + " is too large for the table format");
  }
  const auto pixel_of = [&](const Point& p) {
    return static_cast<std::uint32_t>((p.y - min_y) * roi_w + (p.x - min_x));
  };
  const auto pixels = static_cast<std::uint32_t>(roi_w * roi_h);

  // Overlap n(p) and decimation, in (cell, pixel) order.
  std::vector<std::uint32_t> cover(pixels, 0);
  for (const auto& s : stencils)
    for (const Point& p : s) ++cover[pixel_of(p)];
  std::vector<std::uint32_t> overlap;
  overlap.reserve(total);
  for (const auto& s : stencils)
    for (const Point& p : s) overlap.push_back(cover[pixel_of(p)]);
  const std::vector<bool> kept = decimate(overlap, options.keep, options.seed, options.decimation);

  // CSR: count per pixel, prefix sums, then fill in increasing cell order so
  // each pixel's list is strictly increasing.
  std::vector<std::uint32_t> offsets(pixels + 1, 0);
  std::size_t i = 0;
  for (std::size_t c = 0; c < stencils.size(); ++c) {
    std::uint32_t size = 0;
    for (const Point& p : stencils[c]) {
      if (kept[i++]) {
        ++offsets[pixel_of(p) + 1];
        ++size;
      }
    }
    cells[c].stencil_size = size;
  }
  for (std::uint32_t p = 0; p < pixels; ++p) offsets[p + 1] += offsets[p];
  const std::uint32_t references = offsets[pixels];
  std::vector<std::uint32_t> refs(references);
  std::vector<std::uint32_t> fill(offsets.begin(), offsets.end() - 1);
  i = 0;
  for (std::size_t c = 0; c < stencils.size(); ++c)
    for (const Point& p : stencils[c])
      if (kept[i++]) refs[fill[pixel_of(p)]++] = static_cast<std::uint32_t>(c);

  // Serialise.
  const auto cell_count = static_cast<std::uint32_t>(cells.size());
  const std::uint8_t ref_bytes = tf::narrowest_reference_bytes(cell_count);
  std::uint32_t at = tf::kHeaderBytes;
  const std::uint32_t cells_at = at;
  at = tf::align_up(at + cell_count * tf::kCellDescriptorBytes);
  const std::uint32_t offsets_at = at;
  at = tf::align_up(at + (pixels + 1) * 4);
  const std::uint32_t refs_at = at;
  at = tf::align_up(at + references * ref_bytes);
  const std::uint32_t counts_at = at;
  at = tf::align_up(at + static_cast<std::uint32_t>(model.depths.size()) * 4);
  const std::uint32_t points_at = at;
  at = tf::align_up(at + static_cast<std::uint32_t>(model_points) * tf::kModelPointBytes);

  std::vector<std::byte> out(at, std::byte{0});
  std::byte* b = out.data();
  std::memcpy(b + off::kMagic, tf::kMagic, sizeof tf::kMagic);
  store_le<std::uint16_t>(b + off::kVersionMajor, tf::kVersionMajor);
  store_le<std::uint16_t>(b + off::kVersionMinor, tf::kVersionMinor);
  store_le<std::uint32_t>(b + off::kHeaderBytes, tf::kHeaderBytes);
  store_le<std::uint32_t>(b + off::kFileBytes, at);
  store_le<std::uint32_t>(b + off::kCellCount, cell_count);
  store_le<std::uint32_t>(b + off::kReferenceCount, references);
  store_le<std::uint16_t>(b + off::kRoiWidth, static_cast<std::uint16_t>(roi_w));
  store_le<std::uint16_t>(b + off::kRoiHeight, static_cast<std::uint16_t>(roi_h));
  store_le<std::int16_t>(b + off::kRoiOriginX, static_cast<std::int16_t>(min_x));
  store_le<std::int16_t>(b + off::kRoiOriginY, static_cast<std::int16_t>(min_y));
  store_le<std::uint8_t>(b + off::kReferenceBytes, ref_bytes);
  store_le<std::uint8_t>(b + off::kDetectorKind, static_cast<std::uint8_t>(model.detector.kind));
  store_le<std::uint16_t>(b + off::kDetectorThreshold, model.detector.threshold);
  std::uint32_t max_stencil = 0;
  for (const CellBounds& c : cells) max_stencil = std::max(max_stencil, c.stencil_size);
  store_le<std::uint32_t>(b + off::kMaxStencilSize, max_stencil);
  store_le<std::uint32_t>(b + off::kModelPointCount, static_cast<std::uint32_t>(model_points));
  store_le<std::uint16_t>(b + off::kDepthCount, static_cast<std::uint16_t>(model.depths.size()));
  put_axis(b + off::kAxisX, space.x);
  put_axis(b + off::kAxisY, space.y);
  put_axis(b + off::kAxisTheta, space.theta);
  store_le<float>(b + off::kKeepRatio, static_cast<float>(options.keep));
  store_le<float>(b + off::kModelRefX, model.ref_x);
  store_le<float>(b + off::kModelRefY, model.ref_y);
  store_le<std::uint16_t>(b + off::kModelWidth, model.image_width);
  store_le<std::uint16_t>(b + off::kModelHeight, model.image_height);
  store_le<std::uint64_t>(b + off::kSeed, options.seed);
  store_le<std::uint32_t>(b + off::kCellsOffset, cells_at);
  store_le<std::uint32_t>(b + off::kPixelOffsetsOffset, offsets_at);
  store_le<std::uint32_t>(b + off::kReferencesOffset, refs_at);
  store_le<std::uint32_t>(b + off::kModelCountsOffset, counts_at);
  store_le<std::uint32_t>(b + off::kModelPointsOffset, points_at);

  namespace co = tf::cell_offset;
  for (std::uint32_t c = 0; c < cell_count; ++c) {
    std::byte* d = b + cells_at + std::size_t{c} * tf::kCellDescriptorBytes;
    store_le<float>(d + co::kXLo, cells[c].x_lo);
    store_le<float>(d + co::kXHi, cells[c].x_hi);
    store_le<float>(d + co::kYLo, cells[c].y_lo);
    store_le<float>(d + co::kYHi, cells[c].y_hi);
    store_le<float>(d + co::kThetaLo, cells[c].theta_lo_deg);
    store_le<float>(d + co::kThetaHi, cells[c].theta_hi_deg);
    store_le<std::uint16_t>(d + co::kDepth, cells[c].depth);
    store_le<std::uint32_t>(d + co::kStencilSize, cells[c].stencil_size);
  }
  for (std::uint32_t p = 0; p <= pixels; ++p) store_le<std::uint32_t>(b + offsets_at + std::size_t{p} * 4, offsets[p]);
  for (std::uint32_t r = 0; r < references; ++r) {
    std::byte* d = b + refs_at + std::size_t{r} * ref_bytes;
    switch (ref_bytes) {
      case 1: store_le<std::uint8_t>(d, static_cast<std::uint8_t>(refs[r])); break;
      case 2: store_le<std::uint16_t>(d, static_cast<std::uint16_t>(refs[r])); break;
      default: store_le<std::uint32_t>(d, refs[r]); break;
    }
  }
  std::size_t k = 0;
  for (std::size_t d = 0; d < model.depths.size(); ++d) {
    store_le<std::uint32_t>(b + counts_at + d * 4, static_cast<std::uint32_t>(model.depths[d].size()));
    for (const Point& p : model.depths[d]) {
      store_le<std::int16_t>(b + points_at + k * 4, static_cast<std::int16_t>(p.x));
      store_le<std::int16_t>(b + points_at + k * 4 + 2, static_cast<std::int16_t>(p.y));
      ++k;
    }
  }
  store_le<std::uint32_t>(b + off::kCrc32, table_checksum(out));
  return out;
}

}  // namespace gabarit::host
