// A read-only 8-bit grayscale image owned by someone else (a V4L2 buffer's
// luma plane, a decoded Y4M frame, a const array in flash).
#pragma once

#include <cstddef>
#include <cstdint>

namespace gabarit {

struct ImageView {
  const std::uint8_t* pixels = nullptr;
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::size_t stride = 0;  // bytes from one row to the next, >= width

  bool valid() const noexcept { return pixels != nullptr && width > 0 && height > 0 && stride >= width; }
  std::uint8_t at(std::uint32_t x, std::uint32_t y) const noexcept { return pixels[std::size_t{y} * stride + x]; }
};

// A rectangle of image pixels: (x0, y0) is its top-left corner in image
// coordinates and may lie outside the image (the window is clipped).
struct ImageWindow {
  std::int32_t x0 = 0;
  std::int32_t y0 = 0;
  std::uint16_t width = 0;
  std::uint16_t height = 0;
};

}  // namespace gabarit
