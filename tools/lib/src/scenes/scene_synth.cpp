#include "gabarit/host/scenes/scene_synth.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <utility>

#include "gabarit/app/error.hpp"
#include "gabarit/app/files.hpp"
#include "gabarit/app/image_io.hpp"
#include "gabarit/app/rng.hpp"
#include "gabarit/host/scenes/thesis_shapes.hpp"
#include "scene_images.hpp"

namespace gabarit::host {
namespace {

using namespace scene;  // the images scenes are made of (scene_images.hpp)

struct Pose4 {
  double x, y, theta;
  int depth;
};

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
    const double rate = (rng.next_unit() < 0.5 ? -1.0 : 1.0) * 1.2 * o.max_turn_deg;
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

// The look-alike copy of the object at frame f: it orbits the target once
// every 200 frames (direction `turn`), its distance swinging between just
// clear of it (two radii and 6 px) and four radii every 70 frames, at the
// target's angle plus up to 25 deg. Where the orbit leaves the image, the
// offset is mirrored in x, y or both, and failing that drawn nearer (down
// to just clear of the target); where nothing fits, it is not drawn.
void paint_distractor(Plane& frame, const Layer& layer, const Pose4& target, std::uint32_t f, int radius, double phase, double turn,
                      double margin, double gain) {
  const double near = 2.0 * radius + 6, far = 4.0 * radius;
  const double orbit = near + (far - near) * (0.5 + 0.5 * std::cos(2 * kPi * f / 70.0));
  const double angle = phase + turn * 2 * kPi * f / 200.0;
  const double theta = target.theta + 25 * std::sin(2 * kPi * f / 110.0);
  for (double distance = orbit; distance >= near - 1e-9; distance -= 0.1 * (far - near)) {
    const double dx = distance * std::cos(angle), dy = distance * std::sin(angle);
    for (const auto& [sx, sy] : {std::pair{1, 1}, {-1, 1}, {1, -1}, {-1, -1}}) {
      const double x = target.x + sx * dx, y = target.y + sy * dy;
      if (x >= margin && y >= margin && x <= frame.w - margin && y <= frame.h - margin) {
        composite(frame, layer, x, y, theta, gain);
        return;
      }
    }
  }
}

// The frame quantised to 8 bits with Gaussian noise of `sigma` grey levels
// (Box-Muller from the project's generator: the same noise on every machine).
app::GrayImage with_sensor_noise(const Plane& frame, double sigma, app::Rng& rng) {
  app::GrayImage out(static_cast<std::uint32_t>(frame.w), static_cast<std::uint32_t>(frame.h));
  for (std::size_t i = 0; i < out.pixels.size(); ++i) {
    const double u1 = std::max(rng.next_unit(), 1e-12), u2 = rng.next_unit();
    const double n = sigma * std::sqrt(-2 * std::log(u1)) * std::cos(2 * kPi * u2);
    out.pixels[i] = static_cast<std::uint8_t>(std::clamp(std::lround(frame.v[i] + n), 0L, 255L));
  }
  return out;
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
    case SceneObject::kSmall: return "small";
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
const char* name_of(SceneFamily v) noexcept {
  switch (v) {
    case SceneFamily::kMixed: return "mixed";
    case SceneFamily::kSmallObject: return "small-object";
    case SceneFamily::kFastSpin: return "fast-spin";
    case SceneFamily::kDeepStack: return "deep-stack";
    case SceneFamily::kIllumination: return "illumination";
    case SceneFamily::kDistractor: return "distractor";
  }
  return "?";
}

bool parse_scene_name(const std::string& s, SceneObject& out) {
  using O = SceneObject;
  return parse_from(s, out, std::array{O::kCog, O::kCoin, O::kHorse, O::kPipette, O::kCat, O::kAstronaut, O::kCup, O::kLarge, O::kGlassPipette,
                                          O::kSmall});
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
    case SceneObject::kSmall: width = 640, height = 480; return;
    case SceneObject::kHorse: case SceneObject::kCup: width = 512, height = 384; return;
    default: width = 384, height = 288; return;
  }
}

std::string scene_name(const SceneOptions& o) {
  std::string s = std::string(name_of(o.object)) + "-" + name_of(o.background) + "-" + name_of(o.motion) + "-" +
                  name_of(o.occlusion_side) + "-d" + std::to_string(o.depths);
  if (o.depths > 1 && o.stack == FocusStackKind::kAlike) s += "alike";
  // What departs from the defaults every mixed scene shares.
  const SceneOptions defaults;
  char extra[64];
  if (o.noise_sigma != defaults.noise_sigma) std::snprintf(extra, sizeof extra, "-noise%g", o.noise_sigma), s += extra;
  if (o.max_turn_deg != defaults.max_turn_deg) std::snprintf(extra, sizeof extra, "-turn%g", o.max_turn_deg), s += extra;
  if (o.illumination != defaults.illumination || o.illumination_period != defaults.illumination_period)
    std::snprintf(extra, sizeof extra, "-light%g:%g", o.illumination, o.illumination_period), s += extra;
  if (o.distractor) s += "-twin";
  return s + "-s" + std::to_string(o.seed);
}

namespace {

// Scene `index` of a family (index >= kSuiteMixedScenes): the family's
// difficulty on a scene otherwise like the mixed ones; the two scenes of a
// family differ in object, background, motion and occlusion side.
SceneOptions family_scene(std::uint32_t index, std::uint32_t frames) {
  SceneOptions o;
  o.seed = index + 1;
  o.frames = frames;
  o.width = o.height = 0;
  const bool second = (index - kSuiteMixedScenes) % 2 == 1;
  o.occlusion_side = second ? OcclusionSide::kRight : OcclusionSide::kCover;
  o.occlusion_start = 50 + (index * 7) % 30;
  o.occlusion_frames = 12;
  o.background = second ? SceneBackground::kGrass : SceneBackground::kGravel;
  o.motion = second ? SceneMotion::kSmooth : SceneMotion::kWalk;
  switch (suite_family(index)) {
    case SceneFamily::kMixed:
    case SceneFamily::kSmallObject:
      o.object = SceneObject::kSmall;
      o.background = second ? SceneBackground::kPage : SceneBackground::kGravel;
      break;
    case SceneFamily::kFastSpin:
      o.object = second ? SceneObject::kCat : SceneObject::kCog;
      o.motion = SceneMotion::kSpin;
      o.max_turn_deg = 1.2;  // 1.44 deg/frame
      o.noise_sigma = 12;
      break;
    case SceneFamily::kDeepStack:
      o.object = second ? SceneObject::kCog : SceneObject::kCoin;
      o.depths = 7;
      o.motion = second ? SceneMotion::kSweep : SceneMotion::kSmooth;
      break;
    case SceneFamily::kIllumination:
      o.object = second ? SceneObject::kHorse : SceneObject::kAstronaut;
      o.illumination = 0.5;
      o.illumination_period = 60;
      o.background = second ? SceneBackground::kMoon : SceneBackground::kBrick;
      break;
    case SceneFamily::kDistractor:
      o.object = second ? SceneObject::kAstronaut : SceneObject::kCog;
      o.distractor = true;
      o.motion = second ? SceneMotion::kStopGo : SceneMotion::kSmooth;
      o.width = 512, o.height = 384;  // room for the two
      break;
  }
  return o;
}

}  // namespace

SceneOptions suite_scene(std::uint32_t index, std::uint32_t frames) {
  if (index >= kSuiteMixedScenes) return family_scene(index, frames);
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
  if (!(o.illumination_period >= 1) || !(o.illumination >= 0 && o.illumination < 1))
    throw app::Error("scene: the illumination's swing must be in [0, 1) and its period at least 1 frame");
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
  // The look-alike's orbit: its phase and direction, drawn only when there is one.
  const double orbit_phase = o.distractor ? 2 * kPi * rng.next_unit() : 0;
  const double orbit_turn = o.distractor && rng.next_unit() < 0.5 ? -1.0 : 1.0;

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
    const double gain = 1.0 + o.illumination * std::sin(2 * kPi * f / o.illumination_period);
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
    if (o.distractor) paint_distractor(frame, layer, p, f, object.radius, orbit_phase, orbit_turn, margin, gain);
    double hidden = 0;
    if (const double travel = occluder_cover(f); travel > 0)
      hidden = paint_occluder(frame, cover, brick, p, travel, occluder_side, o.occlusion_side, gain);
    const bool visible = hidden <= 0.25;
    y4m.write(with_sensor_noise(frame, o.noise_sigma, rng));
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
