#include "gabarit/table_view.hpp"

#include <cstring>

#include "gabarit/assert.hpp"
#include "gabarit/crc32.hpp"
#include "gabarit/deterministic_math.hpp"

namespace gabarit {
namespace {

namespace off = table_format::offset;
namespace coff = table_format::cell_offset;

bool all_zero(const std::byte* p, std::size_t n) noexcept {
  for (std::size_t i = 0; i < n; ++i) {
    if (p[i] != std::byte{0}) return false;
  }
  return true;
}

// A bound the kernel can compute with: finite and within +-limit.
bool bounded(float v, float limit) noexcept { return is_finite(v) && v >= -limit && v <= limit; }

Status check_axis(const std::byte* base, std::size_t at, float limit, std::uint32_t& cells_out) noexcept {
  const float lo = load_le<float>(base + at);
  const float hi = load_le<float>(base + at + 4);
  const std::uint32_t cells = load_le<std::uint32_t>(base + at + 8);
  if (!bounded(lo, limit) || !bounded(hi, limit) || cells == 0 || lo > hi) return Status::kBadHeaderField;
  if (cells == 1 && lo != hi) return Status::kBadHeaderField;
  if (cells > 1 && lo == hi) return Status::kBadHeaderField;
  if (cells > table_format::kMaxCells) return Status::kCountTooLarge;
  cells_out = cells;
  return Status::kOk;
}

// Offsets start at 0, never decrease and end at the reference count.
template <class Offsets>
Status check_offsets(const Offsets& offsets, std::uint32_t pixels, std::uint32_t reference_count) noexcept {
  if (offsets.begin(0) != 0) return Status::kOffsetsNotMonotonic;
  for (std::uint32_t p = 0; p < pixels; ++p) {
    if (offsets.begin(p + 1) < offsets.begin(p)) return Status::kOffsetsNotMonotonic;
  }
  if (offsets.begin(pixels) != reference_count) return Status::kOffsetsNotMonotonic;
  return Status::kOk;
}

// Compact offsets are also canonical, so one table has one encoding of its
// lists: ranks count the mask bits before each block, which add up to the
// delta count; no bit for a position past the ROI; within a block the
// deltas strictly increase (a pixel marked non-empty lists a cell) and the
// next block's base is this one's plus its last delta. Reads only inside
// the section (its size was checked against the header's counts).
template <class Delta>
Status check_compact_blocks(const std::byte* blocks, const std::byte* deltas, std::uint32_t pixels,
                            std::uint32_t delta_count) noexcept {
  const std::uint32_t count = table_format::offset_block_count(pixels);
  std::uint32_t rank = 0;
  for (std::uint32_t b = 0; b < count; ++b) {
    const std::byte* h = blocks + std::size_t{b} * table_format::kOffsetBlockHeaderBytes;
    const std::uint32_t base = load_le<std::uint32_t>(h);
    const std::uint64_t mask_lo = load_le<std::uint64_t>(h + 8), mask_hi = load_le<std::uint64_t>(h + 16);
    if (load_le<std::uint32_t>(h + 4) != rank) return Status::kOffsetsNotMonotonic;
    // Only positions that are pixels (< pixels) may be marked.
    const std::uint32_t first = b << table_format::kOffsetBlockLog2;
    const std::uint32_t inside = pixels - first >= table_format::kOffsetBlockPixels ? table_format::kOffsetBlockPixels : pixels - first;
    if ((mask_lo & ~table_format::low_bits(inside)) != 0 || (mask_hi & ~table_format::low_bits(inside < 64 ? 0 : inside - 64)) != 0) {
      return Status::kOffsetsNotMonotonic;
    }
    const auto marked = (table_format::count_bits(mask_lo) + table_format::count_bits(mask_hi));
    if (marked > delta_count - rank) return Status::kOffsetsNotMonotonic;
    std::uint32_t previous = 0;
    for (std::uint32_t k = 0; k < marked; ++k) {
      const std::uint32_t d = load_le<Delta>(deltas + std::size_t{rank + k} * sizeof(Delta));
      if (d <= previous) return Status::kOffsetsNotMonotonic;
      previous = d;
    }
    rank += marked;
    if (b + 1 < count && load_le<std::uint32_t>(h + table_format::kOffsetBlockHeaderBytes) != base + previous) {
      return Status::kOffsetsNotMonotonic;
    }
  }
  return rank == delta_count ? Status::kOk : Status::kOffsetsNotMonotonic;
}

template <class Ref, class Offsets>
Status check_references(const Offsets& offsets, const std::byte* refs, std::uint32_t pixels,
                        std::uint32_t cell_count) noexcept {
  for (std::uint32_t p = 0; p < pixels; ++p) {
    const std::uint32_t begin = offsets.begin(p);
    const std::uint32_t end = offsets.begin(p + 1);
    std::uint32_t previous = 0;
    for (std::uint32_t i = begin; i < end; ++i) {
      const std::uint32_t r = load_le<Ref>(refs + std::size_t{i} * sizeof(Ref));
      if (r >= cell_count) return Status::kReferenceOutOfRange;
      if (i != begin && r <= previous) return Status::kReferencesNotSorted;
      previous = r;
    }
  }
  return Status::kOk;
}

// Each cell must appear in the reference lists exactly stencil_size times
// (scores are votes / stencil_size, at most 1). Counted without scratch of
// the cell count's size: kChunk cells at a time, each pixel's list being
// sorted, so a chunk's references of a pixel are found by binary search.
template <class Ref, class Offsets>
Status check_stencil_counts(const Offsets& offsets, const std::byte* refs, const std::byte* cells, std::uint32_t pixels,
                            std::uint32_t cell_count) noexcept {
  constexpr std::uint32_t kChunk = 512;  // 2 KiB of stack
  for (std::uint32_t first = 0; first < cell_count; first += kChunk) {
    const std::uint32_t last = cell_count - first < kChunk ? cell_count : first + kChunk;
    std::uint32_t counts[kChunk] = {};
    for (std::uint32_t p = 0; p < pixels; ++p) {
      std::uint32_t lo = offsets.begin(p);
      const std::uint32_t end = offsets.begin(p + 1);
      std::uint32_t hi = end;
      while (lo < hi) {  // the first reference >= first
        const std::uint32_t mid = lo + (hi - lo) / 2;
        if (load_le<Ref>(refs + std::size_t{mid} * sizeof(Ref)) < first) lo = mid + 1;
        else hi = mid;
      }
      for (std::uint32_t i = lo; i < end; ++i) {
        const std::uint32_t r = load_le<Ref>(refs + std::size_t{i} * sizeof(Ref));
        if (r >= last) break;
        ++counts[r - first];
      }
    }
    for (std::uint32_t c = first; c < last; ++c) {
      const std::uint32_t declared =
          load_le<std::uint32_t>(cells + std::size_t{c} * table_format::kCellDescriptorBytes + coff::kStencilSize);
      if (counts[c - first] != declared) return Status::kStencilSizeMismatch;
    }
  }
  return Status::kOk;
}

}  // namespace

std::uint32_t table_checksum(std::span<const std::byte> table) noexcept {
  const std::uint32_t head = crc32(table.first(off::kCrc32));
  return crc32_update(head, table.subspan(off::kCrc32 + 4));
}

namespace {

// What TableView::open reads from the header once the checksum holds; each
// field checked by check_header before anything uses it.
struct HeaderFields {
  std::uint32_t file_bytes = 0, flags = 0, cell_count = 0, reference_count = 0, model_point_count = 0, delta_count = 0;
  std::uint32_t channels = 1, image_bytes = 0;
  std::uint16_t roi_width = 0, roi_height = 0, depth_count = 0, threshold = 0;
  std::uint8_t reference_bytes = 0, detector = 0, delta_bytes = 0;
  bool has_images = false, compact = false, channels_flag = false;
};

// Identity, size and checksum: what a random or damaged file fails on.
Status check_identity(std::span<const std::byte> bytes, std::uint32_t& file_bytes) noexcept {
  const std::byte* b = bytes.data();
  const std::size_t n = bytes.size();

  // Identity first, so a random file reports "bad magic", not a size problem.
  if (n < sizeof(table_format::kMagic)) return Status::kTruncated;
  if (std::memcmp(b, table_format::kMagic, sizeof(table_format::kMagic)) != 0) return Status::kBadMagic;
  if (n < off::kHeaderBytes) return Status::kTruncated;
  if (load_le<std::uint16_t>(b + off::kVersionMajor) != table_format::kVersionMajor) {
    return Status::kUnsupportedVersion;
  }
  if (n < table_format::kHeaderBytes) return Status::kTruncated;
  if (load_le<std::uint32_t>(b + off::kHeaderBytes) != table_format::kHeaderBytes) {
    return Status::kBadHeaderField;
  }
  file_bytes = load_le<std::uint32_t>(b + off::kFileBytes);
  if (file_bytes > n) return Status::kTruncated;
  if (file_bytes != n || file_bytes < table_format::kHeaderBytes) return Status::kSizeMismatch;
  // No checksum over a buffer larger than any valid table (seconds for gigabytes).
  if (file_bytes > table_format::kMaxTableBytes) return Status::kCountTooLarge;

  if (table_checksum(bytes) != load_le<std::uint32_t>(b + off::kCrc32)) return Status::kBadChecksum;

  return Status::kOk;
}

Status check_header(const std::byte* b, HeaderFields& h) noexcept {
  // Header fields. Past the CRC only a deliberately crafted table reaches
  // here, but it must still be refused without any out-of-bounds read.
  // Flags: the model-images section from version 1.1, compact offsets from
  // 1.2, orientation channels from 1.3.
  const std::uint32_t flags = load_le<std::uint32_t>(b + off::kFlags);
  const std::uint16_t minor = load_le<std::uint16_t>(b + off::kVersionMinor);
  const bool has_images = (flags & table_format::kFlagModelImages) != 0;
  const bool compact = (flags & table_format::kFlagCompactOffsets) != 0;
  const std::uint8_t delta_bytes = load_le<std::uint8_t>(b + off::kOffsetDeltaBytes);
  const std::uint8_t block_log2 = load_le<std::uint8_t>(b + off::kOffsetBlockLog2);
  const std::uint32_t delta_count = load_le<std::uint32_t>(b + off::kOffsetDeltaCount);
  const bool channels_flag = (flags & table_format::kFlagOrientationChannels) != 0;
  const std::uint8_t channels_field = load_le<std::uint8_t>(b + off::kOrientationChannels);
  if ((flags & ~table_format::kKnownFlags) != 0 || (has_images && minor < 1) || (compact && minor < 2) ||
      (channels_flag ? minor < 3 || !table_format::valid_orientation_channels(channels_field) : channels_field != 0) ||
      load_le<std::uint16_t>(b + off::kReserved58) != 0 ||
      (!has_images && load_le<std::uint32_t>(b + off::kModelImagesOffset) != 0) ||
      (compact ? (delta_bytes != 1 && delta_bytes != 2) || block_log2 != table_format::kOffsetBlockLog2
               : delta_bytes != 0 || block_log2 != 0 || delta_count != 0) ||
      load_le<std::uint8_t>(b + off::kReserved147) != 0 ||
      !all_zero(b + off::kReserved152, table_format::kHeaderBytes - off::kReserved152)) {
    return Status::kBadHeaderField;
  }
  const std::uint32_t cell_count = load_le<std::uint32_t>(b + off::kCellCount);
  const std::uint32_t reference_count = load_le<std::uint32_t>(b + off::kReferenceCount);
  const std::uint16_t roi_width = load_le<std::uint16_t>(b + off::kRoiWidth);
  const std::uint16_t roi_height = load_le<std::uint16_t>(b + off::kRoiHeight);
  const std::uint8_t reference_bytes = load_le<std::uint8_t>(b + off::kReferenceBytes);
  const std::uint8_t detector = load_le<std::uint8_t>(b + off::kDetectorKind);
  const std::uint32_t model_point_count = load_le<std::uint32_t>(b + off::kModelPointCount);
  const std::uint16_t depth_count = load_le<std::uint16_t>(b + off::kDepthCount);

  const std::uint32_t channels = channels_flag ? channels_field : 1u;
  if (cell_count > table_format::kMaxCells || reference_count > table_format::kMaxReferences ||
      std::uint64_t{roi_width} * roi_height * channels > table_format::kMaxRoiPixels ||
      model_point_count > table_format::kMaxModelPoints || depth_count > table_format::kMaxDepths) {
    return Status::kCountTooLarge;
  }
  if (cell_count == 0 || roi_width == 0 || roi_height == 0 || depth_count == 0) return Status::kBadHeaderField;
  if (delta_count > std::uint32_t{roi_width} * roi_height * channels) return Status::kBadHeaderField;
  if (reference_bytes != table_format::narrowest_reference_bytes(cell_count)) return Status::kBadHeaderField;
  if (detector > static_cast<std::uint8_t>(table_format::DetectorKind::kCanny)) {
    return Status::kBadHeaderField;
  }
  // A detector the kernel can run: gradient thresholds in 1..kMaxDetectorThreshold
  // (the Canny variant's low threshold, half of it, at least 1).
  const std::uint16_t threshold = load_le<std::uint16_t>(b + off::kDetectorThreshold);
  if (detector != static_cast<std::uint8_t>(table_format::DetectorKind::kBinary) &&
      (threshold > table_format::kMaxDetectorThreshold ||
       threshold < (detector == static_cast<std::uint8_t>(table_format::DetectorKind::kCanny) ? 2 : 1))) {
    return Status::kBadHeaderField;
  }
  if (table_format::roi_window_side(roi_width, roi_height, load_le<std::int16_t>(b + off::kRoiOriginX),
                                    load_le<std::int16_t>(b + off::kRoiOriginY)) > table_format::kMaxRoiWindowSide) {
    return Status::kCountTooLarge;
  }
  std::uint32_t cells_x = 0, cells_y = 0, cells_theta = 0;
  GABARIT_TRY(check_axis(b, off::kAxisX, table_format::kMaxAxisPixels, cells_x));
  GABARIT_TRY(check_axis(b, off::kAxisY, table_format::kMaxAxisPixels, cells_y));
  GABARIT_TRY(check_axis(b, off::kAxisTheta, table_format::kMaxAxisDegrees, cells_theta));
  const std::uint64_t space_cells = std::uint64_t{cells_x} * cells_y * cells_theta * depth_count;
  if (space_cells != cell_count) return Status::kSizeMismatch;
  const float keep = load_le<float>(b + off::kKeepRatio);
  if (!is_finite(keep) || !(keep > 0.0f) || keep > 1.0f) return Status::kBadHeaderField;
  if (!bounded(load_le<float>(b + off::kModelRefX), table_format::kMaxModelRef) ||
      !bounded(load_le<float>(b + off::kModelRefY), table_format::kMaxModelRef)) {
    return Status::kBadHeaderField;
  }

  // The model images: depth_count images of the model size.
  std::uint32_t image_bytes = 0;
  if (has_images) {
    const std::uint64_t bytes64 = std::uint64_t{depth_count} * load_le<std::uint16_t>(b + off::kModelWidth) *
                                  load_le<std::uint16_t>(b + off::kModelHeight);
    if (bytes64 == 0) return Status::kBadHeaderField;
    if (bytes64 > table_format::kMaxModelImageBytes) return Status::kCountTooLarge;
    image_bytes = static_cast<std::uint32_t>(bytes64);
  }

  h.flags = flags;
  h.cell_count = cell_count;
  h.reference_count = reference_count;
  h.model_point_count = model_point_count;
  h.delta_count = delta_count;
  h.channels = channels;
  h.image_bytes = image_bytes;
  h.roi_width = roi_width;
  h.roi_height = roi_height;
  h.depth_count = depth_count;
  h.threshold = threshold;
  h.reference_bytes = reference_bytes;
  h.detector = detector;
  h.delta_bytes = delta_bytes;
  h.has_images = has_images;
  h.compact = compact;
  h.channels_flag = channels_flag;
  return Status::kOk;
}

// The CSR offsets and reference lists, in the table's offset encoding, and
// then the cell descriptors against them.
Status check_sections(const std::byte* b, const HeaderFields& h, const table_format::Layout& layout, std::uint32_t& stencil_max) noexcept {
  const std::uint32_t pixels = std::uint32_t{h.roi_width} * h.roi_height * h.channels;
  const std::uint32_t cell_count = h.cell_count, reference_count = h.reference_count, delta_count = h.delta_count;
  const std::uint16_t depth_count = h.depth_count;
  const std::uint8_t reference_bytes = h.reference_bytes, delta_bytes = h.delta_bytes;
  const bool compact = h.compact;
  const std::uint32_t cells_at = layout.cells, offsets_at = layout.pixel_offsets, refs_at = layout.references;
  // CSR offsets and lists, in the table's offset encoding.
  const std::byte* offsets = b + offsets_at;
  const std::byte* deltas =
      compact ? offsets + std::size_t{table_format::offset_block_count(pixels)} * table_format::kOffsetBlockHeaderBytes : nullptr;
  const std::byte* refs = b + refs_at;
  const auto check_lists = [&](const auto& reader) -> Status {
    GABARIT_TRY(check_offsets(reader, pixels, reference_count));
    switch (reference_bytes) {
      case 1: return check_references<std::uint8_t>(reader, refs, pixels, cell_count);
      case 2: return check_references<std::uint16_t>(reader, refs, pixels, cell_count);
      default: return check_references<std::uint32_t>(reader, refs, pixels, cell_count);
    }
  };
  const auto check_counts = [&](const auto& reader) -> Status {
    switch (reference_bytes) {
      case 1: return check_stencil_counts<std::uint8_t>(reader, refs, b + cells_at, pixels, cell_count);
      case 2: return check_stencil_counts<std::uint16_t>(reader, refs, b + cells_at, pixels, cell_count);
      default: return check_stencil_counts<std::uint32_t>(reader, refs, b + cells_at, pixels, cell_count);
    }
  };
  const auto with_reader = [&](const auto& check) -> Status {
    switch (delta_bytes) {
      case 0: return check(WideOffsets{offsets});
      case 1: return check(CompactOffsets<std::uint8_t>{offsets, deltas});
      default: return check(CompactOffsets<std::uint16_t>{offsets, deltas});
    }
  };
  if (delta_bytes == 1) GABARIT_TRY(check_compact_blocks<std::uint8_t>(offsets, deltas, pixels, delta_count));
  if (delta_bytes == 2) GABARIT_TRY(check_compact_blocks<std::uint16_t>(offsets, deltas, pixels, delta_count));
  GABARIT_TRY(with_reader(check_lists));

  // Cell descriptors: bounded ordered bounds (twice the axis limit: a cell
  // may reach half a cell past its axis), a valid depth, and stencil sizes
  // that add up to the reference count (each reference is one stencil pixel)
  // and match how often each cell is referenced.
  std::uint64_t stencil_total = 0;
  stencil_max = 0;
  for (std::uint32_t c = 0; c < cell_count; ++c) {
    const std::byte* d = b + cells_at + std::size_t{c} * table_format::kCellDescriptorBytes;
    for (std::size_t f = coff::kXLo; f <= coff::kThetaLo; f += 8) {
      const float limit = 2.0f * (f == coff::kThetaLo ? table_format::kMaxAxisDegrees : table_format::kMaxAxisPixels);
      const float lo = load_le<float>(d + f);
      const float hi = load_le<float>(d + f + 4);
      if (!bounded(lo, limit) || !bounded(hi, limit) || lo > hi) return Status::kBadHeaderField;
    }
    if (load_le<std::uint16_t>(d + coff::kDepth) >= depth_count || load_le<std::uint16_t>(d + coff::kReserved) != 0) {
      return Status::kBadHeaderField;
    }
    const std::uint32_t size = load_le<std::uint32_t>(d + coff::kStencilSize);
    stencil_total += size;
    if (size > stencil_max) stencil_max = size;
  }
  if (stencil_total != reference_count || stencil_max != load_le<std::uint32_t>(b + off::kMaxStencilSize)) {
    return Status::kStencilSizeMismatch;
  }
  GABARIT_TRY(with_reader(check_counts));
  return Status::kOk;
}

}  // namespace

Status TableView::open(std::span<const std::byte> bytes, TableView& out) noexcept {
  const std::byte* b = bytes.data();
  HeaderFields h;
  GABARIT_TRY(check_identity(bytes, h.file_bytes));
  GABARIT_TRY(check_header(b, h));

  // The layout is canonical (table_format::layout_of), so any other offset is
  // an error. The offsets index slots: pixels times orientation channels.
  const std::uint32_t pixels = std::uint32_t{h.roi_width} * h.roi_height * h.channels;
  const table_format::Layout layout = table_format::layout_of({h.cell_count, pixels, h.reference_count, h.reference_bytes, h.depth_count,
                                                               h.model_point_count, h.image_bytes, h.delta_bytes, h.delta_count});
  if (load_le<std::uint32_t>(b + off::kCellsOffset) != layout.cells ||
      load_le<std::uint32_t>(b + off::kPixelOffsetsOffset) != layout.pixel_offsets ||
      load_le<std::uint32_t>(b + off::kReferencesOffset) != layout.references ||
      load_le<std::uint32_t>(b + off::kModelCountsOffset) != layout.model_counts ||
      load_le<std::uint32_t>(b + off::kModelPointsOffset) != layout.model_points ||
      (h.has_images && load_le<std::uint32_t>(b + off::kModelImagesOffset) != layout.model_images)) {
    return Status::kSectionOutOfBounds;
  }
  if (layout.file_bytes != h.file_bytes) return Status::kSizeMismatch;
  std::uint32_t stencil_max = 0;
  GABARIT_TRY(check_sections(b, h, layout, stencil_max));

  std::uint64_t model_total = 0;
  for (std::uint32_t d = 0; d < h.depth_count; ++d) model_total += load_le<std::uint32_t>(b + layout.model_counts + std::size_t{d} * 4);
  if (model_total != h.model_point_count) return Status::kSizeMismatch;

  TableView view;
  view.base_ = b;
  view.cells_ = b + layout.cells;
  view.pixel_offsets_ = b + layout.pixel_offsets;
  view.offset_deltas_ = h.compact ? view.pixel_offsets_ + std::size_t{table_format::offset_block_count(pixels)} * table_format::kOffsetBlockHeaderBytes
                                  : nullptr;
  view.offset_delta_bytes_ = h.delta_bytes;
  view.references_ = b + layout.references;
  view.model_counts_ = b + layout.model_counts;
  view.model_points_ = b + layout.model_points;
  view.model_images_ = h.has_images ? b + layout.model_images : nullptr;
  view.file_bytes_ = h.file_bytes;
  view.cell_count_ = h.cell_count;
  view.reference_count_ = h.reference_count;
  view.max_stencil_size_ = stencil_max;
  view.model_point_count_ = h.model_point_count;
  view.roi_width_ = h.roi_width;
  view.channels_ = h.channels;
  view.channel_bits_ = h.channels_flag ? 9u - table_format::orientation_channel_shift(h.channels) : 0u;  // log2 channels + 1
  view.roi_height_ = h.roi_height;
  view.roi_origin_x_ = load_le<std::int16_t>(b + off::kRoiOriginX);
  view.roi_origin_y_ = load_le<std::int16_t>(b + off::kRoiOriginY);
  view.detector_threshold_ = h.threshold;
  view.depth_count_ = h.depth_count;
  view.reference_bytes_ = h.reference_bytes;
  view.detector_kind_ = static_cast<table_format::DetectorKind>(h.detector);
  out = view;
  return Status::kOk;
}

CellBounds TableView::cell(std::uint32_t cell) const noexcept {
  GABARIT_ASSERT(cell < cell_count_);
  const std::byte* d = cells_ + std::size_t{cell} * table_format::kCellDescriptorBytes;
  CellBounds c;
  c.x_lo = load_le<float>(d + coff::kXLo);
  c.x_hi = load_le<float>(d + coff::kXHi);
  c.y_lo = load_le<float>(d + coff::kYLo);
  c.y_hi = load_le<float>(d + coff::kYHi);
  c.theta_lo_deg = load_le<float>(d + coff::kThetaLo);
  c.theta_hi_deg = load_le<float>(d + coff::kThetaHi);
  c.depth = load_le<std::uint16_t>(d + coff::kDepth);
  c.stencil_size = load_le<std::uint32_t>(d + coff::kStencilSize);
  return c;
}

std::uint32_t TableView::reference(std::uint32_t index) const noexcept {
  GABARIT_ASSERT(index < reference_count_);
  switch (reference_bytes_) {
    case 1: return load_le<std::uint8_t>(references_ + index);
    case 2: return load_le<std::uint16_t>(references_ + std::size_t{index} * 2);
    default: return load_le<std::uint32_t>(references_ + std::size_t{index} * 4);
  }
}

}  // namespace gabarit
