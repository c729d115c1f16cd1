#include "gabarit/app/hdl_export.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "gabarit/app/error.hpp"
#include "gabarit/app/files.hpp"

namespace gabarit::app {

std::uint32_t HdlLayout::max_lane_refs() const {
  std::size_t m = 0;
  for (const auto& r : refs) m = std::max(m, r.size());
  return static_cast<std::uint32_t>(m);
}

std::uint32_t HdlLayout::max_range_count() const {
  std::uint32_t m = 0;
  for (const auto& pixel : ranges)
    for (const HdlRange& r : pixel) m = std::max(m, r.count);
  return m;
}

std::vector<RoiPoint> hdl_features(const TableView& t, std::span<const RoiPoint> features) {
  if (t.channel_bits() == 0) return {features.begin(), features.end()};
  const std::uint32_t slot_width = t.roi_width() * t.orientation_channels();
  std::vector<RoiPoint> out;
  out.reserve(2 * features.size());
  for (const RoiPoint& f : features) {
    const FeatureSlots s = feature_slots(f.col, f.row, t.roi_width(), t.channel_bits());
    for (const std::uint32_t slot : {s.first, s.second})
      out.push_back({static_cast<std::uint16_t>(slot % slot_width), static_cast<std::uint16_t>(slot / slot_width)});
  }
  return out;
}

HdlLayout hdl_layout(const TableView& t, std::uint32_t lanes) {
  if (lanes != 1 && lanes != 2 && lanes != 4 && lanes != 8) throw app::Error("--lanes must be 1, 2, 4 or 8");
  HdlLayout l;
  l.lanes = lanes;
  l.cell_count = t.cell_count();
  l.cells_per_lane = (t.cell_count() + lanes - 1) / lanes;
  l.roi_width = t.roi_width() * t.orientation_channels();  // slots per row (docs/table-format.md, 1.3)
  l.roi_height = t.roi_height();
  l.refs.assign(lanes, {});
  l.sizes.assign(lanes, std::vector<std::uint32_t>(l.cells_per_lane, 1));
  l.ranges.assign(t.roi_slots(), std::vector<HdlRange>(lanes));
  for (std::uint32_t p = 0; p < t.roi_slots(); ++p) {
    for (std::uint32_t k = 0; k < lanes; ++k) l.ranges[p][k].begin = static_cast<std::uint32_t>(l.refs[k].size());
    // Cells of a pixel increase, so each lane's sub-list increases too.
    for (std::uint32_t i = t.references_begin(p); i < t.references_begin(p + 1); ++i) {
      const std::uint32_t c = t.reference(i);
      l.refs[c % lanes].push_back(c / lanes);
      ++l.ranges[p][c % lanes].count;
    }
  }
  for (std::uint32_t c = 0; c < t.cell_count(); ++c) {
    const std::uint32_t s = t.stencil_size(c);
    if (s > 0xFFFF) throw app::Error("stencil of cell " + std::to_string(c) + " has " + std::to_string(s) + " pixels; the hardware voter's size field holds 65535");
    l.sizes[c % lanes][c / lanes] = std::max<std::uint32_t>(1, s);
  }
  return l;
}

HdlWidths hdl_widths(std::uint32_t lanes, std::uint32_t cell_capacity, std::uint32_t refs_per_lane,
                     std::uint32_t max_range_count) {
  const std::uint32_t cells_per_lane = (cell_capacity + lanes - 1) / lanes;
  const std::uint32_t count_max = max_range_count == 0 ? cells_per_lane : max_range_count;
  return {clog2(std::uint64_t{refs_per_lane} + 1), clog2(std::uint64_t{count_max} + 1)};
}

std::vector<std::uint32_t> hdl_offsets_word(const HdlLayout& l, std::uint32_t pixel, const HdlWidths& w) {
  const std::uint32_t bits = l.lanes * w.range_bits();
  std::vector<std::uint32_t> word((bits + 31) / 32, 0);
  const auto put = [&](std::uint32_t at, std::uint64_t value, std::uint32_t width) {
    for (std::uint32_t b = 0; b < width; ++b)
      if ((value >> b) & 1u) word[(at + b) / 32] |= 1u << ((at + b) % 32);
  };
  for (std::uint32_t k = 0; k < l.lanes; ++k) {
    const HdlRange& r = l.ranges[pixel][k];
    if (r.begin >= (1ull << w.offset_bits) || r.count >= (1ull << w.count_bits)) throw app::Error("range does not fit the voter's widths");
    put(k * w.range_bits(), r.count, w.count_bits);
    put(k * w.range_bits() + w.count_bits, r.begin, w.offset_bits);
  }
  return word;
}

namespace {

void write_mem(const std::string& path, const std::vector<std::vector<std::uint32_t>>& words, std::uint32_t bits,
               const std::string& what) {
  std::ostringstream f;
  f << "// " << what << ": " << words.size() << " words of " << bits << " bits ($readmemh)\n";
  const std::uint32_t digits = (bits + 3) / 4;
  for (const auto& w : words) {
    std::string hex(digits, '0');
    for (std::uint32_t d = 0; d < digits; ++d) {
      const std::uint32_t nibble = (w[(d * 4) / 32] >> ((d * 4) % 32)) & 0xF;
      hex[digits - 1 - d] = "0123456789abcdef"[nibble];
    }
    f << hex << '\n';
  }
  app::write_file(path, f.str());
}

}  // namespace

std::string write_hdl_export(const HdlLayout& l, const std::string& dir, HdlCapacities cap) {
  if (cap.cells == 0) cap.cells = l.cell_count;
  if (cap.pixels == 0) cap.pixels = static_cast<std::uint32_t>(l.ranges.size());
  if (cap.refs_per_lane == 0) cap.refs_per_lane = std::max<std::uint32_t>(1, l.max_lane_refs());
  if (l.cell_count > cap.cells || l.ranges.size() > cap.pixels || l.max_lane_refs() > cap.refs_per_lane ||
      (cap.range_count != 0 && l.max_range_count() > cap.range_count)) {
    throw app::Error("table (" + std::to_string(l.cell_count) + " cells, " + std::to_string(l.ranges.size()) + " pixels, " +
                std::to_string(l.max_lane_refs()) + " refs per lane) exceeds the capacities (" + std::to_string(cap.cells) +
                ", " + std::to_string(cap.pixels) + ", " + std::to_string(cap.refs_per_lane) + ")" +
                (cap.range_count != 0 ? " or a pixel's range exceeds " + std::to_string(cap.range_count) + " references" : ""));
  }
  std::filesystem::create_directories(dir);
  const std::uint32_t refs_per_lane = cap.refs_per_lane;
  const HdlWidths w = hdl_widths(l.lanes, cap.cells, refs_per_lane, cap.range_count);
  const std::uint32_t cells_per_lane_cap = (cap.cells + l.lanes - 1) / l.lanes;
  std::vector<std::vector<std::uint32_t>> offsets;
  for (std::uint32_t p = 0; p < l.ranges.size(); ++p) offsets.push_back(hdl_offsets_word(l, p, w));
  write_mem(dir + "/offsets.mem", offsets, l.lanes * w.range_bits(), "per pixel, per lane {begin, count}");
  const std::uint32_t cell_bits = std::max<std::uint32_t>(1, clog2(cells_per_lane_cap));
  std::uint64_t memory_bits = std::uint64_t{l.lanes} * w.range_bits() * l.ranges.size();
  for (std::uint32_t k = 0; k < l.lanes; ++k) {
    std::vector<std::vector<std::uint32_t>> refs, sizes;
    for (std::uint32_t r : l.refs[k]) refs.push_back({r});
    for (std::uint32_t s : l.sizes[k]) sizes.push_back({s});
    write_mem(dir + "/refs_" + std::to_string(k) + ".mem", refs, cell_bits, "lane " + std::to_string(k) + " local cell indices");
    write_mem(dir + "/sizes_" + std::to_string(k) + ".mem", sizes, 16, "lane " + std::to_string(k) + " stencil sizes (>= 1)");
    memory_bits += std::uint64_t{refs_per_lane} * cell_bits + std::uint64_t{l.cells_per_lane} * (16 + 16);
  }
  std::ostringstream pkg;
  pkg << "// Generated by `gabarit tables export-hdl`: the sizes of one table for hdl/rtl/gbt_voter_table.sv.\n"
      << "`default_nettype none\n\npackage gabarit_table_pkg;\n"
      << "  localparam int unsigned Lanes = " << l.lanes << ";\n"
      << "  localparam int unsigned CellCapacity = " << cap.cells << ";\n"
      << "  localparam int unsigned CellCount = " << l.cell_count << ";  // the table's cells\n"
      << "  localparam int unsigned RoiWidth = " << l.roi_width << ";  // slots per row: ROI width x orientation channels\n"
      << "  localparam int unsigned RoiHeight = " << l.roi_height << ";\n"
      << "  localparam int unsigned PixelCapacity = " << cap.pixels << ";\n"
      << "  localparam int unsigned RefsPerLane = " << refs_per_lane << ";\n"
      << "  localparam int unsigned MaxRangeCount = " << cap.range_count << ";  // 0: every cell of a lane\n"
      << "  localparam int unsigned OffsetWidth = " << w.offset_bits << ";\n"
      << "  localparam int unsigned RangeCountWidth = " << w.count_bits << ";\n"
      << "  localparam int unsigned MemoryBits = " << memory_bits << ";  // all voter memories\n"
      << "endpackage\n\n`default_nettype wire\n";
  app::write_file(dir + "/gabarit_table_pkg.sv", pkg.str());
  std::ostringstream s;
  s << dir << ": " << l.lanes << " lane(s), " << l.cell_count << " cells, ROI " << l.roi_width << "x" << l.roi_height << ", "
    << refs_per_lane << " refs per lane, " << memory_bits << " bits of memory (" << memory_bits / 8192.0 << " KiB)";
  return s.str();
}

}  // namespace gabarit::app
