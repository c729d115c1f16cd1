#include "gabarit/host/tables/table_inspect.hpp"

#include <algorithm>
#include <map>
#include <sstream>

namespace gabarit::host {
namespace {

const char* detector_name(table_format::DetectorKind k) {
  switch (k) {
    case table_format::DetectorKind::kBinary: return "binary";
    case table_format::DetectorKind::kGradientRows: return "gradient-rows";
    case table_format::DetectorKind::kCanny: return "canny";
  }
  return "unknown";
}

void axis_json(std::ostringstream& o, const char* name, const Axis& a) {
  o << "    \"" << name << "\": {\"min\": " << a.min << ", \"max\": " << a.max << ", \"cells\": " << a.cells << "}";
}

}  // namespace

std::string inspect_json(const TableView& t) {
  std::map<std::uint32_t, std::uint32_t> refs_per_pixel;  // refs -> pixels
  for (std::uint32_t p = 0; p < t.roi_slots(); ++p) ++refs_per_pixel[t.references_begin(p + 1) - t.references_begin(p)];
  std::uint32_t smin = UINT32_MAX, smax = 0;
  std::uint64_t ssum = 0;
  for (std::uint32_t c = 0; c < t.cell_count(); ++c) {
    const std::uint32_t s = t.stencil_size(c);
    smin = std::min(smin, s);
    smax = std::max(smax, s);
    ssum += s;
  }
  std::ostringstream o;
  o << "{\n  \"format_version\": " << table_format::kVersionMajor << ",\n";
  o << "  \"bytes\": " << t.size_bytes() << ",\n  \"cells\": " << t.cell_count() << ",\n";
  o << "  \"references\": " << t.reference_count() << ",\n";
  o << "  \"reference_bytes\": " << unsigned{t.reference_bytes()} << ",\n";
  o << "  \"offsets\": \"" << (t.offset_delta_bytes() == 0 ? "u32" : t.offset_delta_bytes() == 1 ? "compact u8" : "compact u16") << "\",\n";
  o << "  \"bytes_per_cell\": " << static_cast<double>(t.size_bytes()) / t.cell_count() << ",\n";
  o << "  \"roi\": {\"width\": " << t.roi_width() << ", \"height\": " << t.roi_height()
    << ", \"origin_x\": " << t.roi_origin_x() << ", \"origin_y\": " << t.roi_origin_y() << "},\n";
  // Orientation channels (format 1.3): slots per ROI pixel; the refs-per-pixel histogram then counts slots.
  o << "  \"orientation_channels\": " << (t.orientation_channels() > 1 ? t.orientation_channels() : 0u) << ",\n";
  o << "  \"space\": {\n";
  axis_json(o, "x", t.axis_x());
  o << ",\n";
  axis_json(o, "y", t.axis_y());
  o << ",\n";
  axis_json(o, "theta_deg", t.axis_theta());
  o << ",\n    \"depths\": " << t.depth_count() << "\n  },\n";
  o << "  \"detector\": {\"kind\": \"" << detector_name(t.detector_kind()) << "\", \"threshold\": " << t.detector_threshold() << "},\n";
  o << "  \"model\": {\"points\": " << t.model_point_count() << ", \"ref_x\": " << t.model_ref_x() << ", \"ref_y\": " << t.model_ref_y()
    << ", \"image_width\": " << t.model_width() << ", \"image_height\": " << t.model_height()
    << ", \"images_stored\": " << (t.has_model_images() ? "true" : "false") << "},\n";
  o << "  \"keep_ratio\": " << t.keep_ratio() << ",\n  \"seed\": " << t.seed() << ",\n";
  o << "  \"refs_per_pixel_histogram\": {";
  bool first = true;
  for (const auto& [refs, pixels] : refs_per_pixel) {
    o << (first ? "" : ", ") << "\"" << refs << "\": " << pixels;
    first = false;
  }
  o << "},\n";
  o << "  \"stencil_sizes\": {\"min\": " << smin << ", \"max\": " << smax << ", \"mean\": "
    << static_cast<double>(ssum) / t.cell_count() << ", \"per_cell\": [";
  for (std::uint32_t c = 0; c < t.cell_count(); ++c) o << (c ? ", " : "") << t.stencil_size(c);
  o << "]}\n}\n";
  return o.str();
}

}  // namespace gabarit::host
