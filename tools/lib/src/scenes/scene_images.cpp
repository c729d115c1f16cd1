#include "scene_images.hpp"

#include <algorithm>
#include <cmath>

#include "gabarit/app/error.hpp"
#include "gabarit/host/scenes/thesis_shapes.hpp"

namespace gabarit::host::scene {

Plane from_photo(const app::GrayImage& g) {
  Plane p(static_cast<int>(g.width), static_cast<int>(g.height));
  for (std::size_t i = 0; i < p.v.size(); ++i) p.v[i] = g.pixels[i];
  return p;
}
Plane photo(const char* name) { return from_photo(app::read_pgm(debian_photo_pgm(name))); }

Plane gaussian_blur(const Plane& in, double sigma) {
  if (sigma < 0.05) return in;
  const int r = static_cast<int>(std::ceil(3 * sigma));
  std::vector<double> k(static_cast<std::size_t>(2 * r + 1));
  double sum = 0;
  for (int i = -r; i <= r; ++i) sum += k[static_cast<std::size_t>(i + r)] = std::exp(-0.5 * i * i / (sigma * sigma));
  for (double& x : k) x /= sum;
  Plane tmp(in.w, in.h), out(in.w, in.h);
  for (int y = 0; y < in.h; ++y)
    for (int x = 0; x < in.w; ++x) {
      double a = 0;
      for (int i = -r; i <= r; ++i) a += k[static_cast<std::size_t>(i + r)] * in.clamped(x + i, y);
      tmp.at(x, y) = a;
    }
  for (int y = 0; y < in.h; ++y)
    for (int x = 0; x < in.w; ++x) {
      double a = 0;
      for (int i = -r; i <= r; ++i) a += k[static_cast<std::size_t>(i + r)] * tmp.clamped(x, y + i);
      out.at(x, y) = a;
    }
  return out;
}


double coverage(double signed_distance) { return std::clamp(signed_distance + 0.5, 0.0, 1.0); }

// Averages `scale` x `scale` blocks of `src` around (cx, cy) into a square of side 2 * half + 1.
Plane downscaled(const Plane& src, double cx, double cy, int scale, int half) {
  Plane out(2 * half + 1, 2 * half + 1);
  for (int y = 0; y < out.h; ++y)
    for (int x = 0; x < out.w; ++x) {
      const int sx = static_cast<int>(std::lround(cx)) + scale * (x - half), sy = static_cast<int>(std::lround(cy)) + scale * (y - half);
      double a = 0;
      for (int j = 0; j < scale; ++j)
        for (int i = 0; i < scale; ++i) a += src.clamped(sx + i, sy + j);
      out.at(x, y) = a / (scale * scale);
    }
  return out;
}

ObjectImage make_object(SceneObject which) {
  ObjectImage o;
  const auto begin = [&](int radius) {
    o.radius = radius;
    o.half = radius + 8;  // room for the blurred outline
    o.grey = Plane(2 * o.half + 1, 2 * o.half + 1);
    o.alpha = Plane(2 * o.half + 1, 2 * o.half + 1);
  };
  const auto mask = [&](auto&& signed_distance) {
    for (int y = 0; y < o.alpha.h; ++y)
      for (int x = 0; x < o.alpha.w; ++x) o.alpha.at(x, y) = coverage(signed_distance(x - o.half, y - o.half));
  };
  const auto ellipse = [](double a, double b) {
    return [a, b](double x, double y) { return (1.0 - std::hypot(x / a, y / b)) * std::min(a, b); };
  };
  switch (which) {
    case SceneObject::kCog: {
      // The square around the cameraman's head and camera, 2x box-downscaled;
      // a five-lobed outline, so the outline shows the orientation.
      begin(44);
      o.grey = downscaled(photo("camera"), 134 + 2 * o.half, 24 + 2 * o.half, 2, o.half);
      const double r = o.radius;
      mask([r](double x, double y) { return r * (0.84 + 0.16 * std::cos(5 * std::atan2(y, x))) - std::hypot(x, y); });
      break;
    }
    case SceneObject::kCoin:
      begin(21);
      o.grey = downscaled(photo("coins"), 156, 50, 1, o.half);
      mask(ellipse(21, 21));
      break;
    case SceneObject::kHorse: {
      begin(70);
      const Plane horse = downscaled(photo("horse"), 200, 164, 3, o.half);
      const Plane moon = downscaled(photo("moon"), 256, 256, 1, o.half);
      for (std::size_t i = 0; i < o.alpha.v.size(); ++i) {
        o.alpha.v[i] = std::clamp(1.0 - horse.v[i] / 255.0, 0.0, 1.0);  // the black silhouette
        o.grey.v[i] = 40 + 0.5 * moon.v[i];
      }
      break;
    }
    case SceneObject::kPipette: {
      // A glass tube tapering from 9 to 3 px half-width over 180 px, with a
      // dark rim and a bright core: every cross-section alike.
      begin(90);
      const double length = 90;
      const auto half_width = [&](double x) { return 9.0 - 6.0 * (x + length) / (2 * length); };
      mask([&](double x, double y) { return std::min(half_width(x) - std::fabs(y), length - std::fabs(x)); });
      for (int y = 0; y < o.grey.h; ++y)
        for (int x = 0; x < o.grey.w; ++x) {
          const double d = half_width(x - o.half) - std::fabs(y - o.half);
          o.grey.at(x, y) = 215 - 150 * std::exp(-0.5 * (d - 1) * (d - 1));
        }
      break;
    }
    case SceneObject::kGlassPipette: {
      // Half-width 8 px at the open end (x = -90) to 3 px at the closed tip
      // (x = +90, rounded). Mostly transparent: the wall (~1.5 px) is dense,
      // the bore lets 80% of the background through and brightens it a
      // little (the lens). This is the high-contrast look; other_grey is the
      // low-contrast one (a paler wall, a dimmer bore), and frames blend the two.
      begin(90);
      const double length = 90;
      const auto half_width = [&](double x) { return 8.0 - 5.0 * (std::clamp(x, -length, length) + length) / (2 * length); };
      const auto inside = [&](double x, double y) {  // signed distance to the wall, > 0 inside
        const double tip = length - half_width(length);
        if (x <= tip) return std::min(half_width(x) - std::fabs(y), x + length);
        return half_width(length) - std::hypot(x - tip, y);
      };
      for (int y = 0; y < o.alpha.h; ++y)
        for (int x = 0; x < o.alpha.w; ++x) {
          const double d = inside(x - o.half, y - o.half);
          const double wall = std::exp(-0.5 * (d - 1.0) * (d - 1.0));
          o.alpha.at(x, y) = coverage(d) * (0.2 + 0.75 * wall);
          o.grey.at(x, y) = 40 + 170 * (1 - wall);  // dark wall, bright bore
        }
      o.changes_look = true;
      o.other_grey = o.grey;
      for (int y = 0; y < o.alpha.h; ++y)
        for (int x = 0; x < o.alpha.w; ++x) {
          const double d = inside(x - o.half, y - o.half);
          const double wall = std::exp(-0.5 * (d - 1.0) * (d - 1.0));
          o.other_grey.at(x, y) = 95 * wall + 150 * (1 - wall);  // lit from the side: a paler wall, a dimmer bore
        }
      break;
    }
    case SceneObject::kCat:
      begin(50);
      o.grey = downscaled(photo("chelsea"), 240, 150, 3, o.half);
      mask(ellipse(50, 40));
      break;
    case SceneObject::kAstronaut:
      begin(32);
      o.grey = downscaled(photo("astronaut"), 225, 110, 2, o.half);
      mask(ellipse(32, 32));
      break;
    case SceneObject::kCup:
      begin(66);
      o.grey = downscaled(photo("coffee"), 280, 205, 3, o.half);
      mask(ellipse(66, 53));
      break;
    case SceneObject::kSmall:
      // The cameraman's hand and camera, 4x box-downscaled into a 36x32 ellipse.
      begin(18);
      o.grey = downscaled(photo("camera"), 300, 170, 4, o.half);
      mask(ellipse(18, 16));
      break;
    case SceneObject::kLarge: {
      begin(100);
      o.grey = downscaled(photo("camera"), 256, 190, 1, o.half);
      const double r = o.radius, corner = 24;
      mask([r, corner](double x, double y) {  // a rounded square
        const double qx = std::fabs(x) - (r - corner), qy = std::fabs(y) - (r - corner);
        const double outside = std::hypot(std::max(qx, 0.0), std::max(qy, 0.0)) + std::min(std::max(qx, qy), 0.0);
        return corner - outside;
      });
      break;
    }
  }
  return o;
}

// The object at depth n of `depths`. Tilted: the blur of each column of its
// texture grows with the column's distance from the column in focus, which
// sweeps across the object as n goes from 0 to depths - 1. Alike: the whole
// texture blurred by a sigma growing with n, the two middle depths 0.15 px
// apart. (The outline stays sharp: blurring it too was tried and made every
// axis less accurate, the depth barely more; see docs/experiments.md.)
Layer object_at_depth(const ObjectImage& object, int n, int depths, FocusStackKind kind) {
  constexpr int kLevels = 8;
  constexpr double kSigmaPerPx = 0.05 * 44;  // per object radius: blur growth away from the focused column
  const Plane& grey = object.grey;
  const Plane& alpha = object.alpha;
  Layer out;
  out.half = object.half;
  out.alpha = alpha;
  out.premultiplied = Plane(grey.w, grey.h);
  if (depths <= 1) {
    for (std::size_t i = 0; i < grey.v.size(); ++i) out.premultiplied.v[i] = alpha.v[i] * grey.v[i];
    return out;
  }
  if (kind == FocusStackKind::kAlike) {
    double sigma = 0.7 * n;
    if (n > depths / 2) sigma = 0.7 * (n - 1) + 0.15;  // depth depths/2 + 1 looks like depth depths/2
    const Plane blurred = gaussian_blur(grey, sigma);
    for (std::size_t i = 0; i < grey.v.size(); ++i) out.premultiplied.v[i] = alpha.v[i] * blurred.v[i];
    return out;
  }
  std::vector<Plane> levels;
  for (int l = 0; l < kLevels; ++l) levels.push_back(gaussian_blur(grey, 0.5 * l));
  const double r = object.radius;
  const double focus = -r + 2.0 * r * n / (depths - 1);
  for (int y = 0; y < grey.h; ++y)
    for (int x = 0; x < grey.w; ++x) {
      const double sigma = kSigmaPerPx / r * std::abs((x - object.half) - focus);
      const double level = std::min(sigma / 0.5, kLevels - 1.0);
      const int l0 = static_cast<int>(level);
      const int l1 = std::min(l0 + 1, kLevels - 1);
      const double f = level - l0;
      const double g = (1 - f) * levels[static_cast<std::size_t>(l0)].at(x, y) + f * levels[static_cast<std::size_t>(l1)].at(x, y);
      out.premultiplied.at(x, y) = alpha.at(x, y) * g;
    }
  return out;
}

// Draws `object` rotated by theta about its centre, centred at (x, y). If
// `coverage_out` is given, the object's coverage is accumulated there.
void composite(Plane& frame, const Layer& object, double x, double y, double theta_deg, double gain, Plane* coverage_out) {
  const double c = std::cos(theta_deg * kPi / 180), s = std::sin(theta_deg * kPi / 180);
  const int half = object.half, side = 2 * half + 1;
  // The rotated square reaches sqrt(2) * half from its centre.
  const int reach = static_cast<int>(std::ceil(1.4143 * half)) + 2;
  const int x0 = static_cast<int>(std::floor(x)) - reach, x1 = static_cast<int>(std::ceil(x)) + reach;
  const int y0 = static_cast<int>(std::floor(y)) - reach, y1 = static_cast<int>(std::ceil(y)) + reach;
  for (int py = std::max(0, y0); py <= std::min(frame.h - 1, y1); ++py)
    for (int px = std::max(0, x0); px <= std::min(frame.w - 1, x1); ++px) {
      const double dx = px - x, dy = py - y;
      // Inverse rotation: the object point that lands here.
      const double ox = c * dx + s * dy + half, oy = -s * dx + c * dy + half;
      if (ox < 0 || oy < 0 || ox > side - 1 || oy > side - 1) continue;
      const double alpha = object.alpha.bilinear(ox, oy);
      if (alpha <= 0) continue;
      frame.at(px, py) = (1 - alpha) * frame.at(px, py) + gain * object.premultiplied.bilinear(ox, oy);
      if (coverage_out) coverage_out->at(px, py) += alpha;
    }
}

void write_plane_pgm(const std::string& path, const Plane& p) {
  app::GrayImage g(static_cast<std::uint32_t>(p.w), static_cast<std::uint32_t>(p.h));
  for (std::size_t i = 0; i < p.v.size(); ++i) g.pixels[i] = static_cast<std::uint8_t>(std::clamp(std::lround(p.v[i]), 0L, 255L));
  app::write_pgm(path, g);
}

Plane background_of(SceneBackground which, int w, int h) {
  Plane out(w, h);
  if (which == SceneBackground::kSmooth) {  // no clutter: a soft gradient
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) out.at(x, y) = 90 + 60.0 * x / w + 30.0 * y / h;
    return out;
  }
  const char* name = which == SceneBackground::kGravel ? "gravel"
                     : which == SceneBackground::kGrass ? "grass"
                     : which == SceneBackground::kBrick ? "brick"
                     : which == SceneBackground::kMoon  ? "moon"
                                                        : "page";
  const Plane p = photo(name);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) out.at(x, y) = p.at(x % p.w, y % p.h);
  return out;
}

}  // namespace gabarit::host::scene
