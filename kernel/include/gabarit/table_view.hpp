// A validated, zero-copy view of a gabarit table held in any byte buffer: a
// file mapped by Linux or a const array in MCU flash. open() checks every
// structural promise once (header, version, sizes, CRC-32, monotonic offsets,
// references in range and strictly increasing per pixel); after that the
// accessors and the voter's hot loop read without further checks.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "gabarit/byte_order.hpp"
#include "gabarit/image_view.hpp"
#include "gabarit/roi_point.hpp"
#include "gabarit/status.hpp"
#include "gabarit/table_format.hpp"

namespace gabarit {

// One axis of the state space: `cells` cells whose centres run evenly from
// min to max (min == max when cells == 1).
struct Axis {
  float min = 0;
  float max = 0;
  std::uint32_t cells = 1;
};

// A cell of the state space: [x_lo,x_hi] x [y_lo,y_hi] x [theta_lo,theta_hi] x {depth}.
struct CellBounds {
  float x_lo = 0, x_hi = 0;
  float y_lo = 0, y_hi = 0;
  float theta_lo_deg = 0, theta_hi_deg = 0;
  std::uint16_t depth = 0;
  std::uint32_t stencil_size = 0;

  float x_centre() const noexcept { return (x_lo + x_hi) * 0.5f; }
  float y_centre() const noexcept { return (y_lo + y_hi) * 0.5f; }
  float theta_centre_deg() const noexcept { return (theta_lo_deg + theta_hi_deg) * 0.5f; }
};

// A half-open range of cell indices [begin, end).
struct CellRange {
  std::uint32_t begin = 0;
  std::uint32_t end = 0;
};

struct ModelPoint {
  std::int16_t x = 0;
  std::int16_t y = 0;
};

// Readers of the pixel offsets (CSR row starts) in each encoding of
// docs/table-format.md; begin(p) is the index of pixel p's first reference,
// begin(p + 1) one past its last. The voters are templates over them, so
// each encoding's hot loop is compiled on its own.
// range(p) is {begin(p), begin(p + 1)} in one decode (precondition: p < roi_pixels).
struct ReferenceRange {
  std::uint32_t begin, end;
};
struct WideOffsets {
  const std::byte* offsets;
  std::uint32_t begin(std::size_t pixel) const noexcept { return load_le<std::uint32_t>(offsets + pixel * 4); }
  ReferenceRange range(std::size_t pixel) const noexcept { return {begin(pixel), begin(pixel + 1)}; }
};
template <class Delta>
struct CompactOffsets {
  const std::byte* blocks;  // 24-byte headers: u32 base, u32 rank, u64 mask[2]
  const std::byte* deltas;  // per non-empty pixel, its end less its block's base
  std::uint32_t begin(std::size_t pixel) const noexcept {
    const std::byte* h = blocks + (pixel >> table_format::kOffsetBlockLog2) * table_format::kOffsetBlockHeaderBytes;
    const auto i = static_cast<std::uint32_t>(pixel & (table_format::kOffsetBlockPixels - 1));
    const auto j = (table_format::count_bits(load_le<std::uint64_t>(h + 8) & table_format::low_bits(i)) +
                                              table_format::count_bits(load_le<std::uint64_t>(h + 16) & table_format::low_bits(i < 64 ? 0 : i - 64)));
    const std::uint32_t base = load_le<std::uint32_t>(h);
    return j == 0 ? base : base + load_le<Delta>(deltas + std::size_t{load_le<std::uint32_t>(h + 4) + j - 1} * sizeof(Delta));
  }
  // One block header, no branch (the hot loop meets random pixels, where a
  // mispredicted branch costs more than the decode): an empty pixel (its
  // bit clear) is {begin, begin}, a marked one ends at its own delta. The
  // two deltas around the pixel's rank are read whatever the pixel: before
  // the first that reads the block headers, past the last the next section
  // (references, or model counts of at least one depth), inside the table.
  ReferenceRange range(std::size_t pixel) const noexcept {
    const std::byte* h = blocks + (pixel >> table_format::kOffsetBlockLog2) * table_format::kOffsetBlockHeaderBytes;
    const auto i = static_cast<std::uint32_t>(pixel & (table_format::kOffsetBlockPixels - 1));
    const std::uint64_t lo = load_le<std::uint64_t>(h + 8), hi = load_le<std::uint64_t>(h + 16);
    const std::uint32_t lo_bits = i < 64 ? i : 64;
    const auto j = (table_format::count_bits(lo & table_format::low_bits(lo_bits)) +
                                              table_format::count_bits(hi & table_format::low_bits(i - lo_bits)));
    const std::uint64_t word = i < 64 ? lo : hi;
    const auto marked = static_cast<std::uint32_t>((word >> (i & 63)) & 1u);
    const std::uint32_t base = load_le<std::uint32_t>(h);
    const std::byte* at = deltas + std::size_t{load_le<std::uint32_t>(h + 4) + j} * sizeof(Delta);
    const std::uint32_t before = load_le<Delta>(at - sizeof(Delta)), own = load_le<Delta>(at);
    const std::uint32_t begin = base + (before & (0u - static_cast<std::uint32_t>(j != 0)));
    return {begin, begin + ((base + own - begin) & (0u - marked))};
  }
};

// The slots a feature votes (TableView::channel_bits): its pixel's, or, with
// orientation channels, its channel's and the nearer neighbouring channel's.
struct FeatureSlots {
  std::uint32_t first = 0;
  std::uint32_t second = 0;
  bool two = false;
};
// Precondition: the feature's pixel is inside the ROI (row < roi height,
// column < roi width); channel_bits and width as the table's.
constexpr FeatureSlots feature_slots(std::uint32_t col, std::uint32_t row, std::uint32_t width, std::uint32_t channel_bits) noexcept {
  if (channel_bits == 0) return {row * width + col, 0, false};
  const std::uint32_t k = channel_bits - 1, channels = 1u << k;
  const std::uint32_t base = (row * width + (col >> channel_bits)) << k;
  const std::uint32_t c = (col >> 1) & (channels - 1);
  const std::uint32_t other = (c + ((col & 1u) ? 1u : channels - 1u)) & (channels - 1u);
  return {base + c, base + other, true};
}

// CRC-32 of a table: every byte except the 4-byte CRC field itself (so a
// flipped bit anywhere, header included, is caught). Precondition:
// table.size() >= table_format::kHeaderBytes.
std::uint32_t table_checksum(std::span<const std::byte> table) noexcept;

class TableView {
 public:
  TableView() = default;

