// The thesis-grid regression test: a small version of `gabarit bench`'s
// wrong-frame grid (both thesis shapes, noise x references kept). Seeds are
// fixed and every computation is integer or deterministic float, so the
// counts are exact on every target; the test fails if any count is worse than
// the recorded baseline (tests/tools/grid_baseline.csv, written by
// `gabarit bench --regression-csv FILE`). No timing is asserted.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <sstream>

#include "experiments.hpp"
#include "gabarit/app/error.hpp"
#include "gabarit/host/scenes/thesis_shapes.hpp"

namespace gabarit::bench {
namespace {

TEST(ThesisGrid, WrongFramesAreNoWorseThanTheBaseline) {
  std::vector<Shape> shapes = {make_shape("curve", host::thesis_curve())};
  try {
    shapes.push_back(make_shape("watch", host::watch_shape()));
  } catch (const app::Error& e) {
    GTEST_SKIP() << "watch photograph unavailable (" << e.what() << "); tools/scripts/setup-debian.sh installs it";
  }
  std::ifstream in(GABARIT_GRID_BASELINE);
  ASSERT_TRUE(in) << "missing " << GABARIT_GRID_BASELINE;
  std::map<std::string, std::size_t> baseline;
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string shape, noise, keep, frames, wrong;
    std::getline(ss, shape, ',');
    std::getline(ss, noise, ',');
    std::getline(ss, keep, ',');
    std::getline(ss, frames, ',');
    std::getline(ss, wrong, ',');
    baseline[shape + " noise " + noise + " keep " + keep] = std::stoul(wrong);
  }
  GridSpec spec = regression_grid_spec();
  spec.threads = 2;
  const auto rows = run_grid(shapes, spec);
  ASSERT_EQ(rows.size(), baseline.size());
  std::size_t better = 0;
  for (const GridRow& r : rows) {
    std::ostringstream key;
    key << r.shape << " noise " << r.noise << " keep " << r.keep;
    const auto it = baseline.find(key.str());
    ASSERT_NE(it, baseline.end()) << key.str() << " not in the baseline";
    EXPECT_LE(r.wrong, it->second) << key.str() << ": " << r.wrong << " wrong frames, baseline " << it->second;
    better += r.wrong < it->second;
  }
  if (better) std::printf("%zu grid points improved: rewrite the baseline with gabarit bench --regression-csv\n", better);
  // The thesis's limits hold at full stencils: no wrong frame up to 40% noise
  // (curve) and 44% (watch) in this small grid.
  for (const GridRow& r : rows) {
    if (r.keep == 1.0 && r.noise <= (r.shape == "curve" ? 0.40 : 0.44)) {
      EXPECT_EQ(r.wrong, 0u) << r.shape << " at " << r.noise;
    }
  }
}

}  // namespace
}  // namespace gabarit::bench
