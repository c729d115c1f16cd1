// gabarit synth
#include <cstdio>

#include "args.hpp"
#include "commands.hpp"
#include "gabarit/host/synth.hpp"
#include "gabarit/host/thesis_shapes.hpp"

namespace gabarit::cli {

int synth(const std::vector<std::string>& argv) {
  Args args("synth", "--shape points.csv|random --frames N --max-step PX --noise P --seed S -o DIR",
            "Writes a synthetic sequence of the thesis (section 6.2): a point shape translated over an empty\n"
            "image by a random displacement within +-PX per axis and frame, with salt-and-pepper noise of rate P.\n"
            "Outputs DIR/frames.y4m (Cmono), DIR/gt.csv (frame,x,y,theta_deg,depth,visible), DIR/model.csv\n"
            "and DIR/model.pgm. Deterministic per seed.",
            {{"--shape", "SRC", "random | curve (thesis ~194 points) | watch (~2800 edge points of a Debian\n"
              "                          photograph) | photo:FILE.pgm | points CSV (x,y relative to the reference)", false, true},
             {"--points", "N", "approximate point count for random (default 194) and photo: (default 2800)"},
             {"--frames", "N", "frame count (default 100)"},
             {"--max-step", "PX", "largest displacement per axis and frame (default 4)"},
             {"--noise", "P", "salt-and-pepper rate in [0,1] (default 0)"},
             {"--seed", "S", "seed (default 1)"},
             {"--size", "WxH", "image size (default: 256x256, larger if the shape needs it)"},
             {"-o", "DIR", "output directory", false, true}});
  if (!args.parse(argv)) return 0;
  host::SynthOptions o;
  o.seed = static_cast<std::uint64_t>(args.integer("--seed", 1, 0, INT64_MAX));
  const std::string shape = args.get("--shape");
  const bool counted = shape == "random" || shape.rfind("photo:", 0) == 0;
  if (args.has("--points") && !counted) throw UsageError("--points applies to --shape random and photo:");
  o.shape = host::resolve_shape(shape, static_cast<std::size_t>(args.integer("--points", shape == "random" ? 194 : 2800, 8, 20000)),
                                o.seed);
  o.frames = static_cast<std::uint32_t>(args.integer("--frames", 100, 1, 1000000));
  o.max_step = static_cast<std::int32_t>(args.integer("--max-step", 4, 0, 1000));
  o.noise = args.number("--noise", 0.0, 0.0, 1.0);
  if (args.has("--size")) {
    unsigned w = 0, h = 0;
    char tail = 0;
    if (std::sscanf(args.get("--size").c_str(), "%ux%u%c", &w, &h, &tail) != 2 || w < 8 || h < 8 || w > 8192 || h > 8192) {
      throw UsageError("--size '" + args.get("--size") + "': want WxH with 8 <= W,H <= 8192");
    }
    o.width = w;
    o.height = h;
  } else {
    host::fit_image_to_shape(o);
  }
  const auto truth = host::write_synthetic_sequence(o, args.get("-o"));
  std::fprintf(stderr, "%s: %zu frames %ux%u, %zu-point shape, noise %.3f, seed %llu\n", args.get("-o").c_str(), truth.size(),
               o.width, o.height, o.shape.size(), o.noise, static_cast<unsigned long long>(o.seed));
  return 0;
}

}  // namespace gabarit::cli
