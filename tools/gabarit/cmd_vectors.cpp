// gabarit vectors
#include <cstdio>

#include "gabarit/app/args.hpp"
#include "commands.hpp"
#include "gabarit/host/scenes/test_vector_scene.hpp"

namespace gabarit::cli {

int vectors(const std::vector<std::string>& argv) {
  app::Args args("vectors", "--out DIR [options]",
            "Writes the cross-target test vectors: DIR/table.gbt (a 4-DOF table: x, y +-6 px in 2-px cells,\n"
            "theta +-3 deg in 2-deg cells, every focus-stack depth), DIR/vectors.gbv (frames plus the host's\n"
            "track_step results) and DIR/session.gbs (a longer sequence with an occlusion, the focus stack and a\n"
            "TrackingSession's results: motion filter, refinement, recovery, depth and angle by intensity), its twin\n"
            "DIR/session-screened.gbs, DIR/particle.gbp (the session's sequence through gabarit track --tracker\n"
            "particle's defaults on that table: every frame's estimate) and DIR/particle-intensity.gbp (the same on\n"
            "DIR/particle-table.gbt, the model's table with its images: the intensity measure), all in\n"
            "docs/file-formats.md. Every target replays them and must match bit for bit. Same options, same bytes.",
            {{"--out", "DIR", "output directory", false, true},
             {"--points", "N", "approximate model feature count at depth 0, 100..5000 (default 1000)"},
             {"--depths", "N", "focus-stack depths, 1..16 (default 4)"},
             {"--frames", "N", "frames, 1..1000 (default 8)"},
             {"--table-bytes", "N", "the table's budget: the most references that fit in N bytes (default 1048576, half\n"
              "                          of an STM32H7-class part's 2 MiB flash)"},
             {"--keep", "RATIO", "instead of --table-bytes: this fraction of stencil references, (0,1]"},
             {"--noise", "P", "salt-and-pepper rate in [0,1] (default 0.02)"},
             {"--session-frames", "N", "frames of the session's sequence, 1..1000 (default 16)"},
             {"--hidden", "START,FRAMES", "the session's occlusion (default 4,8)"},
             {"--particles", "N", "the particle tracker's particles in particle.gbp, 1..100000 (default 1000)"},
             {"--seed", "S", "seed (default 1; the scene's and the particle tracker's)"}});
  if (!args.parse(argv)) return 0;
  host::VectorSceneOptions o;
  o.model_points = static_cast<std::uint32_t>(args.integer("--points", o.model_points, 100, 5000));
  o.depths = static_cast<std::uint16_t>(args.integer("--depths", o.depths, 1, 16));
  o.frames = static_cast<std::uint32_t>(args.integer("--frames", o.frames, 1, 1000));
  if (args.has("--keep") && args.has("--table-bytes")) throw app::UsageError("--keep and --table-bytes exclude each other");
  o.keep = args.has("--keep") ? args.number("--keep", 0.2, 1e-6, 1.0) : 0.0;
  o.table_budget_bytes = static_cast<std::uint64_t>(args.integer("--table-bytes", static_cast<long long>(o.table_budget_bytes), 4096, 1 << 30));
  o.noise = args.number("--noise", o.noise, 0.0, 1.0);
  o.seed = static_cast<std::uint64_t>(args.integer("--seed", 1, 0, INT64_MAX));
  o.session_frames = static_cast<std::uint32_t>(args.integer("--session-frames", o.session_frames, 1, 1000));
  o.particles = static_cast<std::uint32_t>(args.integer("--particles", o.particles, 1, 100000));
  if (args.has("--hidden")) {
    const auto hidden = app::parse_number_list(args.get("--hidden"), "--hidden", 2, 2);
    for (double v : hidden)
      if (v < 0 || v > 1000 || v != static_cast<double>(static_cast<std::uint32_t>(v)))
        throw app::UsageError("--hidden '" + args.get("--hidden") + "': want START,FRAMES, whole numbers up to 1000");
    o.hidden_from = static_cast<std::uint32_t>(hidden[0]);
    o.hidden_frames = static_cast<std::uint32_t>(hidden[1]);
  }
  const auto s = host::write_test_vectors(o, args.get("--out"));
  std::fprintf(stderr,
               "%s: %zu-point model x %u depths, %u cells, table %zu bytes (keep %.3g%%); %u frames %ux%u, vectors %zu bytes; "
               "%u/%u frames on the true pose; session %u frames, %zu bytes, %u lost, %s; particle tracker %zu bytes, %u frames "
               "tracking; with the intensity measure on a %zu-byte table with images, %u frames tracking\n",
               args.get("--out").c_str(), s.model_points, o.depths, s.cells, s.table_bytes, 100 * s.keep, o.frames, s.width, s.height,
               s.vector_bytes, s.frames_on_truth, o.frames, o.session_frames, s.session_bytes, s.session_lost_frames,
               s.session_reacquired ? "reacquired" : "not reacquired", s.particle_bytes, s.particle_frames_tracking,
               s.particle_table_bytes, s.particle_intensity_frames_tracking);
  return 0;
}

}  // namespace gabarit::cli
