// Fuzz target: a board's hardware map (hil/boards/*.yaml): parsed or refused
// with app::Error, never a crash; what parses names a relay.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "gabarit/app/error.hpp"
#include "gabarit/hil/board_map.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const gabarit::hil::BoardMap m =
        gabarit::hil::parse_board_map(std::string(reinterpret_cast<const char*>(data), size), "fuzz.yaml");
    if (m.relay.empty() || m.name.empty()) std::abort();
  } catch (const gabarit::app::Error&) {
  }
  return 0;
}
