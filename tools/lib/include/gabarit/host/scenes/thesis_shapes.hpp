// The point shapes of the thesis's synthetic experiments (section 6.2), and
// the `--shape` argument that names them:
//   random        a random hand-drawn-like closed curve (--points, --seed)
//   curve         the fixed ~194-point closed curve
//   watch         ~2800 edge points of a real photograph from a Debian package
//                 (python3-skimage's coffee.png, a round cup on a saucer),
//                 converted to PGM at run time with netpbm; never committed
//   photo:F.pgm   ~N edge points (--points, default 2800) of any PGM photograph
//   FILE.csv      integer x,y points relative to the reference point
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "gabarit/app/image_io.hpp"
#include "gabarit/host/tables/model.hpp"

namespace gabarit::host {

std::vector<Point> thesis_curve();

// Edge points (gradient-rows detector, threshold searched so the count comes
// closest to `target`) of `photo` after averaging `downscale` x `downscale`
// blocks, relative to the image centre.
std::vector<Point> photo_edge_points(const app::GrayImage& photo, std::size_t target, std::uint32_t downscale);

// A photograph of python3-skimage's data folder (NAME.png: coffee, camera,
// gravel, brick, ...) converted to PGM with netpbm into the temporary
// directory, once; returns its path. Throws app::Error saying what to install.
std::string debian_photo_pgm(const std::string& name);

// The Debian photograph behind `watch` as a PGM path: $GABARIT_WATCH_PGM if
// set, else python3-skimage's coffee.png converted with pngtopnm | ppmtopgm
// into the temporary directory. Throws app::Error saying what to install.
std::string watch_photo_pgm();
std::vector<Point> watch_shape();

// Resolves a --shape argument (see above). `points` and `seed` apply to
// `random` and `photo:`.
std::vector<Point> resolve_shape(const std::string& spec, std::size_t points, std::uint64_t seed);

}  // namespace gabarit::host
