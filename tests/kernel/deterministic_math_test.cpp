#include "gabarit/deterministic_math.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace gabarit {
namespace {

TEST(DeterministicMath, SinCosAgreeWithLibmWithinAMillionth) {
  for (double deg = -720; deg <= 720; deg += 0.37) {
    const SinCos sc = sin_cos_deg(static_cast<float>(deg));
    const double rad = static_cast<double>(static_cast<float>(deg)) * M_PI / 180.0;
    EXPECT_NEAR(sc.sin, std::sin(rad), 1e-6) << deg;
    EXPECT_NEAR(sc.cos, std::cos(rad), 1e-6) << deg;
  }
}

TEST(DeterministicMath, ExactAtRightAngles) {
  EXPECT_EQ(sin_cos_deg(0).sin, 0.0f);
  EXPECT_EQ(sin_cos_deg(0).cos, 1.0f);
  EXPECT_EQ(sin_cos_deg(90).sin, 1.0f);
  EXPECT_EQ(sin_cos_deg(180).cos, -1.0f);
  EXPECT_EQ(sin_cos_deg(-90).sin, -1.0f);
}

TEST(DeterministicMath, RoundsHalvesAwayFromZero) {
  EXPECT_EQ(round_to_int(0.5f), 1);
  EXPECT_EQ(round_to_int(-0.5f), -1);
  EXPECT_EQ(round_to_int(1.49f), 1);
  EXPECT_EQ(round_to_int(-1.51f), -2);
  EXPECT_EQ(round_to_int(0.0f), 0);
}

}  // namespace
}  // namespace gabarit
