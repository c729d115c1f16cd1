// Fuzz target: a session profile's text (gabarit track --profile, the board's,
// gabarit hil run --profile): parsed or refused with app::Error, never a
// crash; what parses validates, and writes back to text that parses to it.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "gabarit/app/error.hpp"
#include "gabarit/app/session_profile_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace gabarit;
  try {
    const app::SessionProfile p = app::parse_profile(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz");
    if (app::validate(p) != Status::kOk) std::abort();
    if (!(app::parse_profile(app::format_profile(p), "again") == p)) std::abort();
  } catch (const app::Error&) {
  }
  return 0;
}
