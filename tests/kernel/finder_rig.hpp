// The detection tests' scene (model_finder_test.cpp, finder_search_test.cpp):
// a 33-point model in a 320 x 320 frame, its finder with the default options
// and scratch for both levels, and a frame holding the model twice.
#pragma once

#include <algorithm>

#include "gabarit/app/scratch.hpp"
#include "gabarit/model_finder.hpp"
#include "test_tables.hpp"

namespace gabarit::testing {

inline constexpr std::uint32_t kFinderSide = 320;

// 0.5-degree cells: a detection within 1 degree is then a cell's worth.
struct FinderRig : PointScene {
  FinderRig() : PointScene(33, 70, 20, "-4:4:9", "-2:2:9", kFinderSide, 0.005) {}
};

struct Finding {
  FinderRig rig;
  ModelFinder finder{rig.table, detector_of(rig.table)};
  FinderOptions options;
  app::FinderBuffers buffers{rig.table, detector_of(rig.table), options, kFinderSide, kFinderSide};
  TrackerTestScratch fine{rig.table};
};

// A frame holding the rig's model twice: at (x, y, theta) and at the copy's place.
inline app::GrayImage twins(const FinderRig& rig, float x, float y, float theta, float cx, float cy, float ctheta) {
  app::GrayImage a = draw_points(rig.points, x, y, theta, kFinderSide);
  const app::GrayImage b = draw_points(rig.points, cx, cy, ctheta, kFinderSide);
  for (std::size_t i = 0; i < a.pixels.size(); ++i) a.pixels[i] = std::max(a.pixels[i], b.pixels[i]);
  return a;
}

}  // namespace gabarit::testing
