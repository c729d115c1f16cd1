// Fuzz target: the model points CSV reader (tables build --model-points).
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "gabarit/app/error.hpp"
#include "gabarit/host/tables/model.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    static_cast<void>(gabarit::host::read_points_csv(in, "fuzz.csv"));
  } catch (const gabarit::app::Error&) {
  }
  return 0;
}
