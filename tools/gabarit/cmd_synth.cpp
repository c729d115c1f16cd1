// gabarit synth
#include <cstdio>
#include <filesystem>

#include "gabarit/app/args.hpp"
#include "gabarit/app/files.hpp"
#include "commands.hpp"
#include "gabarit/host/scenes/scene_synth.hpp"
#include "gabarit/host/scenes/synth.hpp"
#include "gabarit/host/scenes/thesis_shapes.hpp"

namespace gabarit::cli {
namespace {

template <typename E>
E scene_choice(const app::Args& args, const char* option, E fallback, const char* choices) {
  if (!args.has(option)) return fallback;
  E out = fallback;
  if (!host::parse_scene_name(args.get(option), out))
    throw app::UsageError(std::string(option) + " '" + args.get(option) + "': want " + choices);
  return out;
}

constexpr const char* kObjects = "microscope, cog, coin, horse, pipette, cat, astronaut, cup, large, glass-pipette or small";

int synth_scene(const app::Args& args) {
  for (const char* shape_only : {"--points", "--max-step", "--noise"})
    if (args.has(shape_only)) throw app::UsageError(std::string(shape_only) + " applies to --shape");
  host::SceneOptions o;
  const std::string object = args.get("--scene");
  if (object != "microscope" && !host::parse_scene_name(object, o.object))
    throw app::UsageError("--scene '" + object + "': want " + std::string(kObjects));
  if (object != "microscope" && object != "cog") o.width = o.height = 0;  // the object's own size
  o.background = scene_choice(args, "--background", o.background, "gravel, grass, brick, moon, page or smooth");
  o.motion = scene_choice(args, "--motion", o.motion, "smooth, walk, stopgo, spin or sweep");
  o.occlusion_side = scene_choice(args, "--occlusion-side", o.occlusion_side, "none, cover, left, right, top or bottom");
  o.stack = scene_choice(args, "--stack", o.stack, "tilted or alike");
  o.seed = static_cast<std::uint64_t>(args.integer("--seed", 1, 0, INT64_MAX));
  o.frames = static_cast<std::uint32_t>(args.integer("--frames", o.frames, 1, 100000));
  o.depths = static_cast<std::uint16_t>(args.integer("--depths", 1, 1, 32));
  if (args.has("--clean")) {
    for (const char* option : {"--sensor-noise", "--light"})
      if (args.has(option)) throw app::UsageError(std::string(option) + " and --clean contradict each other");
    o.noise_sigma = 0.0, o.illumination = 0.0, o.blur_every = 0;
  }
  o.noise_sigma = args.number("--sensor-noise", o.noise_sigma, 0.0, 100.0);
  o.max_turn_deg = args.number("--max-turn", o.max_turn_deg, 0.0, 10.0);
  o.distractor = args.has("--distractor");
  if (args.has("--light")) {
    double swing = 0, period = o.illumination_period;
    char tail = 0;
    const int n = std::sscanf(args.get("--light").c_str(), "%lf:%lf%c", &swing, &period, &tail);
    if ((n != 1 && n != 2) || !(swing >= 0 && swing < 1) || !(period >= 1 && period <= 1e6))
      throw app::UsageError("--light '" + args.get("--light") + "': want SWING[:PERIOD], SWING in [0, 1), PERIOD >= 1 frame");
    o.illumination = swing;
    o.illumination_period = period;
  }
  if (args.has("--occlusion")) {
    unsigned start = 0, count = 0;
    char tail = 0;
    if (std::sscanf(args.get("--occlusion").c_str(), "%u:%u%c", &start, &count, &tail) != 2)
      throw app::UsageError("--occlusion '" + args.get("--occlusion") + "': want START:FRAMES");
    o.occlusion_start = start;
    o.occlusion_frames = count;
  }
  if (args.has("--size")) {
    const app::FrameSize size = app::parse_size(args.get("--size"), "--size", 8, 8192);
    o.width = size.width;
    o.height = size.height;
  }
  const auto summary = host::write_scene_sequence(o, args.get("-o"));
  std::fprintf(stderr, "%s: %s, %u frames %ux%u (%u visible), object radius %u px, %u depths, seed %llu\n", args.get("-o").c_str(),
               host::scene_name(o).c_str(), o.frames, summary.width, summary.height, summary.visible_frames, summary.object_radius,
               o.depths, static_cast<unsigned long long>(o.seed));
  return 0;
}

// The scene suite (or the pipette scenes): DIR/NN/ per scene and
// DIR/suite.csv listing them.
int synth_suite(const app::Args& args, bool pipette) {
  const char* option = pipette ? "--pipette-suite" : "--suite";
  for (const char* other : {"--points", "--max-step", "--noise", "--depths", "--occlusion", "--size", "--seed", "--background",
                            "--motion", "--occlusion-side", "--stack", "--clean"})
    if (args.has(other)) throw app::UsageError(std::string(other) + " does not apply to " + option + " (its scenes are fixed)");
  const std::uint32_t all = pipette ? host::kPipetteScenes : host::kSuiteScenes;
  const auto count = static_cast<std::uint32_t>(args.integer("--scenes", all, 1, pipette ? all : 1000));
  const auto frames = static_cast<std::uint32_t>(args.integer("--frames", pipette ? 200 : 160, 1, 100000));
  const std::filesystem::path dir(args.get("-o"));
  std::string listing = "index,name,half,object,background,motion,occlusion_side,depths,stack,seed,frames,visible,width,height,family\n";
  for (std::uint32_t i = 0; i < count; ++i) {
    const host::SceneOptions o = pipette ? host::pipette_scene(i, frames) : host::suite_scene(i, frames);
    const bool held_out = pipette ? host::pipette_held_out(i) : host::suite_held_out(i);
    char sub[16];
    std::snprintf(sub, sizeof sub, "%02u", i);
    const host::SceneSummary s = host::write_scene_sequence(o, (dir / sub).string());
    listing += std::to_string(i) + "," + host::scene_name(o) + "," + (held_out ? "held-out" : "tuning") + "," +
               host::name_of(o.object) + "," + host::name_of(o.background) + "," + host::name_of(o.motion) + "," +
               host::name_of(o.occlusion_side) + "," + std::to_string(o.depths) + "," + host::name_of(o.stack) + "," +
               std::to_string(o.seed) + "," + std::to_string(o.frames) + "," + std::to_string(s.visible_frames) + "," +
               std::to_string(s.width) + "," + std::to_string(s.height) + "," +
               (pipette ? "pipette" : host::name_of(host::suite_family(i))) + "\n";
    std::fprintf(stderr, "\r%s: scene %u/%u %-40s", dir.c_str(), i + 1, count, host::scene_name(o).c_str());
  }
  app::write_file((dir / "suite.csv").string(), listing);
  std::fprintf(stderr, "\n%s: %u scenes, listed in suite.csv\n", dir.c_str(), count);
  return 0;
}

}  // namespace

int synth(const std::vector<std::string>& argv) {
  app::Args args("synth", "(--shape SRC --frames N --max-step PX --noise P | --scene OBJECT [--depths N] | --suite | --pipette-suite) --seed S -o DIR",
            "--shape: a synthetic sequence of the thesis (section 6.2): a point shape translated over an empty\n"
            "image by a random displacement within +-PX per axis and frame, with salt-and-pepper noise of rate P.\n"
            "Outputs DIR/frames.y4m (Cmono), DIR/gt.csv (frame,x,y,theta_deg,depth,visible), DIR/model.csv\n"
            "and DIR/model.pgm.\n"
            "--scene microscope: a grayscale 4-DOF sequence from real photographs (python3-skimage): an object\n"
            "moving smoothly in x, y, theta (and through a focus stack with --depths) over a cluttered\n"
            "background, with an illumination change, sensor noise, motion-blurred frames and an occlusion.\n"
            "Outputs DIR/frames.y4m, DIR/gt.csv and the model stack DIR/model_NN.pgm. Deterministic per seed.\n"
            "--scene OBJECT: the same with another object, background, motion and occlusion (docs/scene-suite.md).\n"
            "--suite: the scene suite, DIR/00 .. DIR/41 (half for tuning, half held out) and DIR/suite.csv.\n"
            "--pipette-suite: the 8 glass-pipette scenes of gabarit bench --pipette (docs/particle-filter.md).",
            {{"--shape", "SRC", "random | curve (thesis ~194 points) | watch (~2800 edge points of a Debian\n"
              "                          photograph) | photo:FILE.pgm | points CSV (x,y relative to the reference)"},
             {"--scene", "OBJECT", "the grayscale 4-DOF scene instead of a point shape: microscope (the cog over\n"
              "                          gravel), cog, coin, horse, pipette, cat, astronaut, cup, large, glass-pipette,\n"
              "                          small (36x32 px in a 640x480 frame)"},
             {"--background", "NAME", "--scene: gravel (default), grass, brick, moon, page, smooth"},
             {"--motion", "NAME", "--scene: smooth (default), walk (velocity random walk, reversing at the margins),\n"
              "                          stopgo, spin (~1.2 deg/frame), sweep (depth steps every 6 frames);\n"
              "                          --shape: steps (default: independent steps of +-PX) or walk (a velocity\n"
              "                          random walk within +-PX that reverses at the margins)"},
             {"--occlusion-side", "SIDE", "--scene: cover (default: all at once), left, right, top, bottom (sliding in), none"},
             {"--stack", "KIND", "--scene: tilted (default: no two depths alike) or alike (two middle depths nearly equal)"},
             {"--clean", "", "--scene: no sensor noise, illumination change or motion blur (sub-pixel accuracy checks)"},
             {"--sensor-noise", "SIGMA", "--scene: Gaussian sensor noise in grey levels (default 3)"},
             {"--light", "SWING[:PERIOD]", "--scene: the gain swings within 1 +- SWING every PERIOD frames (default 0.2:300)"},
             {"--max-turn", "DEG", "--scene: largest turn per frame (default 1; spin turns 1.2 times this)"},
             {"--distractor", "", "--scene: a look-alike copy of the object orbiting close by (not in gt.csv)"},
             {"--suite", "", "the scene suite (fixed scenes; --frames and --scenes apply)"},
             {"--pipette-suite", "", "the glass-pipette scenes (fixed; 0-3 tuning, 4-7 held out; --frames, default 200,\n"
              "                          and --scenes apply)"},
             {"--scenes", "N", "--suite: the first N scenes (default 42)"},
             {"--depths", "N", "--scene: focus-stack depths of the tilted object, 1..32 (default 1)"},
             {"--occlusion", "START:FRAMES", "--scene: frames hidden behind another photograph (default 100:18; 0:0 none)"},
             {"--points", "N", "approximate point count for random (default 194) and photo: (default 2800)"},
             {"--frames", "N", "frame count (default 100; --scene: 240; --suite: 160; --pipette-suite: 200)"},
             {"--max-step", "PX", "largest displacement per axis and frame (default 4)"},
             {"--noise", "P", "salt-and-pepper rate in [0,1] (default 0)"},
             {"--seed", "S", "seed (default 1)"},
             {"--size", "WxH", "image size (default: 256x256, larger if the shape needs it)"},
             {"-o", "DIR", "output directory", false, true}});
  if (!args.parse(argv)) return 0;
  if (int{args.has("--scene")} + int{args.has("--shape")} + int{args.has("--suite")} + int{args.has("--pipette-suite")} != 1)
    throw app::UsageError("give one of --shape, --scene, --suite and --pipette-suite");
  if (args.has("--scenes") && !args.has("--suite") && !args.has("--pipette-suite"))
    throw app::UsageError("--scenes applies to --suite and --pipette-suite");
  if (args.has("--suite") || args.has("--pipette-suite")) return synth_suite(args, args.has("--pipette-suite"));
  if (args.has("--scene")) return synth_scene(args);
  for (const char* scene_only : {"--depths", "--occlusion", "--background", "--occlusion-side", "--stack", "--clean", "--sensor-noise",
                                  "--light", "--max-turn", "--distractor"})
    if (args.has(scene_only)) throw app::UsageError(std::string(scene_only) + " applies to --scene");
  host::SynthOptions o;
  o.seed = static_cast<std::uint64_t>(args.integer("--seed", 1, 0, INT64_MAX));
  const std::string shape = args.get("--shape");
  if (shape != "random" && shape != "curve" && shape != "watch") {  // a file: never one of the outputs
    const std::string input = shape.rfind("photo:", 0) == 0 ? shape.substr(6) : shape;
    for (const char* name : {"frames.y4m", "gt.csv", "model.csv", "model.pgm"})
      app::refuse_same_file(args.get("-o") + "/" + name, "-o", {input});
  }
  const bool counted = shape == "random" || shape.rfind("photo:", 0) == 0;
  if (args.has("--points") && !counted) throw app::UsageError("--points applies to --shape random and photo:");
  o.shape = host::resolve_shape(shape, static_cast<std::size_t>(args.integer("--points", shape == "random" ? 194 : 2800, 8, 20000)),
                                o.seed);
  o.frames = static_cast<std::uint32_t>(args.integer("--frames", 100, 1, 1000000));
  o.max_step = static_cast<std::int32_t>(args.integer("--max-step", 4, 0, 1000));
  if (args.has("--motion")) {
    if (args.get("--motion") == "walk") o.velocity_walk = true;
    else if (args.get("--motion") != "steps") throw app::UsageError("--motion '" + args.get("--motion") + "' with --shape: want steps or walk");
  }
  o.noise = args.number("--noise", 0.0, 0.0, 1.0);
  if (args.has("--size")) {
    const app::FrameSize size = app::parse_size(args.get("--size"), "--size", 8, 8192);
    o.width = size.width;
    o.height = size.height;
  } else {
    host::fit_image_to_shape(o);
  }
  const auto truth = host::write_synthetic_sequence(o, args.get("-o"));
  std::fprintf(stderr, "%s: %zu frames %ux%u, %zu-point shape, noise %.3f, seed %llu\n", args.get("-o").c_str(), truth.size(),
               o.width, o.height, o.shape.size(), o.noise, static_cast<unsigned long long>(o.seed));
  return 0;
}

}  // namespace gabarit::cli
