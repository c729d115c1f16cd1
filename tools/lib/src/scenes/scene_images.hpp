// The scene synthesiser's images (private to tools/lib/src/scenes): float
// planes, the objects cut from Debian's photographs with their coverage, an
// object's look at each depth of a focus stack, backgrounds, and drawing an
// object rotated into a frame. scene_synth.cpp composes scenes from them.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "gabarit/app/image_io.hpp"
#include "gabarit/host/scenes/scene_synth.hpp"

namespace gabarit::host::scene {

constexpr double kPi = 3.14159265358979323846;

// A float image, the working format before quantisation.
struct Plane {
  int w = 0, h = 0;
  std::vector<double> v;
  Plane(int width, int height, double fill = 0) : w(width), h(height), v(static_cast<std::size_t>(width) * height, fill) {}
  double& at(int x, int y) { return v[static_cast<std::size_t>(y) * w + x]; }
  double at(int x, int y) const { return v[static_cast<std::size_t>(y) * w + x]; }
  double clamped(int x, int y) const { return at(std::clamp(x, 0, w - 1), std::clamp(y, 0, h - 1)); }
  double bilinear(double x, double y) const {
    const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
    const double fx = x - x0, fy = y - y0;
    return (1 - fy) * ((1 - fx) * clamped(x0, y0) + fx * clamped(x0 + 1, y0)) +
           fy * ((1 - fx) * clamped(x0, y0 + 1) + fx * clamped(x0 + 1, y0 + 1));
  }
};

// The object in its own frame, a square of side 2 * half + 1 centred on its
// reference point: grey, coverage (alpha), and after object_at_depth the
// premultiplied grey (value * coverage).
struct Layer {
  int half = 0;
  Plane premultiplied{1, 1};
  Plane alpha{1, 1};
};
struct ObjectImage {
  int radius = 0;  // of the object's outline, pixels
  int half = 0;
  Plane grey{1, 1};
  Plane alpha{1, 1};
  // An object whose look changes with the illumination (the glass pipette):
  // its other look; frames blend the two (appearance_at).
  bool changes_look = false;
  Plane other_grey{1, 1};
};

Plane from_photo(const app::GrayImage& g);
// A Debian package's photograph (thesis_shapes.hpp, debian_photo_pgm) as a plane.
Plane photo(const char* name);
Plane gaussian_blur(const Plane& in, double sigma);
// Averages `scale` x `scale` blocks of `src` around (cx, cy) into a square of side 2 * half + 1.
Plane downscaled(const Plane& src, double cx, double cy, int scale, int half);
ObjectImage make_object(SceneObject which);
// The object's look at depth n of a focus stack of `depths` (see the definition).
Layer object_at_depth(const ObjectImage& object, int n, int depths, FocusStackKind kind);
// Draws `object` rotated by theta about its centre, centred at (x, y). If
// `coverage_out` is given, the object's coverage is accumulated there.
void composite(Plane& frame, const Layer& object, double x, double y, double theta_deg, double gain, Plane* coverage_out = nullptr);
void write_plane_pgm(const std::string& path, const Plane& p);
Plane background_of(SceneBackground which, int w, int h);

}  // namespace gabarit::host::scene
