#include "gabarit/host/scenes/synth.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <set>

#include "gabarit/app/error.hpp"
#include "gabarit/app/files.hpp"

namespace gabarit::host {
namespace {

std::filesystem::path temp_dir(const char* name) { return std::filesystem::temp_directory_path() / name; }

TEST(Synth, RandomCurveIsAClosedCurveOfAboutTheRequestedSize) {
  for (std::size_t target : {100u, 194u, 2800u}) {
    const auto curve = random_closed_curve(target, 3);
    EXPECT_NEAR(static_cast<double>(curve.size()), static_cast<double>(target), 0.1 * static_cast<double>(target));
    const std::set<Point> unique(curve.begin(), curve.end());
    EXPECT_EQ(unique.size(), curve.size());
    // Closed and connected: consecutive points (and last->first) are 8-neighbours.
    for (std::size_t i = 0; i < curve.size(); ++i) {
      const Point& a = curve[i];
      const Point& b = curve[(i + 1) % curve.size()];
      EXPECT_LE(std::max(std::abs(a.x - b.x), std::abs(a.y - b.y)), 1) << "gap after point " << i;
    }
  }
  EXPECT_EQ(random_closed_curve(194, 3), random_closed_curve(194, 3));
  EXPECT_NE(random_closed_curve(194, 3), random_closed_curve(194, 4));
}

TEST(Synth, SequencesAreDeterministicAndMoveWithinTheBound) {
  SynthOptions o;
  o.shape = random_closed_curve(150, 1);
  o.frames = 40;
  o.max_step = 4;
  o.noise = 0.2;
  o.seed = 9;
  o.width = 160;
  o.height = 140;
  const auto a = write_synthetic_sequence(o, temp_dir("gabarit_synth_a").string());
  const auto b = write_synthetic_sequence(o, temp_dir("gabarit_synth_b").string());
  EXPECT_EQ(app::read_file((temp_dir("gabarit_synth_a") / "frames.y4m").string()),
            app::read_file((temp_dir("gabarit_synth_b") / "frames.y4m").string()));
  ASSERT_EQ(a.size(), 40u);
  for (std::size_t i = 1; i < a.size(); ++i) {
    EXPECT_LE(std::abs(a[i].x - a[i - 1].x), 4);
    EXPECT_LE(std::abs(a[i].y - a[i - 1].y), 4);
    EXPECT_EQ(a[i].x, b[i].x);
  }
  std::filesystem::remove_all(temp_dir("gabarit_synth_a"));
  std::filesystem::remove_all(temp_dir("gabarit_synth_b"));
}

TEST(Synth, NoiseFlipsPixelsAtTheRequestedRate) {
  SynthOptions o;
  o.shape = {{0, 0}};
  o.width = o.height = 200;
  for (double p : {0.0, 0.1, 0.5}) {
    o.noise = p;
    const app::GrayImage img = render_frame(o, 100, 100, 1234);
    std::size_t lit = 0;
    for (auto v : img.pixels) lit += v != 0;
    EXPECT_NEAR(static_cast<double>(lit) / static_cast<double>(img.pixels.size()), p, 0.01) << p;
  }
}

TEST(Synth, RejectsShapesThatDoNotFit) {
  SynthOptions o;
  o.shape = {{-100, 0}, {100, 0}};
  o.width = o.height = 64;
  EXPECT_THROW(write_synthetic_sequence(o, temp_dir("gabarit_synth_c").string()), app::Error);
}

}  // namespace
}  // namespace gabarit::host
