// The pose of the tracked object: what every tracking stage reads and writes.
#pragma once

#include <cstdint>

#include "gabarit/deterministic_math.hpp"

namespace gabarit {

struct Pose {
  float x = 0.0f;          // image position of the model's reference point, pixels
  float y = 0.0f;
  float theta_deg = 0.0f;  // rotation about the reference point, degrees
  std::uint16_t depth = 0; // focus-stack index
};

// The range every pose-taking entry point accepts: x, y and theta_deg finite
// and within +-kPoseLimit (pixels, degrees), so that rounding to pixels and
// the fixed-point geometry downstream cannot overflow.
inline constexpr float kPoseLimit = 1.0e6f;
constexpr bool pose_in_range(const Pose& p) noexcept {
  return within_limit(p.x, kPoseLimit) && within_limit(p.y, kPoseLimit) && within_limit(p.theta_deg, kPoseLimit);
}

}  // namespace gabarit
