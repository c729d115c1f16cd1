// Feature extraction into caller buffers. Features are written in window
// coordinates (column, row inside the ImageWindow), in raster order, at most
// out.size() of them; the rest are counted as dropped, never written. Slots
// of `out` past the features written may be used as scratch.
//
// Detectors:
//  - binary: a pixel is a feature when it is non-zero;
//  - gradient rows (the thesis's fast edge detector): the gradient magnitude
//    m = |gx| + |gy| of the 3x3 Sobel operator is thresholded (m >= threshold,
//    threshold >= 1), and of each run of contiguous above-threshold pixels on
//    a row only the strongest is kept (the leftmost on ties). Pixels on the
//    image border have no full neighbourhood and are never features; runs are
//    cut at the window's edges.
//  - Canny variant (the thesis found Canny more accurate, its own detector
//    faster): Sobel gradient, m = |gx| + |gy|; non-maximum suppression across
//    the edge, along the gradient direction quantised to 0, 45, 90 or 135
//    degrees (a pixel is kept if m >= the neighbour ahead and m > the one
//    behind); two thresholds (hysteresis), high = threshold and low = threshold / 2: a
//    strong pixel (m >= high) is a feature, a weak one (low <= m < high) only
//    if one of its 8 neighbours is strong. That is one step of Canny's
//    hysteresis, which otherwise follows weak chains of any length and needs
//    a window-sized buffer; this variant needs none.
// None needs scratch memory; the Canny variant is faster with three rows of it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "gabarit/image_view.hpp"
#include "gabarit/roi_point.hpp"
#include "gabarit/status.hpp"
#include "gabarit/table_format.hpp"

namespace gabarit {

// Capacity that can never overflow: one feature per window pixel.
constexpr std::size_t feature_capacity(std::uint16_t window_width, std::uint16_t window_height) noexcept {
  return std::size_t{window_width} * window_height;
}

struct FeatureCount {
  std::uint32_t written = 0;
  std::uint32_t dropped = 0;  // features found beyond out.size()
  std::uint64_t scanned = 0;  // pixels the detector examined (the cost of extraction)
};

// Largest gradient magnitude the Sobel L1 norm can produce on 8-bit images.
inline constexpr std::uint16_t kMaxGradientMagnitude = 2040;
static_assert(kMaxGradientMagnitude == table_format::kMaxDetectorThreshold, "a table may ask for any threshold up to the largest magnitude");

// Sobel |gx| + |gy| at (x, y); 0 on the image border. Precondition: image.valid(), x < width, y < height.
std::uint16_t gradient_magnitude(const ImageView& image, std::uint32_t x, std::uint32_t y) noexcept;

// The 3x3 Sobel gradient at (x, y) (x to the right, y down); 0 on the image
// border. Precondition: image.valid(), x < width, y < height.
struct SobelGradient {
  std::int32_t gx = 0;
  std::int32_t gy = 0;
};
SobelGradient sobel_gradient(const ImageView& image, std::uint32_t x, std::uint32_t y) noexcept;

// The gradient's orientation modulo 180 degrees (an edge's orientation,
// whichever side is brighter), in 256ths of a half turn: 0 for a gradient
// along +x or -x, 128 along +y or -y.
// Integer comparisons against a fixed table of directions, so every target
// gets the same value. (0, 0) gives 0.
inline constexpr std::uint32_t kOrientationSteps = 256;  // per half turn
std::uint8_t orientation_256(std::int32_t gx, std::int32_t gy) noexcept;
// The orientation of the edge at (x, y) of a model image: of its Sobel
// gradient, or, where that vanishes (a point between two edge pixels), of
// the strongest of its 8 neighbours'. The table builder (orientation
// channels) and the model finder read model images with it. Outside the
// image: 0. Precondition: image.valid().
std::uint8_t edge_orientation_at(const ImageView& image, std::int32_t x, std::int32_t y) noexcept;
// Orientation channels: the 256 steps in kOrientationChannels bins of 11.25 degrees.
inline constexpr std::uint32_t kOrientationChannels = 16;
constexpr std::uint8_t orientation_channel(std::uint8_t orientation) noexcept {
  return static_cast<std::uint8_t>(orientation >> 4);
}

Status extract_gradient_rows(const ImageView& image, const ImageWindow& window, std::uint16_t threshold,
                             std::span<RoiPoint> out, FeatureCount& count) noexcept;

// The Canny variant looks at each pixel's gradient magnitude up to eleven
// times (its own, two across the edge, eight for the hysteresis). Given
// canny_scratch_entries(window.width) entries of `magnitude_rows`, it keeps
// three rows of magnitudes and computes each pixel's once; the features are
// the same with or without them (the per-pixel path is the reference). With
// them, where the build has vector bodies for this CPU, whole vectors of a
// row are decided at once, with the same features (canny_vector_body).
constexpr std::size_t canny_scratch_entries(std::uint16_t window_width) noexcept {
  return 3 * (std::size_t{window_width} + 2);
}
// The part of a window a caller keeps: the image pixels p whose offset
// p - centre, turned by -theta, lies in [u_min, u_max] x [v_min, v_max]
// (u = cos dx + sin dy, v = -sin dx + cos dy). A tracker at an angle scans
// the square that holds its rotated ROI and keeps only the ROI's pixels.
struct TurnedRectangle {
  float centre_x = 0.0f, centre_y = 0.0f;
  float cos = 1.0f, sin = 0.0f;
  float u_min = 0.0f, u_max = 0.0f, v_min = 0.0f, v_max = 0.0f;
};
// Given `keep`, the binary and Canny detectors scan of each window row only
// the columns the rectangle covers, two pixels wider on each side (so that
// no rounding leaves out a pixel it covers): the features written are those
// of the whole window that lie there, in the same order (a subset that holds
// every feature within the rectangle). Gradient rows, whose runs are cut at
// the window's edges, ignore it.
Status extract_binary(const ImageView& image, const ImageWindow& window, std::span<RoiPoint> out, FeatureCount& count,
                      const TurnedRectangle* keep = nullptr) noexcept;
Status extract_canny(const ImageView& image, const ImageWindow& window, std::uint16_t threshold, std::span<RoiPoint> out,
                     FeatureCount& count, std::span<std::uint16_t> magnitude_rows = {},
                     const TurnedRectangle* keep = nullptr) noexcept;

// The body that decides Canny's rows of magnitudes on this CPU: "AVX2" or
// "SSE4" (x86-64), "NEON" (AArch64), or "scalar" (other targets, builds
// without Google Highway, or a CPU without the instructions). The dense
// voter's adders run the same body (dense_voter.hpp).
[[nodiscard]] const char* canny_vector_body() noexcept;

// Dispatches on the detector recorded in a table; magnitude_rows and keep as extract_canny's.
Status extract_features(const ImageView& image, const ImageWindow& window, table_format::DetectorKind kind,
                        std::uint16_t threshold, std::span<RoiPoint> out, FeatureCount& count,
                        std::span<std::uint16_t> magnitude_rows = {}, const TurnedRectangle* keep = nullptr) noexcept;

}  // namespace gabarit
