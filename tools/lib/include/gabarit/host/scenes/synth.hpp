// Synthetic sequences of the thesis (section 6.2): a point shape translated
// over an empty image by a random integer displacement within +-max_step px
// per axis and frame, kept inside the image, then salt-and-pepper noise of
// rate p (each pixel flips between 0 and 255 with probability p).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "gabarit/app/image_io.hpp"
#include "gabarit/host/tables/model.hpp"

namespace gabarit::host {

// A hand-drawn-like closed curve: a radius that wobbles with a few random
// low harmonics, rasterised to about `target_points` distinct pixels around
// the origin. Deterministic per seed.
std::vector<Point> random_closed_curve(std::size_t target_points, std::uint64_t seed);

struct SynthOptions {
  std::vector<Point> shape;  // relative to the reference point
  std::uint32_t frames = 100;
  std::int32_t max_step = 4;
  // Instead of independent steps: a velocity random walk (each frame the
  // velocity changes by -1, 0 or +1 px per axis, |v| <= max_step) that
  // reverses at the image margins.
  bool velocity_walk = false;
  double noise = 0.0;
  std::uint64_t seed = 1;
  std::uint32_t width = 256;
  std::uint32_t height = 256;
};

struct TruthRow {
  std::uint32_t frame;
  std::int32_t x, y;
};

// Grows width/height (from at least 256x256) so the shape fits with room to move.
void fit_image_to_shape(SynthOptions& options);

// Writes DIR/frames.y4m, DIR/gt.csv, DIR/model.csv and DIR/model.pgm (the
// shape drawn with its reference point at the image centre floor(w/2),
// floor(h/2), so `tables build --model model.pgm --binary` agrees with
// `--model-points model.csv`). Returns the ground truth.
std::vector<TruthRow> write_synthetic_sequence(const SynthOptions& options, const std::string& dir);

// The sequence's positions, one per frame (write_synthetic_sequence's), and
// the seed of frame f's noise: render_frame(o, x, y, synthetic_frame_seed(o, f))
// is the sequence's frame f, so a study can render frames as it goes.
// Throws app::Error for options out of range.
std::vector<TruthRow> synthetic_trajectory(const SynthOptions& options);
std::uint64_t synthetic_frame_seed(const SynthOptions& options, std::uint32_t frame);

// Renders one frame: shape at (x, y), then noise from `rng`-seeded draws.
app::GrayImage render_frame(const SynthOptions& options, std::int32_t x, std::int32_t y, std::uint64_t frame_seed);

}  // namespace gabarit::host
