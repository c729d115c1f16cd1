// Single-frame voting trials (the thesis's section 6.2 protocol, "one-step"):
// a shape at a known previous position moves by a random integer step within
// +-kMaxStep px per axis, the frame gets salt-and-pepper noise, and an
// estimator is asked for the new position. The bench's experiments
// (tools/bench/experiments.hpp) and the hardware voter's co-simulation
// (tests/hdl) share these trials and tables.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "gabarit/app/image_io.hpp"
#include "gabarit/host/tables/decimation.hpp"
#include "gabarit/host/scenes/synth.hpp"

namespace gabarit::host {

inline constexpr std::int32_t kMaxStep = 4;    // motion per axis and frame
inline constexpr const char* kCellAxis = "-5:5:11";  // 1-pixel cells over +-5 px

struct Shape {
  std::string name;
  std::vector<Point> points;
  std::uint32_t width = 0, height = 0;  // frame size
};
Shape make_shape(const std::string& name, std::vector<Point> points);

struct Trial {
  app::GrayImage frame;
  Point previous;
  Point truth;
};
// `count` trials at noise rate `noise`, deterministic in `seed`.
std::vector<Trial> make_trials(const Shape& shape, double noise, std::size_t count, std::uint64_t seed);

// A table for the shape (binary detector, 1-pixel cells over +-5 px),
// decimated to `keep` by `policy`.
std::vector<std::byte> shape_table(const Shape& shape, double keep, std::uint64_t seed, const DecimationPolicy& policy = {});

}  // namespace gabarit::host
