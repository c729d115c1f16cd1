#include "gabarit/host/scenes/synth.hpp"

#include <algorithm>
#include <sstream>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include "gabarit/deterministic_math.hpp"
#include "gabarit/app/error.hpp"
#include "gabarit/app/files.hpp"
#include "gabarit/app/rng.hpp"

namespace gabarit::host {
namespace {

std::vector<Point> trace_curve(double base_radius, const double (&amp)[4], const double (&phase)[4]) {
  std::vector<Point> out;
  std::set<Point> seen;
  const int samples = std::max(720, static_cast<int>(base_radius * 40));
  for (int i = 0; i < samples; ++i) {
    const float deg = 360.0f * static_cast<float>(i) / static_cast<float>(samples);
    double r = base_radius;
    for (int k = 0; k < 4; ++k) r += base_radius * amp[k] * sin_cos_deg(deg * static_cast<float>(k + 2) + static_cast<float>(phase[k])).cos;
    const SinCos sc = sin_cos_deg(deg);
    const Point p{round_to_int(static_cast<float>(r * sc.cos)), round_to_int(static_cast<float>(r * sc.sin))};
    if (seen.insert(p).second) out.push_back(p);
  }
  return out;
}

}  // namespace

std::vector<Point> random_closed_curve(std::size_t target_points, std::uint64_t seed) {
  if (target_points < 8 || target_points > 20000) throw app::Error("random shape: point count must be in 8..20000");
  app::Rng rng(seed);
  double amp[4], phase[4];
  for (int k = 0; k < 4; ++k) {
    amp[k] = rng.next_unit() * 0.12 / (k + 1);
    phase[k] = rng.next_unit() * 360.0;
  }
  // A digital circle of radius r has about 5.66 r pixels (8-connected); adjust
  // the radius a few times to land near the target count.
  double radius = static_cast<double>(target_points) / 5.66;
  std::vector<Point> curve;
  for (int iter = 0; iter < 6; ++iter) {
    curve = trace_curve(radius, amp, phase);
    radius *= static_cast<double>(target_points) / static_cast<double>(curve.size());
  }
  return curve;
}

void fit_image_to_shape(SynthOptions& o) {
  std::int32_t extent_x = 0, extent_y = 0;
  for (const Point& p : o.shape) {
    extent_x = std::max(extent_x, std::abs(p.x));
    extent_y = std::max(extent_y, std::abs(p.y));
  }
  const std::int32_t room = std::max(16, 4 * o.max_step);
  o.width = std::max<std::uint32_t>(256, static_cast<std::uint32_t>(2 * (extent_x + room) + 1));
  o.height = std::max<std::uint32_t>(256, static_cast<std::uint32_t>(2 * (extent_y + room) + 1));
}

app::GrayImage render_frame(const SynthOptions& o, std::int32_t x, std::int32_t y, std::uint64_t frame_seed) {
  app::GrayImage image(o.width, o.height, 0);
  for (const Point& p : o.shape) {
    const std::int64_t px = std::int64_t{x} + p.x, py = std::int64_t{y} + p.y;
    if (px >= 0 && py >= 0 && px < o.width && py < o.height) image.at(static_cast<std::uint32_t>(px), static_cast<std::uint32_t>(py)) = 255;
  }
  if (o.noise > 0) {
    app::Rng rng(frame_seed);
    const auto threshold = static_cast<std::uint64_t>(o.noise * 4294967296.0);
    for (auto& v : image.pixels) {
      if (rng.next_u32() < threshold) v = static_cast<std::uint8_t>(255 - v);
    }
  }
  return image;
}

std::vector<TruthRow> synthetic_trajectory(const SynthOptions& o) {
  if (o.shape.empty()) throw app::Error("synth: empty shape");
  if (o.frames == 0 || o.frames > 1000000) throw app::Error("synth: --frames must be in 1..1000000");
  if (o.max_step < 0 || o.max_step > 1000) throw app::Error("synth: --max-step must be in 0..1000");
  if (!(o.noise >= 0.0 && o.noise <= 1.0)) throw app::Error("synth: --noise must be in [0, 1]");
  std::int32_t min_x = INT32_MAX, min_y = INT32_MAX, max_x = INT32_MIN, max_y = INT32_MIN;
  for (const Point& p : o.shape) {
    min_x = std::min(min_x, p.x); max_x = std::max(max_x, p.x);
    min_y = std::min(min_y, p.y); max_y = std::max(max_y, p.y);
  }
  // Positions keep the whole shape inside the image.
  const std::int64_t lo_x = -std::int64_t{min_x}, hi_x = std::int64_t{o.width} - 1 - max_x;
  const std::int64_t lo_y = -std::int64_t{min_y}, hi_y = std::int64_t{o.height} - 1 - max_y;
  if (lo_x > hi_x || lo_y > hi_y) throw app::Error("synth: the shape does not fit in a " + std::to_string(o.width) + "x" + std::to_string(o.height) + " image");

  app::Rng motion(o.seed);
  std::int32_t x = static_cast<std::int32_t>(std::clamp<std::int64_t>(o.width / 2, lo_x, hi_x));
  std::int32_t y = static_cast<std::int32_t>(std::clamp<std::int64_t>(o.height / 2, lo_y, hi_y));
  std::vector<TruthRow> truth;
  std::int32_t vx = 0, vy = 0;  // velocity_walk's
  for (std::uint32_t f = 0; f < o.frames; ++f) {
    if (f > 0 && o.velocity_walk) {
      // The velocity takes a step of -1, 0 or +1 px per axis, within
      // +-max_step, and reverses where the shape would leave the image.
      vx = std::clamp(vx + motion.uniform_int(-1, 1), -o.max_step, o.max_step);
      vy = std::clamp(vy + motion.uniform_int(-1, 1), -o.max_step, o.max_step);
      if (x + vx < lo_x || x + vx > hi_x) vx = -vx;
      if (y + vy < lo_y || y + vy > hi_y) vy = -vy;
      x = static_cast<std::int32_t>(std::clamp<std::int64_t>(x + vx, lo_x, hi_x));
      y = static_cast<std::int32_t>(std::clamp<std::int64_t>(y + vy, lo_y, hi_y));
    } else if (f > 0) {
      // Redraw a step that leaves the image (bounded tries), then clamp.
      std::int32_t nx = x, ny = y;
      for (int attempt = 0; attempt < 64; ++attempt) {
        nx = x + motion.uniform_int(-o.max_step, o.max_step);
        ny = y + motion.uniform_int(-o.max_step, o.max_step);
        if (nx >= lo_x && nx <= hi_x && ny >= lo_y && ny <= hi_y) break;
      }
      x = static_cast<std::int32_t>(std::clamp<std::int64_t>(nx, lo_x, hi_x));
      y = static_cast<std::int32_t>(std::clamp<std::int64_t>(ny, lo_y, hi_y));
    }
    truth.push_back({f, x, y});
  }
  return truth;
}

std::uint64_t synthetic_frame_seed(const SynthOptions& o, std::uint32_t frame) {
  return o.seed ^ (0xA5A5A5A5ull + 0x100000001B3ull * (frame + 1));
}

std::vector<TruthRow> write_synthetic_sequence(const SynthOptions& o, const std::string& dir) {
  const std::vector<TruthRow> truth = synthetic_trajectory(o);
  std::int32_t min_x = INT32_MAX, min_y = INT32_MAX, max_x = INT32_MIN, max_y = INT32_MIN;
  for (const Point& p : o.shape) {
    min_x = std::min(min_x, p.x); max_x = std::max(max_x, p.x);
    min_y = std::min(min_y, p.y); max_y = std::max(max_y, p.y);
  }
  std::filesystem::create_directories(dir);
  app::Y4mWriter video(dir + "/frames.y4m", o.width, o.height);
  std::ostringstream gt;
  gt << "frame,x,y,theta_deg,depth,visible\n";
  for (const TruthRow& t : truth) {
    video.write(render_frame(o, t.x, t.y, synthetic_frame_seed(o, t.frame)));
    gt << t.frame << ',' << t.x << ',' << t.y << ",0,0,1\n";
  }
  video.close();
  app::write_file(dir + "/gt.csv", gt.str());

  write_points_csv(dir + "/model.csv", o.shape);
  const std::int32_t radius = std::max({-min_x, max_x, -min_y, max_y}) + 2;
  const auto side = static_cast<std::uint32_t>(2 * radius + 1);
  app::GrayImage model(side, side, 0);
  for (const Point& p : o.shape) model.at(static_cast<std::uint32_t>(radius + p.x), static_cast<std::uint32_t>(radius + p.y)) = 255;
  app::write_pgm(dir + "/model.pgm", model);
  return truth;
}

}  // namespace gabarit::host
