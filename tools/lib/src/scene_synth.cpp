#include "gabarit/host/scene_synth.hpp"

#include <algorithm>
#include <sstream>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "gabarit/app/error.hpp"
#include "gabarit/app/files.hpp"
#include "gabarit/app/image_io.hpp"
#include "gabarit/host/rng.hpp"
#include "gabarit/host/thesis_shapes.hpp"

namespace gabarit::host {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kObjectRadius = 44;  // pixels, after the 2x downscale
constexpr int kHalf = kObjectRadius + 8;  // the object's square: room for its blurred outline
constexpr int kPatch = 2 * kHalf + 1;

// A float image, the working format before quantisation.
struct Plane {
  int w = 0, h = 0;
  std::vector<double> v;
  Plane(int width, int height, double fill = 0) : w(width), h(height), v(static_cast<std::size_t>(width) * height, fill) {}
  double& at(int x, int y) { return v[static_cast<std::size_t>(y) * w + x]; }
  double at(int x, int y) const { return v[static_cast<std::size_t>(y) * w + x]; }
  double bilinear(double x, double y) const {
    const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
    const double fx = x - x0, fy = y - y0;
    const auto px = [&](int xx, int yy) { return at(std::clamp(xx, 0, w - 1), std::clamp(yy, 0, h - 1)); };
    return (1 - fy) * ((1 - fx) * px(x0, y0) + fx * px(x0 + 1, y0)) + fy * ((1 - fx) * px(x0, y0 + 1) + fx * px(x0 + 1, y0 + 1));
  }
};

Plane from_photo(const app::GrayImage& g) {
  Plane p(static_cast<int>(g.width), static_cast<int>(g.height));
  for (std::size_t i = 0; i < p.v.size(); ++i) p.v[i] = g.pixels[i];
  return p;
}

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
      for (int i = -r; i <= r; ++i) a += k[static_cast<std::size_t>(i + r)] * in.at(std::clamp(x + i, 0, in.w - 1), y);
      tmp.at(x, y) = a;
    }
  for (int y = 0; y < in.h; ++y)
    for (int x = 0; x < in.w; ++x) {
      double a = 0;
      for (int i = -r; i <= r; ++i) a += k[static_cast<std::size_t>(i + r)] * tmp.at(x, std::clamp(y + i, 0, in.h - 1));
      out.at(x, y) = a;
    }
  return out;
}

// The object in its own frame: premultiplied grey (value * coverage) and its
// coverage (alpha), both kPatch square.
struct Layer {
  Plane premultiplied{kPatch, kPatch};
  Plane alpha{kPatch, kPatch};
};

