// Grayscale test sequences for 4-DOF tracking (the microscope case of the
// thesis, section 6.1), built from real photographs of Debian's
// python3-skimage at run time, never committed. A scene is
//   - an object cut from a photograph (SceneObject): asymmetric, near
//     symmetric (a coin), elongated and self-similar (a pipette), small
//     (~40 px) or large (~200 px);
//   - over a background (SceneBackground): a cluttered real texture, tiled;
//   - moving along a trajectory (SceneMotion) in x, y and theta, and through
//     a focus stack (SceneOptions::depths);
//   - with a slow illumination change (gain), Gaussian sensor noise, motion
//     blur on a few frames, and an occlusion (OcclusionSide) by a patch of
//     another photograph (`brick.png`) that covers the object at once or
//     slides in from one side and out again;
//   - a focus stack (FocusStackKind): the object *tilted*, so at depth n its
//     blur grows with the distance of each column from the column in focus,
//     which moves across the object with n (no two depths alike); or blurred
//     evenly, with two neighbouring depths almost alike.
// Outputs frames.y4m, gt.csv (frame,x,y,theta_deg,depth,visible: visible is 0
// while more than a quarter of the object is hidden) and the model stack
// model_NN.pgm (the object at theta 0 on mid-grey, one per depth, the
// reference point at the image centre). Same options, same bytes.
//
// The scene suite (suite_scene) is a fixed list of such scenes, mixing every
// object, background, motion and occlusion side; half its scenes are for
// tuning and the other half held out (suite_held_out), each half holding every
// object twice. docs/scene-suite.md describes it.
#pragma once

#include <cstdint>
#include <string>

