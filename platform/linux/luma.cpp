#include "luma.hpp"

namespace gabarit::board {

std::size_t frame_bytes(const FrameLayout& l) {
  const std::size_t rows = l.height, line = l.bytes_per_line;
  if (l.pixel_format == kFourccGrey || l.pixel_format == kFourccYuyv) return rows * line;
  if (l.pixel_format == kFourccNv12) return rows * line + (rows + 1) / 2 * line;  // Y, then interleaved CbCr at half height
  return 0;
}

std::size_t luma_scratch_bytes(const FrameLayout& l) {
  return l.pixel_format == kFourccYuyv ? std::size_t{l.width} * l.height : 0;
}

const char* luma_status_name(LumaStatus status) {
  switch (status) {
    case LumaStatus::kOk: return "ok";
    case LumaStatus::kUnsupportedFormat: return "unsupported pixel format";
    case LumaStatus::kBadLayout: return "bytes per line smaller than a row";
    case LumaStatus::kShortFrame: return "frame shorter than its layout";
    case LumaStatus::kScratchTooSmall: return "luma buffer too small";
  }
  return "?";
}

LumaStatus luma_view(const FrameLayout& l, const std::uint8_t* data, std::size_t bytes_used, std::span<std::uint8_t> scratch,
                     ImageView& out) {
  const std::size_t bytes_per_pixel = l.pixel_format == kFourccYuyv ? 2 : 1;
  if (frame_bytes(l) == 0) return LumaStatus::kUnsupportedFormat;
  if (l.width == 0 || l.height == 0 || l.bytes_per_line < std::size_t{l.width} * bytes_per_pixel) return LumaStatus::kBadLayout;
  if (data == nullptr || bytes_used < frame_bytes(l)) return LumaStatus::kShortFrame;
  if (l.pixel_format != kFourccYuyv) {
    out = {data, l.width, l.height, l.bytes_per_line};
    return LumaStatus::kOk;
  }
  if (scratch.size() < luma_scratch_bytes(l)) return LumaStatus::kScratchTooSmall;
  // YUYV: Y0 U Y1 V — luma is every even byte.
  for (std::uint32_t y = 0; y < l.height; ++y) {
    const std::uint8_t* row = data + std::size_t{y} * l.bytes_per_line;
    std::uint8_t* dst = scratch.data() + std::size_t{y} * l.width;
    for (std::uint32_t x = 0; x < l.width; ++x) dst[x] = row[2 * std::size_t{x}];
  }
  out = {scratch.data(), l.width, l.height, l.width};
  return LumaStatus::kOk;
}

FourccText fourcc_text(std::uint32_t code) {
  FourccText t{};
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((code >> (8 * i)) & 0xFF);
    t.text[i] = c >= 32 && c < 127 ? c : '?';
  }
  return t;
}

}  // namespace gabarit::board
