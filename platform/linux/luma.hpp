// The luma plane of a captured V4L2 frame as the kernel's ImageView: GREY and
// NV12 are viewed in place (their first plane is luma), YUYV is de-interleaved
// into a caller buffer. The buffer's size is untrusted (a driver reports
// bytesused), so it is checked here, once, before the tracker reads a pixel.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "gabarit/image_view.hpp"

namespace gabarit::board {

// V4L2 fourcc codes (linux/videodev2.h), spelled out so this file builds anywhere.
constexpr std::uint32_t fourcc(char a, char b, char c, char d) {
  return static_cast<std::uint32_t>(static_cast<unsigned char>(a)) | static_cast<std::uint32_t>(static_cast<unsigned char>(b)) << 8 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(c)) << 16 | static_cast<std::uint32_t>(static_cast<unsigned char>(d)) << 24;
}
inline constexpr std::uint32_t kFourccGrey = fourcc('G', 'R', 'E', 'Y');
inline constexpr std::uint32_t kFourccYuyv = fourcc('Y', 'U', 'Y', 'V');
inline constexpr std::uint32_t kFourccNv12 = fourcc('N', 'V', '1', '2');

struct FrameLayout {
  std::uint32_t pixel_format = 0;
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::uint32_t bytes_per_line = 0;  // of the luma (GREY, NV12) or packed (YUYV) plane
};

// Bytes a complete frame of this layout occupies (0 for an unsupported format).
std::size_t frame_bytes(const FrameLayout& layout);
// Bytes of caller buffer luma_view needs (0 when the frame is viewed in place).
std::size_t luma_scratch_bytes(const FrameLayout& layout);

enum class [[nodiscard]] LumaStatus { kOk, kUnsupportedFormat, kBadLayout, kShortFrame, kScratchTooSmall };
const char* luma_status_name(LumaStatus status);

// `data` holds `bytes_used` bytes as the driver reported them.
LumaStatus luma_view(const FrameLayout& layout, const std::uint8_t* data, std::size_t bytes_used,
                     std::span<std::uint8_t> scratch, ImageView& out);

// A printable fourcc, e.g. "YUYV".
struct FourccText {
  char text[5];
};
FourccText fourcc_text(std::uint32_t code);

}  // namespace gabarit::board