namespace gabarit::host {

enum class SceneObject : std::uint8_t {
  kCog,        // a five-lobed cog cut from camera.png (the default, asymmetric)
  kCoin,       // one coin of coins.png, ~42 px across: near-circular outline, relief inside
  kHorse,      // the silhouette of horse.png filled with moon.png's texture (asymmetric)
  kPipette,    // a tapered glass tube ~180 px long: elongated and self-similar
  kCat,        // chelsea.png's head in an ellipse
  kAstronaut,  // astronaut.png's helmet and face in a disk, ~60 px
  kCup,        // coffee.png's cup and saucer in an ellipse
  kLarge,      // camera.png at full scale in a rounded square ~200 px wide
  // A glass micro-pipette (thesis 6.4), 180 px long: transparent (the
  // background shows through it), a closed tapered tip, a wall whose
  // contrast swings from strong to weak with the illumination (a period of
  // 90 frames), every cross-section alike. Not in the 32-scene suite: the
  // pipette scenes (pipette_scene) are its own.
  kGlassPipette,
  // A small cut of camera.png in a 36x32 ellipse (~280 edge points), its
  // default frame a wide 640x480: the suite's small-object family.
  kSmall,
};
enum class SceneBackground : std::uint8_t { kGravel, kGrass, kBrick, kMoon, kPage, kSmooth };
enum class SceneMotion : std::uint8_t {
  kSmooth,  // slow sines in x, y and theta
  kWalk,    // a velocity random walk that reverses at the image margins
  kStopGo,  // the smooth path travelled in bursts: stops, then up to 1.6x the speed
  kSpin,    // a fast steady rotation (~1.2 deg/frame) and a slow drift
  kSweep,   // the smooth path, slower, with the depth stepping every 6 frames
};
enum class OcclusionSide : std::uint8_t { kNone, kCover, kLeft, kRight, kTop, kBottom };
enum class FocusStackKind : std::uint8_t { kTilted, kAlike };

const char* name_of(SceneObject v) noexcept;
const char* name_of(SceneBackground v) noexcept;
const char* name_of(SceneMotion v) noexcept;
const char* name_of(OcclusionSide v) noexcept;
const char* name_of(FocusStackKind v) noexcept;
// Parse a name (as name_of prints it); false if it names nothing.
bool parse_scene_name(const std::string& s, SceneObject& out);
bool parse_scene_name(const std::string& s, SceneBackground& out);
bool parse_scene_name(const std::string& s, SceneMotion& out);
bool parse_scene_name(const std::string& s, OcclusionSide& out);
bool parse_scene_name(const std::string& s, FocusStackKind& out);

struct SceneOptions {
  std::uint32_t frames = 240;
  std::uint32_t width = 384;   // 0 (with height 0): the object's own default size
  std::uint32_t height = 288;
  std::uint16_t depths = 1;              // focus-stack images (1: no depth change)
  SceneObject object = SceneObject::kCog;
  SceneBackground background = SceneBackground::kGravel;
  SceneMotion motion = SceneMotion::kSmooth;
  OcclusionSide occlusion_side = OcclusionSide::kCover;
  FocusStackKind stack = FocusStackKind::kTilted;
  double max_speed_px = 2.5;             // largest per-frame translation of the trajectory
  double max_turn_deg = 1.0;             // largest per-frame rotation (kSpin: its steady rate is 1.2 times this)
  double noise_sigma = 3.0;              // grey levels
  double illumination = 0.2;             // gain swings between 1 - this and 1 + this
  double illumination_period = 300;      // frames per swing of the gain
  // A look-alike: a second copy of the object (same look, same depth) on
  // its own orbit around it, from just clear of it to four radii away, at
  // another angle. Not in gt.csv; the tracker must not follow it.
  bool distractor = false;
  std::uint32_t occlusion_start = 100;   // first occluded frame (0 frames: none)
  std::uint32_t occlusion_frames = 18;   // frames fully covered (a sliding occluder also takes 8 to enter and 8 to leave)
  std::uint32_t blur_every = 50;         // a motion-blurred frame every N frames (0: none)
  std::uint64_t seed = 1;
};

struct SceneSummary {
  std::uint32_t object_radius = 0;
  std::uint32_t visible_frames = 0;
  std::uint32_t width = 0, height = 0;
};

// The image size an object needs (its default when width and height are 0).
void default_scene_size(SceneObject object, std::uint32_t& width, std::uint32_t& height) noexcept;

SceneSummary write_scene_sequence(const SceneOptions& options, const std::string& dir);

// The scene suite: scene `index` (0-based; the suite proper is
// 0..kSuiteScenes-1), seed index + 1. Scenes 0..31 mix every object,
// background, motion and occlusion side; from 32 on come the families
// (SceneFamily), two scenes each, the first for tuning, the second held out.
inline constexpr std::uint32_t kSuiteMixedScenes = 32;
enum class SceneFamily : std::uint8_t {
  kMixed,         // scenes 0..31
  kSmallObject,   // the small object (kSmall) in a wide 640x480 textured frame
  kFastSpin,      // spinning at 1.44 deg/frame (the tables' bound is 1.5) in noise of sigma 12
  kDeepStack,     // a tilted 7-depth focus stack: neighbouring depths differ little
  kIllumination,  // the gain swinging +-50% every 60 frames
  kDistractor,    // a look-alike copy of the object orbiting close by
};
inline constexpr std::uint32_t kSceneFamilies = 5;  // the families after kMixed
inline constexpr std::uint32_t kSuiteScenes = kSuiteMixedScenes + 2 * kSceneFamilies;
const char* name_of(SceneFamily v) noexcept;
constexpr SceneFamily suite_family(std::uint32_t index) noexcept {
  return index < kSuiteMixedScenes ? SceneFamily::kMixed
                                   : static_cast<SceneFamily>(1 + (index - kSuiteMixedScenes) / 2 % kSceneFamilies);
}
SceneOptions suite_scene(std::uint32_t index, std::uint32_t frames = 160);
// Held-out scenes (never used for tuning): 8..15 and 24..31 of the mixed
// scenes, and the second scene of each family (33, 35, ...).
constexpr bool suite_held_out(std::uint32_t index) noexcept {
  return index < kSuiteMixedScenes ? (index / 8) % 2 == 1 : (index - kSuiteMixedScenes) % 2 == 1;
}
// The pipette scenes (gabarit bench --pipette, thesis 6.4): the glass
// pipette over cluttered backgrounds, each motion and occlusion side, blur
// and the illumination swing; scenes 0..3 for tuning, 4..7 held out.
inline constexpr std::uint32_t kPipetteScenes = 8;
SceneOptions pipette_scene(std::uint32_t index, std::uint32_t frames = 200);
constexpr bool pipette_held_out(std::uint32_t index) noexcept { return index >= 4; }
// "cog-gravel-smooth-cover-d5-s1": the scene's name in reports.
std::string scene_name(const SceneOptions& options);

}  // namespace gabarit::host
