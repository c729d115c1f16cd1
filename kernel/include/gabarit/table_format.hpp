// Byte layout of a gabarit table, version 1. The prose specification is
// docs/table-format.md; these constants are the single source both the kernel
// (reader) and the host table builder (writer) use, so the two cannot drift.
#pragma once

#include <cstddef>
#include <cstdint>

namespace gabarit::table_format {

inline constexpr char kMagic[8] = {'G', 'B', 'R', 'T', 'L', 'U', 'T', '\0'};
inline constexpr std::uint16_t kVersionMajor = 1;
// 1.1 added the optional model-images section (kFlagModelImages); 1.2 the
// compact pixel offsets (kFlagCompactOffsets); 1.3 the orientation channels
// (kFlagOrientationChannels). A table is written with the lowest minor
// version that holds what it uses: without any, as 1.0, byte for byte as before.
inline constexpr std::uint16_t kVersionMinor = 3;
inline constexpr std::uint32_t kFlagModelImages = 1u;
inline constexpr std::uint32_t kFlagCompactOffsets = 2u;
inline constexpr std::uint32_t kFlagOrientationChannels = 4u;
inline constexpr std::uint32_t kKnownFlags = kFlagModelImages | kFlagCompactOffsets | kFlagOrientationChannels;  // others must be 0

// Orientation channels (1.3): each ROI pixel is split into C slots, one per
// channel of edge orientation (modulo 180 degrees, in the table frame);
// slot = pixel * C + channel, and the pixel offsets index slots. A feature
// whose gradient orientation (features.hpp, orientation_256, less the ROI's
// angle) lies in channel c votes only the references of slot (p, c): the
// cells whose stencils cover p with a model point of that orientation.
// C is 2, 4, 8 or 16; channel = orientation_256 >> (8 - log2 C).
inline constexpr std::uint8_t kMaxOrientationChannels = 16;
constexpr bool valid_orientation_channels(std::uint32_t c) noexcept { return c == 2 || c == 4 || c == 8 || c == 16; }
constexpr std::uint32_t orientation_channel_shift(std::uint32_t c) noexcept {
  return c == 2 ? 7u : c == 4 ? 6u : c == 8 ? 5u : 4u;
}

// Compact pixel offsets (1.2): the ROI's pixels in blocks of 128. Per block
// a 24-byte header { u32 base: the block's first reference; u32 rank: the
// non-empty pixels before the block; u64 mask[2]: bit i of the 128 set when
// pixel 128 b + i lists a cell }, then one u8 or u16 delta per non-empty
// pixel: its end (one past its last reference) less its block's base. So
//   begin(p) = base + (j ? delta[rank + j - 1] : 0),  j = the mask's bits below p,
// and an empty pixel costs a bit. Bytes fall with the references.
inline constexpr std::uint8_t kOffsetBlockLog2 = 7;
inline constexpr std::uint32_t kOffsetBlockPixels = 1u << kOffsetBlockLog2;
inline constexpr std::uint32_t kOffsetBlockHeaderBytes = 24;

// The n lowest bits (all 64 for n >= 64), without a branch (the voter's hot
// loop meets random pixels: a mispredicted branch costs more than the decode).
constexpr std::uint64_t low_bits(std::uint32_t n) noexcept {
  return ((std::uint64_t{1} << (n & 63)) - 1) | (std::uint64_t{0} - std::uint64_t{n >= 64});
}
// Bits set in x, inline on every target: without a population-count
// instruction (baseline x86-64, Cortex-M) std::popcount is a library call,
// which in the voter's hot loop costs more than this.
constexpr std::uint32_t count_bits(std::uint64_t x) noexcept {
  x = x - ((x >> 1) & 0x5555555555555555ull);
  x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
  x = (x + (x >> 4)) & 0x0F0F0F0F0F0F0F0Full;
  return static_cast<std::uint32_t>((x * 0x0101010101010101ull) >> 56);
}
static_assert(count_bits(0) == 0 && count_bits(~std::uint64_t{0}) == 64 && count_bits(0x8000000000000001ull) == 2);
static_assert(low_bits(0) == 0 && low_bits(5) == 31 && low_bits(63) == ~std::uint64_t{0} >> 1 && low_bits(64) == ~std::uint64_t{0} &&
              low_bits(128) == ~std::uint64_t{0});

inline constexpr std::uint32_t kHeaderBytes = 160;
inline constexpr std::uint32_t kCellDescriptorBytes = 32;
inline constexpr std::uint32_t kModelPointBytes = 4;  // int16 x, int16 y
inline constexpr std::uint32_t kSectionAlignment = 8;

// Limits that keep every size computation inside 32 bits and every counter
// comparison inside 64 bits; a header above them is rejected as kCountTooLarge.
inline constexpr std::uint32_t kMaxCells = 1u << 24;
inline constexpr std::uint32_t kMaxRoiPixels = 1u << 24;
inline constexpr std::uint32_t kMaxReferences = 1u << 28;
inline constexpr std::uint32_t kMaxModelPoints = 1u << 20;
inline constexpr std::uint32_t kMaxDepths = 4096;

// Limits of what a table may ask of the programs that run it, so that no
// valid table makes a host allocate gigabytes or the kernel's arithmetic
// overflow (docs/table-format.md, "Limits"). TableView::open refuses a table
// beyond them (kCountTooLarge, kBadHeaderField); the builder refuses to write one.
inline constexpr std::uint32_t kMaxTableBytes = 1u << 30;
inline constexpr float kMaxAxisPixels = 1024.0f;   // |x|, |y|: axis and cell bounds
inline constexpr float kMaxAxisDegrees = 360.0f;   // |theta|: axis and cell bounds
inline constexpr float kMaxModelRef = 16384.0f;    // |model_ref_x|, |model_ref_y|
// The side of the square image window that holds the ROI rotated by any
// angle (roi_window_side below) is at most this: the tracker's feature
// scratch (tracker_feature_capacity) is then at most 4 Mi entries (16 MiB).
inline constexpr std::uint32_t kMaxRoiWindowSide = 2048;
// A gradient detector's threshold: at most the largest Sobel L1 magnitude of
// an 8-bit image (features.hpp's kMaxGradientMagnitude).
inline constexpr std::uint16_t kMaxDetectorThreshold = 2040;
// The model images (one 8-bit image per depth, model_width x model_height)
// take at most this many bytes in all.
inline constexpr std::uint32_t kMaxModelImageBytes = 1u << 26;

// Side of the square image window that contains the ROI rotated by any angle:
// 2 * ceil(r) + 1 where r is the ROI corner farthest from the ROI centre.
constexpr std::uint32_t roi_window_side(std::uint16_t roi_width, std::uint16_t roi_height, std::int16_t roi_origin_x,
                                        std::int16_t roi_origin_y) noexcept {
  std::int64_t r2 = 0;
  const std::int64_t xs[2] = {roi_origin_x, std::int64_t{roi_origin_x} + roi_width - 1};
  const std::int64_t ys[2] = {roi_origin_y, std::int64_t{roi_origin_y} + roi_height - 1};
  for (std::int64_t x : xs)
    for (std::int64_t y : ys) r2 = x * x + y * y > r2 ? x * x + y * y : r2;
  std::int64_t r = 0;
  while (r * r < r2) ++r;  // ceil(sqrt(r2)) without floating point
  return static_cast<std::uint32_t>(2 * r + 1);
}

// Header field offsets (bytes from the start of the table).
namespace offset {
inline constexpr std::size_t kMagic = 0;               // char[8]
inline constexpr std::size_t kVersionMajor = 8;        // u16
inline constexpr std::size_t kVersionMinor = 10;       // u16
inline constexpr std::size_t kHeaderBytes = 12;        // u32 = 160
inline constexpr std::size_t kFileBytes = 16;          // u32, whole table
inline constexpr std::size_t kCrc32 = 20;              // u32, CRC-32 of every byte except these four
inline constexpr std::size_t kFlags = 24;              // u32: 0, or kFlagModelImages (v1.1)
inline constexpr std::size_t kCellCount = 28;          // u32
inline constexpr std::size_t kReferenceCount = 32;     // u32
inline constexpr std::size_t kRoiWidth = 36;           // u16
inline constexpr std::size_t kRoiHeight = 38;          // u16
inline constexpr std::size_t kRoiOriginX = 40;         // i16, x of ROI column 0 relative to the ROI centre
inline constexpr std::size_t kRoiOriginY = 42;         // i16
inline constexpr std::size_t kReferenceBytes = 44;     // u8: 1, 2 or 4 (narrowest that fits)
inline constexpr std::size_t kDetectorKind = 45;       // u8: DetectorKind
inline constexpr std::size_t kDetectorThreshold = 46;  // u16
inline constexpr std::size_t kMaxStencilSize = 48;     // u32
inline constexpr std::size_t kModelPointCount = 52;    // u32, all depths
inline constexpr std::size_t kDepthCount = 56;         // u16
inline constexpr std::size_t kReserved58 = 58;         // u16, must be 0
inline constexpr std::size_t kAxisX = 60;              // f32 min, f32 max, u32 cells
inline constexpr std::size_t kAxisY = 72;
inline constexpr std::size_t kAxisTheta = 84;          // degrees
inline constexpr std::size_t kKeepRatio = 96;          // f32
inline constexpr std::size_t kModelRefX = 100;         // f32, reference point in model-image pixels
inline constexpr std::size_t kModelRefY = 104;         // f32
inline constexpr std::size_t kModelWidth = 108;        // u16, model image size (0 for point models)
inline constexpr std::size_t kModelHeight = 110;       // u16
inline constexpr std::size_t kSeed = 112;              // u64
inline constexpr std::size_t kCellsOffset = 120;       // u32
inline constexpr std::size_t kPixelOffsetsOffset = 124;  // u32
inline constexpr std::size_t kReferencesOffset = 128;  // u32
inline constexpr std::size_t kModelCountsOffset = 132; // u32: depth_count x u32
inline constexpr std::size_t kModelPointsOffset = 136; // u32: model_point_count x (i16, i16)
inline constexpr std::size_t kModelImagesOffset = 140; // u32 (v1.1): depth_count x model_width x model_height u8, 0 if absent
inline constexpr std::size_t kOffsetDeltaBytes = 144;  // u8 (v1.2, compact offsets): 1 or 2; else 0
inline constexpr std::size_t kOffsetBlockLog2 = 145;   // u8 (v1.2, compact offsets): 7; else 0
inline constexpr std::size_t kOrientationChannels = 146;  // u8 (v1.3, kFlagOrientationChannels): 2, 4, 8 or 16; else 0
inline constexpr std::size_t kReserved147 = 147;       // u8, must be 0
inline constexpr std::size_t kOffsetDeltaCount = 148;  // u32 (v1.2, compact offsets): non-empty pixels; else 0
inline constexpr std::size_t kReserved152 = 152;       // 8 bytes, must be 0
}  // namespace offset

// Cell descriptor field offsets (bytes from the start of the descriptor).
namespace cell_offset {
inline constexpr std::size_t kXLo = 0;    // f32, translation bounds in pixels
inline constexpr std::size_t kXHi = 4;
inline constexpr std::size_t kYLo = 8;
inline constexpr std::size_t kYHi = 12;
inline constexpr std::size_t kThetaLo = 16;  // f32, degrees
inline constexpr std::size_t kThetaHi = 20;
inline constexpr std::size_t kDepth = 24;    // u16, focus-stack index
inline constexpr std::size_t kReserved = 26; // u16, must be 0
inline constexpr std::size_t kStencilSize = 28;  // u32, pixels in the (decimated) stencil
}  // namespace cell_offset

enum class DetectorKind : std::uint8_t {
  kBinary = 0,        // any non-zero pixel is a feature
  kGradientRows = 1,  // Sobel |gx|+|gy| >= threshold, strongest of each run along a row
  kCanny = 2,         // Canny variant: non-maximum suppression, hysteresis thresholds (features.hpp)
};

constexpr std::uint32_t align_up(std::uint32_t n) noexcept {
  return (n + (kSectionAlignment - 1)) & ~(kSectionAlignment - 1);
}

// The counts that fix a table's layout.
struct LayoutCounts {
  std::uint32_t cell_count = 0;
  std::uint32_t roi_pixels = 0;        // roi_width * roi_height, times the orientation channels (the slots)
  std::uint32_t reference_count = 0;
  std::uint8_t reference_bytes = 0;    // narrowest_reference_bytes(cell_count)
  std::uint16_t depth_count = 0;
  std::uint32_t model_point_count = 0;
  std::uint32_t model_image_bytes = 0;  // 0: no model-images section
  std::uint8_t offset_delta_bytes = 0;  // 0: u32 offsets; 1, 2: compact offsets (v1.2)
  std::uint32_t offset_delta_count = 0; // compact offsets: non-empty ROI pixels
};

// Blocks of compact offsets covering pixels 0..roi_pixels (one past the last).
constexpr std::uint32_t offset_block_count(std::uint32_t roi_pixels) noexcept { return (roi_pixels >> kOffsetBlockLog2) + 1; }
// Bytes of the pixel-offsets section.
constexpr std::uint32_t pixel_offsets_bytes(const LayoutCounts& n) noexcept {
  if (n.offset_delta_bytes == 0) return (n.roi_pixels + 1) * 4;
  return offset_block_count(n.roi_pixels) * kOffsetBlockHeaderBytes + n.offset_delta_count * n.offset_delta_bytes;
}
// Where each section starts, and the file's size: the sections follow the
// header in this order, each 8-byte aligned, with no gaps beyond alignment
// (docs/table-format.md). The one description of the layout: the reader
// (TableView::open) checks the header's offsets against it and the writer
// (the table builder) places the sections by it. Precondition: the counts
// are within the kMax* limits, which keeps every sum inside 32 bits.
struct Layout {
  std::uint32_t cells = 0;          // cell descriptors
  std::uint32_t pixel_offsets = 0;  // CSR offsets: roi_pixels + 1 x u32, or compact (bases, then deltas)
  std::uint32_t references = 0;     // reference_count x reference_bytes
  std::uint32_t model_counts = 0;   // depth_count x u32
  std::uint32_t model_points = 0;   // model_point_count x (i16, i16)
  std::uint32_t model_images = 0;   // model_image_bytes (where it would start if absent)
  std::uint32_t file_bytes = 0;
};
constexpr Layout layout_of(const LayoutCounts& n) noexcept {
  Layout l;
  l.cells = kHeaderBytes;
  l.pixel_offsets = align_up(l.cells + n.cell_count * kCellDescriptorBytes);
  l.references = align_up(l.pixel_offsets + pixel_offsets_bytes(n));
  l.model_counts = align_up(l.references + n.reference_count * n.reference_bytes);
  l.model_points = align_up(l.model_counts + std::uint32_t{n.depth_count} * 4);
  l.model_images = align_up(l.model_points + n.model_point_count * kModelPointBytes);
  l.file_bytes = align_up(l.model_images + n.model_image_bytes);
  return l;
}
// The worked example of docs/table-format.md: 3 cells, a 2 x 2 ROI, 5
// one-byte references, 1 depth, 3 model points.
static_assert(layout_of({3, 4, 5, 1, 1, 3}).pixel_offsets == 256 && layout_of({3, 4, 5, 1, 1, 3}).references == 280 &&
                  layout_of({3, 4, 5, 1, 1, 3}).model_counts == 288 && layout_of({3, 4, 5, 1, 1, 3}).model_points == 296 &&
                  layout_of({3, 4, 5, 1, 1, 3}).file_bytes == 312,
              "the section offsets of docs/table-format.md's worked example");
// The largest table the limits allow still fits a 32-bit size.
static_assert(std::uint64_t{kHeaderBytes} + std::uint64_t{kMaxCells} * kCellDescriptorBytes + (kMaxRoiPixels + 1ull) * 4 +
                      std::uint64_t{kMaxReferences} * 4 + kMaxDepths * 4ull + std::uint64_t{kMaxModelPoints} * kModelPointBytes +
                      kMaxModelImageBytes + 6 * kSectionAlignment <
                  (1ull << 32),
              "every section sum stays inside 32 bits");

constexpr std::uint8_t narrowest_reference_bytes(std::uint32_t cell_count) noexcept {
  return cell_count <= 0x100u ? 1 : (cell_count <= 0x10000u ? 2 : 4);
}

}  // namespace gabarit::table_format
