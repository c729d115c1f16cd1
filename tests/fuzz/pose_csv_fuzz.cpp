// Fuzz target: eval's poses and ground-truth CSV reader, then the accuracy
// and its JSON (which must stay valid: no NaN or infinity can get in).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

#include "gabarit/app/error.hpp"
#include "gabarit/app/evaluation.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const auto poses = gabarit::app::read_pose_csv(in, "fuzz.csv");
    const gabarit::app::Accuracy a = gabarit::app::evaluate(poses, poses);
    const std::string json = gabarit::app::accuracy_json(a);
    if (json.find("nan") != std::string::npos || json.find("inf") != std::string::npos) std::abort();
    if (!std::isfinite(a.mean_error_px) || !std::isfinite(a.max_error_deg)) std::abort();
  } catch (const gabarit::app::Error&) {
  }
  return 0;
}
