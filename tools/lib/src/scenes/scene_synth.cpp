#include "gabarit/host/scenes/scene_synth.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "gabarit/app/error.hpp"
#include "gabarit/app/files.hpp"
#include "gabarit/app/image_io.hpp"
#include "gabarit/app/rng.hpp"
#include "gabarit/host/scenes/thesis_shapes.hpp"

namespace gabarit::host {
namespace {

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

struct Pose4 {
  double x, y, theta;
  int depth;
};

// Draws `object` rotated by theta about its centre, centred at (x, y). If
// `coverage_out` is given, the object's coverage is accumulated there.
void composite(Plane& frame, const Layer& object, double x, double y, double theta_deg, double gain,
               Plane* coverage_out = nullptr) {
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

template <typename E, std::size_t N>
bool parse_from(const std::string& s, E& out, const std::array<E, N>& all) {
  for (E v : all)
    if (s == name_of(v)) return out = v, true;
  return false;
}

// The smooth trajectory of a scene (sinusoids of random periods and phases,
// drawn from `rng` in a fixed order) and its depth schedule.
class ScenePath {
 public:
  ScenePath(const SceneOptions& o, double margin, app::Rng& rng)
      : o_(o),
        px_(90 + 40 * rng.next_unit()), py_(70 + 40 * rng.next_unit()), pt_(120 + 60 * rng.next_unit()),
        phx_(2 * kPi * rng.next_unit()), phy_(2 * kPi * rng.next_unit()), pht_(2 * kPi * rng.next_unit()) {
    const bool slow = o.motion == SceneMotion::kSweep || o.motion == SceneMotion::kSpin;
    const double speed = o.max_speed_px * (slow ? 0.6 : o.motion == SceneMotion::kStopGo ? 1.0 / 1.6 : 1.0);
    ax_ = std::min(speed * px_ / (2 * kPi), o.width / 2.0 - margin);
    ay_ = std::min(speed * py_ / (2 * kPi), o.height / 2.0 - margin);
    at_ = o.max_turn_deg * pt_ / (2 * kPi);
    depth_every_ = o.motion == SceneMotion::kSweep ? 6 : 20;
  }
  int depth_at(double t) const {  // up and down the stack
    const int period = 2 * std::max(1, o_.depths - 1);
    const int phase = static_cast<int>(t / depth_every_) % period;
    return o_.depths <= 1 ? 0 : (phase < o_.depths ? phase : period - phase);
  }
  Pose4 at(double t) const {
    return Pose4{o_.width / 2.0 + ax_ * std::sin(2 * kPi * t / px_ + phx_), o_.height / 2.0 + ay_ * std::sin(2 * kPi * t / py_ + phy_),
                 at_ * std::sin(2 * kPi * t / pt_ + pht_), depth_at(t)};
  }

 private:
  const SceneOptions& o_;
  double px_, py_, pt_, phx_, phy_, pht_;
  double ax_ = 0, ay_ = 0, at_ = 0;
  int depth_every_ = 20;
};

// The pose at every frame, path[f + 1] for frame f and path[0] the instant
// before: the smooth path (smooth, sweep), its clock run in bursts (stop-go),
// a steady spin, or a velocity random walk reversed at the margins (walk).
std::vector<Pose4> scene_path(const SceneOptions& o, double margin, const ScenePath& smooth, app::Rng& rng) {
  std::vector<Pose4> path(o.frames + 1);
  if (o.motion == SceneMotion::kSmooth || o.motion == SceneMotion::kSweep) {
    for (std::uint32_t f = 0; f <= o.frames; ++f) path[f] = smooth.at(static_cast<double>(f) - 1.0);
  } else if (o.motion == SceneMotion::kStopGo) {
    // The smooth path's clock runs in bursts: 0 or 1.6x for 10..29 frames each.
    double clock = -1;
    bool moving = rng.next_unit() < 0.5;
    int left = 10 + static_cast<int>(20 * rng.next_unit());
    for (std::uint32_t f = 0; f <= o.frames; ++f) {
      path[f] = smooth.at(clock);
      path[f].depth = smooth.depth_at(static_cast<double>(f) - 1.0);
      if (--left <= 0) moving = !moving, left = 10 + static_cast<int>(20 * rng.next_unit());
      clock += moving ? 1.6 : 0.0;
    }
  } else if (o.motion == SceneMotion::kSpin) {
    const double rate = (rng.next_unit() < 0.5 ? -1.0 : 1.0) * 1.2;
    for (std::uint32_t f = 0; f <= o.frames; ++f) {
      path[f] = smooth.at(static_cast<double>(f) - 1.0);
      path[f].theta = rate * (static_cast<double>(f) - 1.0);
    }
  } else {  // kWalk: velocity random walk, reversed at the margins
    const double vmax = o.max_speed_px, turn_max = o.max_turn_deg;
    double x = o.width / 2.0, y = o.height / 2.0, theta = 0, vx = 0, vy = 0, vt = 0;
    const double lo_x = margin, hi_x = o.width - margin, lo_y = margin, hi_y = o.height - margin;
    for (std::uint32_t f = 0; f <= o.frames; ++f) {
      path[f] = {x, y, theta, smooth.depth_at(static_cast<double>(f) - 1.0)};
      vx = std::clamp(vx + 1.2 * (rng.next_unit() - 0.5), -vmax, vmax);
      vy = std::clamp(vy + 1.2 * (rng.next_unit() - 0.5), -vmax, vmax);
      vt = std::clamp(vt + 0.4 * (rng.next_unit() - 0.5), -turn_max, turn_max);
      if (x + vx < lo_x || x + vx > hi_x) vx = -vx;
      if (y + vy < lo_y || y + vy > hi_y) vy = -vy;
      if (std::fabs(theta + vt) > 30) vt = -vt;
      x += vx, y += vy, theta += vt;
    }
  }
  return path;
}

// The occluder's square of brick, at its final place over the object shifted
// back towards its side by (1 - travel) of its side, painted into `frame`;
// returns the share of the object (`cover`, its alpha) it hides.
double paint_occluder(Plane& frame, const Plane& cover, const Plane& brick, const Pose4& p, double travel, int side,
                      OcclusionSide from, double gain) {
  int ox = static_cast<int>(std::lround(p.x)) - side / 2, oy = static_cast<int>(std::lround(p.y)) - side / 2;
  const int shift = static_cast<int>(std::lround((1 - travel) * side));
  if (from == OcclusionSide::kLeft) ox -= shift;
  if (from == OcclusionSide::kRight) ox += shift;
  if (from == OcclusionSide::kTop) oy -= shift;
  if (from == OcclusionSide::kBottom) oy += shift;
  double covered = 0, total = 0;
  for (double a : cover.v) total += a;
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x)
      if (ox + x >= 0 && oy + y >= 0 && ox + x < frame.w && oy + y < frame.h) {
        frame.at(ox + x, oy + y) = gain * brick.at((x + 200) % brick.w, (y + 100) % brick.h);
        covered += cover.at(ox + x, oy + y);
      }
  return total > 0 ? covered / total : 1;
}

}  // namespace


const char* name_of(SceneObject v) noexcept {
  switch (v) {
    case SceneObject::kCog: return "cog";
    case SceneObject::kCoin: return "coin";
    case SceneObject::kHorse: return "horse";
    case SceneObject::kPipette: return "pipette";
    case SceneObject::kGlassPipette: return "glass-pipette";
    case SceneObject::kCat: return "cat";
    case SceneObject::kAstronaut: return "astronaut";
    case SceneObject::kCup: return "cup";
    case SceneObject::kLarge: return "large";
  }
  return "?";
}
const char* name_of(SceneBackground v) noexcept {
  switch (v) {
    case SceneBackground::kGravel: return "gravel";
    case SceneBackground::kGrass: return "grass";
    case SceneBackground::kBrick: return "brick";
    case SceneBackground::kMoon: return "moon";
    case SceneBackground::kPage: return "page";
    case SceneBackground::kSmooth: return "smooth";
  }
  return "?";
}
const char* name_of(SceneMotion v) noexcept {
  switch (v) {
    case SceneMotion::kSmooth: return "smooth";
    case SceneMotion::kWalk: return "walk";
    case SceneMotion::kStopGo: return "stopgo";
    case SceneMotion::kSpin: return "spin";
    case SceneMotion::kSweep: return "sweep";
  }
  return "?";
}
const char* name_of(OcclusionSide v) noexcept {
  switch (v) {
    case OcclusionSide::kNone: return "none";
    case OcclusionSide::kCover: return "cover";
    case OcclusionSide::kLeft: return "left";
    case OcclusionSide::kRight: return "right";
    case OcclusionSide::kTop: return "top";
    case OcclusionSide::kBottom: return "bottom";
  }
  return "?";
}
const char* name_of(FocusStackKind v) noexcept { return v == FocusStackKind::kTilted ? "tilted" : "alike"; }

bool parse_scene_name(const std::string& s, SceneObject& out) {
  using O = SceneObject;
  return parse_from(s, out, std::array{O::kCog, O::kCoin, O::kHorse, O::kPipette, O::kCat, O::kAstronaut, O::kCup, O::kLarge, O::kGlassPipette});
}
bool parse_scene_name(const std::string& s, SceneBackground& out) {
  using B = SceneBackground;
  return parse_from(s, out, std::array{B::kGravel, B::kGrass, B::kBrick, B::kMoon, B::kPage, B::kSmooth});
}
bool parse_scene_name(const std::string& s, SceneMotion& out) {
  using M = SceneMotion;
  return parse_from(s, out, std::array{M::kSmooth, M::kWalk, M::kStopGo, M::kSpin, M::kSweep});
}
bool parse_scene_name(const std::string& s, OcclusionSide& out) {
  using S = OcclusionSide;
  return parse_from(s, out, std::array{S::kNone, S::kCover, S::kLeft, S::kRight, S::kTop, S::kBottom});
}
bool parse_scene_name(const std::string& s, FocusStackKind& out) {
  return parse_from(s, out, std::array{FocusStackKind::kTilted, FocusStackKind::kAlike});
}

void default_scene_size(SceneObject object, std::uint32_t& width, std::uint32_t& height) noexcept {
  switch (object) {
    case SceneObject::kLarge: width = 704, height = 528; return;
    case SceneObject::kPipette: width = 640, height = 480; return;
    case SceneObject::kGlassPipette: width = 640, height = 480; return;
    case SceneObject::kHorse: case SceneObject::kCup: width = 512, height = 384; return;
    default: width = 384, height = 288; return;
  }
}

std::string scene_name(const SceneOptions& o) {
  std::string s = std::string(name_of(o.object)) + "-" + name_of(o.background) + "-" + name_of(o.motion) + "-" +
                  name_of(o.occlusion_side) + "-d" + std::to_string(o.depths);
  if (o.depths > 1 && o.stack == FocusStackKind::kAlike) s += "alike";
  return s + "-s" + std::to_string(o.seed);
}

SceneOptions suite_scene(std::uint32_t index, std::uint32_t frames) {
  SceneOptions o;
  o.seed = index + 1;
  o.frames = frames;
  // Each object appears once per block of 8 scenes; from block to block it
  // gets another motion, background, occlusion side and stack.
  const std::uint32_t block = index / 8;
  o.object = static_cast<SceneObject>(index % 8);
  o.background = static_cast<SceneBackground>((index + 2 * block) % 6);
  o.motion = static_cast<SceneMotion>((index + block) % 5);
  o.occlusion_side = static_cast<OcclusionSide>(1 + (index + 3 * block) % 5);
  static constexpr std::uint16_t kDepths[3] = {1, 3, 5};
  o.depths = o.object == SceneObject::kLarge ? 1 : kDepths[(index + 2 * block) % 3];
  o.stack = o.depths > 1 && index % 5 == 2 ? FocusStackKind::kAlike : FocusStackKind::kTilted;
  o.occlusion_start = 40 + (index * 7) % 40;
  o.occlusion_frames = 12;
  o.width = o.height = 0;
  return o;
}

SceneOptions pipette_scene(std::uint32_t index, std::uint32_t frames) {
  SceneOptions o;
  o.seed = 1001 + index;
  o.frames = frames;
  o.object = SceneObject::kGlassPipette;
  o.width = o.height = 0;
  static constexpr SceneBackground kBackgrounds[4] = {SceneBackground::kGravel, SceneBackground::kGrass, SceneBackground::kPage,
                                                      SceneBackground::kMoon};
  static constexpr SceneMotion kMotions[4] = {SceneMotion::kSmooth, SceneMotion::kWalk, SceneMotion::kStopGo, SceneMotion::kSweep};
  // The held-out half pairs each background with another motion and side.
  o.background = kBackgrounds[index % 4];
  o.motion = kMotions[(index + index / 4) % 4];
  o.occlusion_side = static_cast<OcclusionSide>(1 + (index + 2 * (index / 4)) % 5);
  o.occlusion_start = 60 + (index * 13) % 60;
  o.occlusion_frames = 12;
  o.depths = 1;
  return o;
}

SceneSummary write_scene_sequence(const SceneOptions& options, const std::string& dir) {
  SceneOptions o = options;
  if (o.width == 0 && o.height == 0) default_scene_size(o.object, o.width, o.height);
  const ObjectImage object = make_object(o.object);
  const int patch = 2 * object.half + 1;
  if (o.frames < 1 || o.frames > 100000) throw app::Error("scene: frames must be in 1..100000");
  if (o.width < 3u * patch || o.height < 2u * patch + 20 || o.width > 4096 || o.height > 4096)
    throw app::Error("scene: the " + std::string(name_of(o.object)) + " needs a size of at least " + std::to_string(3 * patch) +
                     "x" + std::to_string(2 * patch + 20));
  if (o.depths < 1 || o.depths > 32) throw app::Error("scene: depths must be in 1..32");
  std::filesystem::create_directories(dir);

  const Plane brick = photo("brick");
  const Plane background = background_of(o.background, static_cast<int>(o.width), static_cast<int>(o.height));

  std::vector<Layer> stack, other_stack;
  ObjectImage other = object;
  other.grey = object.other_grey;
  // The look at frame f of an object that changes it: the two looks blended,
  // half and half at frame 0 (and in the model images).
  const auto look_at = [&](std::uint32_t f, std::size_t n) -> Layer {
    if (!object.changes_look) return stack[n];
    const double w = 0.5 + 0.5 * std::sin(2 * kPi * f / 90.0);
    Layer l = stack[n];
    for (std::size_t i = 0; i < l.premultiplied.v.size(); ++i)
      l.premultiplied.v[i] = (1 - w) * stack[n].premultiplied.v[i] + w * other_stack[n].premultiplied.v[i];
    return l;
  };
  const int model_side = patch + 16;
  for (int n = 0; n < o.depths; ++n) {
    stack.push_back(object_at_depth(object, n, o.depths, o.stack));
    if (object.changes_look) other_stack.push_back(object_at_depth(other, n, o.depths, o.stack));
    Plane model(model_side, model_side, 128.0);
    composite(model, look_at(0, static_cast<std::size_t>(n)), model_side / 2, model_side / 2, 0, 1.0);
    char name[32];
    std::snprintf(name, sizeof name, "model_%02d.pgm", n);
    write_plane_pgm((std::filesystem::path(dir) / name).string(), model);
  }

  // The trajectory, one pose per frame and one before the first (motion blur
  // interpolates between them).
  app::Rng rng(o.seed);
  const double margin = std::ceil(1.4143 * object.half) + 4;  // the rotated object stays inside the image
  const ScenePath smooth(o, margin, rng);
  const std::vector<Pose4> path = scene_path(o, margin, smooth, rng);
  const bool smooth_path = o.motion == SceneMotion::kSmooth || o.motion == SceneMotion::kSweep;
  const auto smooth_at = [&](double t) { return smooth.at(t); };

  // The occluder: a square of brick a little larger than the object; for a
  // side, it slides in over 8 frames, stays, and slides back out.
  const int occluder_side = patch + 12;
  const bool sliding = o.occlusion_side != OcclusionSide::kCover && o.occlusion_side != OcclusionSide::kNone;
  const std::uint32_t occlusion_span = o.occlusion_side == OcclusionSide::kNone ? 0 : o.occlusion_frames + (sliding ? 16 : 0);
  // Fraction of the occluder's travel [0, 1] at frame f (1: fully over the object).
  const auto occluder_cover = [&](std::uint32_t f) -> double {
    if (occlusion_span == 0 || f < o.occlusion_start || f >= o.occlusion_start + occlusion_span) return 0;
    if (!sliding) return 1;
    const double k = f - o.occlusion_start;
    if (k < 8) return (k + 1) / 9.0;
    if (k >= 8 + o.occlusion_frames) return (occlusion_span - k) / 9.0;
    return 1;
  };

  const std::filesystem::path out_dir(dir);
  app::Y4mWriter y4m((out_dir / "frames.y4m").string(), o.width, o.height);
  std::ostringstream gt;
  gt << "frame,x,y,theta_deg,depth,visible\n";
  SceneSummary summary;
  summary.object_radius = static_cast<std::uint32_t>(object.radius);
  summary.width = o.width;
  summary.height = o.height;
  for (std::uint32_t f = 0; f < o.frames; ++f) {
    const Pose4 p = path[f + 1];
    const Pose4 prev = path[f];
    const double gain = 1.0 + o.illumination * std::sin(2 * kPi * f / 300.0);
    Plane frame = background;
    for (double& v : frame.v) v *= gain;
    Plane cover(frame.w, frame.h);
    const Layer layer = look_at(f, static_cast<std::size_t>(p.depth));
    const bool blurred = o.blur_every > 0 && f > 0 && f % o.blur_every == 0;
    if (blurred) {
      // Motion blur: the object averaged over 7 instants of the last frame interval.
      Plane acc(frame.w, frame.h);
      for (int k = 0; k < 7; ++k) {
        Plane sub = frame;
        const double u = (k + 1) / 7.0;
        // The smooth paths are known between frames; the others are interpolated.
        const Pose4 q = smooth_path ? smooth_at(f - 1 + u)
                                    : Pose4{prev.x + u * (p.x - prev.x), prev.y + u * (p.y - prev.y), prev.theta + u * (p.theta - prev.theta), 0};
        composite(sub, layer, q.x, q.y, q.theta, gain, k == 6 ? &cover : nullptr);
        for (std::size_t i = 0; i < acc.v.size(); ++i) acc.v[i] += sub.v[i] / 7;
      }
      frame = acc;
    } else {
      composite(frame, layer, p.x, p.y, p.theta, gain, &cover);
    }
    double hidden = 0;
    if (const double travel = occluder_cover(f); travel > 0)
      hidden = paint_occluder(frame, cover, brick, p, travel, occluder_side, o.occlusion_side, gain);
    const bool visible = hidden <= 0.25;
    app::GrayImage out(o.width, o.height);
    for (std::size_t i = 0; i < out.pixels.size(); ++i) {
      // Box-Muller from the project's generator: the same noise on every machine.
      const double u1 = std::max(rng.next_unit(), 1e-12), u2 = rng.next_unit();
      const double n = o.noise_sigma * std::sqrt(-2 * std::log(u1)) * std::cos(2 * kPi * u2);
      out.pixels[i] = static_cast<std::uint8_t>(std::clamp(std::lround(frame.v[i] + n), 0L, 255L));
    }
    y4m.write(out);
    char row[128];
    std::snprintf(row, sizeof row, "%u,%.3f,%.3f,%.3f,%d,%d\n", f, p.x, p.y, p.theta, p.depth, visible ? 1 : 0);
    gt << row;
    summary.visible_frames += visible ? 1 : 0;
  }
  y4m.close();
  app::write_file((out_dir / "gt.csv").string(), gt.str());
  return summary;
}

}  // namespace gabarit::host
