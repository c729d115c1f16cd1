// Builds a table (docs/table-format.md) from a model and a state space: one
// stencil per cell, the ROI that holds them all, decimation, and the
// pixel -> cells lists in compressed-sparse-row form. Same inputs and seed,
// same bytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "gabarit/host/tables/decimation.hpp"
#include "gabarit/host/tables/model.hpp"
#include "gabarit/host/tables/stencil.hpp"
#include "gabarit/host/tables/state_space.hpp"

namespace gabarit::host {

struct BuildOptions {
  StateSpace space;      // space.depths is taken from the model
  double keep = 1.0;     // fraction of references kept by decimation
  DecimationPolicy decimation;  // which references go when keep < 1
  TranslationPolicy translations = TranslationPolicy::kInsideElseClosest;
  std::uint64_t seed = 1;
  // Store the model's images (when it has them) in the table: the focus
  // stack depth and angle by intensity compare (table format 1.1).
  bool store_model_images = true;
  // Write the pixel offsets compactly (format 1.2: per-block bases and u8 or
  // u16 deltas) when that is smaller; false keeps one u32 per pixel (1.0/1.1).
  bool compact_offsets = true;
  // Orientation channels (format 1.3, docs/table-format.md): 0 for a
  // position-only table, else 2, 4, 8 or 16 channels of edge orientation;
  // needs a model built from images (the orientation of each model point is
  // the model image's edge there, features.hpp's edge_orientation_at).
  std::uint32_t orientation_channels = 0;
  // Called now and then with (cells done, cells total) while stencils are built.
  std::function<void(std::size_t, std::size_t)> progress;
};

// build_table in its three stages, for a caller (or a test) that wants one:
//   compute_stencils  every cell's stencil, in cell index order, and the ROI
//                     that holds them all (stencil.hpp);
//   assemble_csr      decimation (decimation.hpp) and the pixel -> cells
//                     lists, each pixel's cells in increasing order;
//   serialise_table   the bytes, placed by table_format::layout_of.
struct Stencils {
  StateSpace space;                       // with the model's depth count
  std::vector<CellBounds> cells;          // stencil_size is set by assemble_csr
  std::vector<std::vector<Point>> points; // per cell, offsets from the ROI centre
  // With orientation channels, per cell the channel of each point (aligned
  // with points; a pixel may appear once per channel). Empty without.
  std::vector<std::vector<std::uint8_t>> channels;
  std::uint32_t channel_count = 1;        // orientation channels, 1 for none
  std::int32_t roi_min_x = 0, roi_min_y = 0;
  std::uint16_t roi_width = 0, roi_height = 0;
  std::uint64_t references = 0;           // before decimation
  std::uint32_t pixel_of(const Point& p) const {
    return static_cast<std::uint32_t>((p.y - roi_min_y) * roi_width + (p.x - roi_min_x));
  }
  // The slot of point i of cell c: its pixel, times the channels, plus its channel.
  std::uint32_t slot_of(std::size_t c, std::size_t i) const {
    return channels.empty() ? pixel_of(points[c][i]) : pixel_of(points[c][i]) * channel_count + channels[c][i];
  }
  std::uint32_t slots() const { return std::uint32_t{roi_width} * roi_height * channel_count; }
};
struct CsrLists {
  std::vector<std::uint32_t> offsets;  // roi slots (pixels times channels) + 1
  std::vector<std::uint32_t> cells;    // the references
};
Stencils compute_stencils(const ModelStack& model, const BuildOptions& options);
CsrLists assemble_csr(Stencils& stencils, const BuildOptions& options);
std::vector<std::byte> serialise_table(const ModelStack& model, const BuildOptions& options, const Stencils& stencils,
                                       const CsrLists& csr);

// The three stages in turn. Throws app::Error naming the limit a model or a
// space exceeds.
std::vector<std::byte> build_table(const ModelStack& model, const BuildOptions& options);

}  // namespace gabarit::host