  // Validates `bytes` and, on success, makes `out` a view of it. `bytes` must
  // outlive the view. Never reads outside `bytes`, whatever it contains.
  static Status open(std::span<const std::byte> bytes, TableView& out) noexcept;

  std::uint32_t cell_count() const noexcept { return cell_count_; }
  std::uint32_t reference_count() const noexcept { return reference_count_; }
  std::uint16_t roi_width() const noexcept { return roi_width_; }
  std::uint16_t roi_height() const noexcept { return roi_height_; }
  std::uint32_t roi_pixels() const noexcept { return std::uint32_t{roi_width_} * roi_height_; }
  // Orientation channels (format 1.3): 1 for a position-only table, else 2,
  // 4, 8 or 16 slots per ROI pixel; the pixel offsets index slots.
  std::uint32_t orientation_channels() const noexcept { return channels_; }
  std::uint32_t roi_slots() const noexcept { return roi_pixels() * channels_; }
  // With channels, a feature's RoiPoint carries its channel: col holds
  // (column << (k + 1)) | (channel << 1) | upper, k = log2 channels, upper
  // set when its orientation lies in the upper half of its channel. It votes
  // its channel's slot and the nearer neighbour's (feature_slots).
  std::uint32_t channel_bits() const noexcept { return channel_bits_; }  // k + 1, or 0 without channels
  std::uint32_t feature_column(const RoiPoint& f) const noexcept { return std::uint32_t{f.col} >> channel_bits_; }
  // Position of ROI column 0 / row 0 relative to the ROI centre (the previous pose).
  std::int16_t roi_origin_x() const noexcept { return roi_origin_x_; }
  std::int16_t roi_origin_y() const noexcept { return roi_origin_y_; }
  std::uint8_t reference_bytes() const noexcept { return reference_bytes_; }
  table_format::DetectorKind detector_kind() const noexcept { return detector_kind_; }
  std::uint16_t detector_threshold() const noexcept { return detector_threshold_; }
  std::uint32_t max_stencil_size() const noexcept { return max_stencil_size_; }
  std::uint16_t depth_count() const noexcept { return depth_count_; }
  std::uint32_t model_point_count() const noexcept { return model_point_count_; }
  Axis axis_x() const noexcept { return read_axis(table_format::offset::kAxisX); }
  Axis axis_y() const noexcept { return read_axis(table_format::offset::kAxisY); }
  Axis axis_theta() const noexcept { return read_axis(table_format::offset::kAxisTheta); }
  float keep_ratio() const noexcept { return load_le<float>(base_ + table_format::offset::kKeepRatio); }
  float model_ref_x() const noexcept { return load_le<float>(base_ + table_format::offset::kModelRefX); }
  float model_ref_y() const noexcept { return load_le<float>(base_ + table_format::offset::kModelRefY); }
  std::uint16_t model_width() const noexcept { return load_le<std::uint16_t>(base_ + table_format::offset::kModelWidth); }
  std::uint16_t model_height() const noexcept { return load_le<std::uint16_t>(base_ + table_format::offset::kModelHeight); }
  std::uint64_t seed() const noexcept { return load_le<std::uint64_t>(base_ + table_format::offset::kSeed); }
  std::size_t size_bytes() const noexcept { return file_bytes_; }

