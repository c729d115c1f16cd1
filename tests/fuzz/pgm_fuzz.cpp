// Fuzz target: the PGM reader (P5 and P2), from memory as from a pipe.
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
    static_cast<void>(gabarit::app::read_pgm(stream, "fuzz.pgm"));
  } catch (const gabarit::app::Error&) {
  }
  std::fclose(stream);
  return 0;
}