// The object at depth n of `depths`: it is tilted, so the blur of each column
// of its texture grows with the column's distance from the column in focus,
// which sweeps across the object as n goes from 0 to depths - 1. (The outline
// stays sharp: blurring it too was tried and made every axis less accurate,
// the depth barely more; see docs/experiments.md.)
Layer object_at_depth(const Plane& grey, const Plane& alpha, int n, int depths) {
  constexpr int kLevels = 8;
  constexpr double kSigmaPerPx = 0.05;  // blur growth away from the focused column
  Layer out;
  out.alpha = alpha;
  if (depths <= 1) {
    for (std::size_t i = 0; i < grey.v.size(); ++i) out.premultiplied.v[i] = alpha.v[i] * grey.v[i];
    return out;
  }
  std::vector<Plane> levels;
  for (int l = 0; l < kLevels; ++l) levels.push_back(gaussian_blur(grey, 0.5 * l));
  const double focus = -kObjectRadius + 2.0 * kObjectRadius * n / (depths - 1);
  for (int y = 0; y < kPatch; ++y)
    for (int x = 0; x < kPatch; ++x) {
      const double sigma = kSigmaPerPx * std::abs((x - kHalf) - focus);
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

// The object's outline in its own frame: a five-lobed cog, so that its
// outline shows its orientation (a disk's would not).
double outline_radius(double ox, double oy) {
  const double phi = std::atan2(oy, ox);
  return kObjectRadius * (0.84 + 0.16 * std::cos(5 * phi));
}

// Draws `object` rotated by theta about its centre, centred at (x, y).
void composite(Plane& frame, const Layer& object, double x, double y, double theta_deg, double gain) {
  const double c = std::cos(theta_deg * kPi / 180), s = std::sin(theta_deg * kPi / 180);
  const int x0 = static_cast<int>(std::floor(x - kHalf - 2)), x1 = static_cast<int>(std::ceil(x + kHalf + 2));
  const int y0 = static_cast<int>(std::floor(y - kHalf - 2)), y1 = static_cast<int>(std::ceil(y + kHalf + 2));
  for (int py = std::max(0, y0); py <= std::min(frame.h - 1, y1); ++py)
    for (int px = std::max(0, x0); px <= std::min(frame.w - 1, x1); ++px) {
      const double dx = px - x, dy = py - y;
      // Inverse rotation: the object point that lands here.
      const double ox = c * dx + s * dy + kHalf, oy = -s * dx + c * dy + kHalf;
      if (ox < 0 || oy < 0 || ox > kPatch - 1 || oy > kPatch - 1) continue;
      const double alpha = object.alpha.bilinear(ox, oy);
      if (alpha <= 0) continue;
      frame.at(px, py) = (1 - alpha) * frame.at(px, py) + gain * object.premultiplied.bilinear(ox, oy);
    }
}

void write_plane_pgm(const std::string& path, const Plane& p) {
  app::GrayImage g(static_cast<std::uint32_t>(p.w), static_cast<std::uint32_t>(p.h));
  for (std::size_t i = 0; i < p.v.size(); ++i) g.pixels[i] = static_cast<std::uint8_t>(std::clamp(std::lround(p.v[i]), 0L, 255L));
  app::write_pgm(path, g);
}

}  // namespace

SceneSummary write_scene_sequence(const SceneOptions& o, const std::string& dir) {
  if (o.frames < 1 || o.frames > 100000) throw app::Error("scene: frames must be in 1..100000");
  if (o.width < 3 * kPatch || o.height < 2 * kPatch + 20 || o.width > 4096 || o.height > 4096)
    throw app::Error("scene: size must be at least " + std::to_string(3 * kPatch) + "x" + std::to_string(2 * kPatch + 20));
  if (o.depths < 1 || o.depths > 32) throw app::Error("scene: depths must be in 1..32");
  std::filesystem::create_directories(dir);

  // The photographs, converted at run time.
  const Plane camera = gaussian_blur(from_photo(app::read_pgm(debian_photo_pgm("camera"))), 0.0);
  Plane grey(kPatch, kPatch), alpha(kPatch, kPatch);
  for (int y = 0; y < kPatch; ++y)  // 2x box downscale of the square around the cameraman's head and camera
    for (int x = 0; x < kPatch; ++x) {
      const int sx = 134 + 2 * x, sy = 24 + 2 * y;
      grey.at(x, y) = 0.25 * (camera.at(sx, sy) + camera.at(sx + 1, sy) + camera.at(sx, sy + 1) + camera.at(sx + 1, sy + 1));
      alpha.at(x, y) = std::clamp(outline_radius(x - kHalf, y - kHalf) + 0.5 - std::hypot(x - kHalf, y - kHalf), 0.0, 1.0);
    }
  const Plane gravel = from_photo(app::read_pgm(debian_photo_pgm("gravel")));
  const Plane brick = from_photo(app::read_pgm(debian_photo_pgm("brick")));
  Plane background(static_cast<int>(o.width), static_cast<int>(o.height));
  for (int y = 0; y < background.h; ++y)
    for (int x = 0; x < background.w; ++x) background.at(x, y) = gravel.at(x % gravel.w, y % gravel.h);

  std::vector<Layer> stack;
  for (int n = 0; n < o.depths; ++n) {
    stack.push_back(object_at_depth(grey, alpha, n, o.depths));
    Plane model(kPatch + 16, kPatch + 16, 128.0);
    composite(model, stack.back(), (kPatch + 16) / 2, (kPatch + 16) / 2, 0, 1.0);
    char name[32];
    std::snprintf(name, sizeof name, "model_%02d.pgm", n);
    write_plane_pgm((std::filesystem::path(dir) / name).string(), model);
  }

  // The trajectory: slow sines with random phases, scaled to the speed limits.
  Rng rng(o.seed);
  const double px = 90 + 40 * rng.next_unit(), py = 70 + 40 * rng.next_unit(), pt = 120 + 60 * rng.next_unit();
  const double phx = 2 * kPi * rng.next_unit(), phy = 2 * kPi * rng.next_unit(), pht = 2 * kPi * rng.next_unit();
  const double ax = std::min(o.max_speed_px * px / (2 * kPi), o.width / 2.0 - kPatch);
  const double ay = std::min(o.max_speed_px * py / (2 * kPi), o.height / 2.0 - kPatch);
  const double at = o.max_turn_deg * pt / (2 * kPi);
  const auto pose_at = [&](double t) {
    Pose4 p;
    p.x = o.width / 2.0 + ax * std::sin(2 * kPi * t / px + phx);
    p.y = o.height / 2.0 + ay * std::sin(2 * kPi * t / py + phy);
    p.theta = at * std::sin(2 * kPi * t / pt + pht);
    // Depth: up and down the stack, one step every 20 frames.
    const int period = 2 * std::max(1, o.depths - 1);
    const int phase = static_cast<int>(t / 20) % period;
    p.depth = o.depths <= 1 ? 0 : (phase < o.depths ? phase : period - phase);
    return p;
  };

  app::Y4mWriter y4m((std::filesystem::path(dir) / "frames.y4m").string(), o.width, o.height);
  std::ostringstream gt;
  gt << "frame,x,y,theta_deg,depth,visible\n";
  SceneSummary summary;
  summary.object_radius = kObjectRadius;
  for (std::uint32_t f = 0; f < o.frames; ++f) {
    const Pose4 p = pose_at(f);
    const double gain = 1.0 + o.illumination * std::sin(2 * kPi * f / 300.0);
    Plane frame = background;
    for (double& v : frame.v) v *= gain;
    const bool blurred = o.blur_every > 0 && f > 0 && f % o.blur_every == 0;
    if (blurred) {
      // Motion blur: the object averaged over 7 instants of the last frame interval.
      Plane acc(frame.w, frame.h);
      for (int k = 0; k < 7; ++k) {
        Plane sub = frame;
        const Pose4 q = pose_at(f - 1 + (k + 1) / 7.0);
        composite(sub, stack[static_cast<std::size_t>(p.depth)], q.x, q.y, q.theta, gain);
        for (std::size_t i = 0; i < acc.v.size(); ++i) acc.v[i] += sub.v[i] / 7;
      }
      frame = acc;
    } else {
      composite(frame, stack[static_cast<std::size_t>(p.depth)], p.x, p.y, p.theta, gain);
    }
    const bool occluded = o.occlusion_frames > 0 && f >= o.occlusion_start && f < o.occlusion_start + o.occlusion_frames;
    if (occluded) {
      // A patch of another photograph covers the whole object.
      const int side = kPatch + 12;
      const int ox = static_cast<int>(std::lround(p.x)) - side / 2, oy = static_cast<int>(std::lround(p.y)) - side / 2;
      for (int y = 0; y < side; ++y)
        for (int x = 0; x < side; ++x)
          if (ox + x >= 0 && oy + y >= 0 && ox + x < frame.w && oy + y < frame.h)
            frame.at(ox + x, oy + y) = gain * brick.at((x + 200) % brick.w, (y + 100) % brick.h);
    }
    app::GrayImage out(o.width, o.height);
    for (std::size_t i = 0; i < out.pixels.size(); ++i) {
      // Box-Muller from the project's generator: the same noise on every machine.
      const double u1 = std::max(rng.next_unit(), 1e-12), u2 = rng.next_unit();
      const double n = o.noise_sigma * std::sqrt(-2 * std::log(u1)) * std::cos(2 * kPi * u2);
      out.pixels[i] = static_cast<std::uint8_t>(std::clamp(std::lround(frame.v[i] + n), 0L, 255L));
    }
    y4m.write(out);
    char row[128];
    std::snprintf(row, sizeof row, "%u,%.3f,%.3f,%.3f,%d,%d\n", f, p.x, p.y, p.theta, p.depth, occluded ? 0 : 1);
    gt << row;
    summary.visible_frames += occluded ? 0 : 1;
  }
  y4m.close();
  app::write_file((std::filesystem::path(dir) / "gt.csv").string(), gt.str());
  return summary;
}

}  // namespace gabarit::host
