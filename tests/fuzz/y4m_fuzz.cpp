// Fuzz target: the Y4M frame reader, from memory as from a pipe. Bad input
// must end in app::Error, never a crash, undefined behaviour or an
// allocation beyond the frame limit (image_io.hpp).
#include <cstddef>
#include <cstdint>
#include <cstdio>

#include "gabarit/app/error.hpp"
#include "gabarit/app/image_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  std::FILE* stream = ::fmemopen(const_cast<std::uint8_t*>(data), size, "rb");
  if (stream == nullptr) return 0;
  try {
    auto frames = gabarit::app::open_y4m(stream, "fuzz.y4m");
    gabarit::app::GrayImage frame;
    for (int i = 0; i < 8 && frames->next(frame); ++i) {
    }
  } catch (const gabarit::app::Error&) {
  }
  std::fclose(stream);
  return 0;
}
