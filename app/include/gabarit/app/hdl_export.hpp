// The hardware voter's view of a table (hdl/rtl/gbt_voter.sv): references
// split into Lanes banks by cell (cell c lives in lane c % Lanes at local
// address c / Lanes), per-pixel {begin, count} ranges for every lane, and
// stencil sizes clamped to >= 1. `gabarit tables export-hdl` writes it as
// $readmemh images plus a SystemVerilog package; the co-simulation testbench
// loads the same layout through the voter's table port, so both use one code path.
#pragma once

#include <cstdint>
#include <string>
#include <span>
#include <vector>

#include "gabarit/roi_point.hpp"
#include "gabarit/table_view.hpp"

namespace gabarit::app {

struct HdlRange {
  std::uint32_t begin = 0;
  std::uint32_t count = 0;
};

struct HdlLayout {
  std::uint32_t lanes = 1;
  std::uint32_t cell_count = 0;
  std::uint32_t cells_per_lane = 0;  // ceil(cell_count / lanes)
  std::uint16_t roi_width = 0, roi_height = 0;
  std::vector<std::vector<HdlRange>> ranges;      // [pixel][lane]
  std::vector<std::vector<std::uint32_t>> refs;   // [lane] local cell indices
  std::vector<std::vector<std::uint32_t>> sizes;  // [lane] sizes of local cells, clamped to [1, 65535]
  std::uint32_t max_lane_refs() const;
  std::uint32_t max_range_count() const;  // the longest {begin, count} range of any pixel and lane
};

// Throws app::Error for lanes other than 1, 2, 4, 8 or stencils above 65535 pixels.
// With orientation channels (format 1.3) the voter addresses slots: the
// layout's roi_width is the slots per ROI row (roi_width x channels), and
// features go to it as hdl_features gives them.
HdlLayout hdl_layout(const TableView& table, std::uint32_t lanes);

// The kernel's features (prepare_frame) as the hardware voter takes them:
// the same points for a position-only table; with orientation channels,
// each feature's two slots as (slot mod slot-width, slot / slot-width), in
// the kernel voter's order, so the counters match bit for bit.
std::vector<RoiPoint> hdl_features(const TableView& table, std::span<const RoiPoint> features);

// SystemVerilog's $clog2.
constexpr std::uint32_t clog2(std::uint64_t n) {
  std::uint32_t b = 0;
  while ((std::uint64_t{1} << b) < n) ++b;
  return b;
}

// Field widths of gbt_voter for given capacities (its localparams);
// max_range_count 0 means a range may hold every cell of a lane.
struct HdlWidths {
  std::uint32_t offset_bits, count_bits;
  std::uint32_t range_bits() const { return offset_bits + count_bits; }
};
HdlWidths hdl_widths(std::uint32_t lanes, std::uint32_t cell_capacity, std::uint32_t refs_per_lane,
                     std::uint32_t max_range_count = 0);

// Offsets word of one pixel, as 32-bit chunks, least significant first.
std::vector<std::uint32_t> hdl_offsets_word(const HdlLayout& layout, std::uint32_t pixel, const HdlWidths& widths);

// Hardware capacities the images are written for (the voter's CellCapacity,
// PixelCapacity, RefsPerLane); 0 = exactly this table's sizes. range_count
// is the voter's MaxRangeCount: 0 = a range may hold every cell of a lane
// (any table of the capacities fits); narrower offsets words otherwise.
struct HdlCapacities {
  std::uint32_t cells = 0, pixels = 0, refs_per_lane = 0, range_count = 0;
};

// Writes offsets.mem, refs_<k>.mem, sizes_<k>.mem and gabarit_table_pkg.sv
// into `dir`. Throws app::Error if the table exceeds the capacities. Returns a
// one-line summary.
std::string write_hdl_export(const HdlLayout& layout, const std::string& dir, HdlCapacities capacities = {});

}  // namespace gabarit::app