  // Precondition: cell < cell_count().
  CellBounds cell(std::uint32_t cell) const noexcept;
  // The cells of one focus-stack depth: cells are numbered depth-major
  // (docs/table-format.md), cell_count() / depth_count() per depth.
  // Precondition: depth < depth_count().
  CellRange depth_cells(std::uint16_t depth) const noexcept {
    const std::uint32_t per_depth = cell_count_ / depth_count_;
    return {depth * per_depth, (depth + 1u) * per_depth};
  }
  std::uint32_t stencil_size(std::uint32_t cell) const noexcept {
    return load_le<std::uint32_t>(cells_ + std::size_t{cell} * table_format::kCellDescriptorBytes +
                                  table_format::cell_offset::kStencilSize);
  }

  // CSR access. Precondition: pixel <= roi_pixels(); references of pixel p are
  // indices [references_begin(p), references_begin(p + 1)).
  std::uint32_t references_begin(std::uint32_t pixel) const noexcept {
    switch (offset_delta_bytes_) {
      case 0: return WideOffsets{pixel_offsets_}.begin(pixel);
      case 1: return CompactOffsets<std::uint8_t>{pixel_offsets_, offset_deltas_}.begin(pixel);
      default: return CompactOffsets<std::uint16_t>{pixel_offsets_, offset_deltas_}.begin(pixel);
    }
  }
  // Precondition: index < reference_count().
  std::uint32_t reference(std::uint32_t index) const noexcept;
  const std::byte* references_data() const noexcept { return references_; }
  // The offsets' encoding: 0 for one u32 per pixel (1.0, 1.1), else the
  // compact deltas' width (1.2).
  std::uint8_t offset_delta_bytes() const noexcept { return offset_delta_bytes_; }
  // Calls f with the reader of this table's offset encoding (WideOffsets or
  // CompactOffsets<u8 or u16>) and returns what f returns.
  template <class F>
  decltype(auto) with_offsets(F&& f) const noexcept {
    switch (offset_delta_bytes_) {
      case 0: return f(WideOffsets{pixel_offsets_});
      case 1: return f(CompactOffsets<std::uint8_t>{pixel_offsets_, offset_deltas_});
      default: return f(CompactOffsets<std::uint16_t>{pixel_offsets_, offset_deltas_});
    }
  }

  // Model points of one focus-stack depth, relative to the reference point.
  // Precondition: depth < depth_count(), i < model_point_count(depth).
  std::uint32_t model_point_count(std::uint16_t depth) const noexcept {
    return load_le<std::uint32_t>(model_counts_ + std::size_t{depth} * 4);
  }
  ModelPoint model_point(std::uint32_t index_over_all_depths) const noexcept {
    const std::byte* p = model_points_ + std::size_t{index_over_all_depths} * table_format::kModelPointBytes;
    return {load_le<std::int16_t>(p), load_le<std::int16_t>(p + 2)};
  }

  // The model images the table was built from, one per depth (v1.1 tables
  // built from images; the focus stack depth_by_intensity.hpp compares).
  bool has_model_images() const noexcept { return model_images_ != nullptr; }
  // Precondition: has_model_images(), depth < depth_count().
  ImageView model_image(std::uint16_t depth) const noexcept {
    const std::size_t w = model_width(), h = model_height();
    return ImageView{reinterpret_cast<const std::uint8_t*>(model_images_) + std::size_t{depth} * w * h,
                     static_cast<std::uint32_t>(w), static_cast<std::uint32_t>(h), w};
  }

 private:
  Axis read_axis(std::size_t at) const noexcept {
    return {load_le<float>(base_ + at), load_le<float>(base_ + at + 4), load_le<std::uint32_t>(base_ + at + 8)};
  }

  const std::byte* base_ = nullptr;
  const std::byte* cells_ = nullptr;
  const std::byte* pixel_offsets_ = nullptr;  // u32 offsets, or the compact offsets' block headers
  const std::byte* offset_deltas_ = nullptr;  // compact offsets only
  const std::byte* references_ = nullptr;
  const std::byte* model_counts_ = nullptr;
  const std::byte* model_points_ = nullptr;
  const std::byte* model_images_ = nullptr;  // null: no model-images section
  std::uint32_t file_bytes_ = 0;
  std::uint32_t cell_count_ = 0;
  std::uint32_t reference_count_ = 0;
  std::uint32_t max_stencil_size_ = 0;
  std::uint32_t model_point_count_ = 0;
  std::uint16_t roi_width_ = 0;
  std::uint16_t roi_height_ = 0;
  std::uint32_t channels_ = 1;
  std::uint32_t channel_bits_ = 0;
  std::int16_t roi_origin_x_ = 0;
  std::int16_t roi_origin_y_ = 0;
  std::uint16_t detector_threshold_ = 0;
  std::uint16_t depth_count_ = 0;
  std::uint8_t reference_bytes_ = 0;
  std::uint8_t offset_delta_bytes_ = 0;
  table_format::DetectorKind detector_kind_ = table_format::DetectorKind::kBinary;
};

}  // namespace gabarit
