// gabarit track
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <sstream>

#include "gabarit/app/args.hpp"
#include "commands.hpp"
#include "gabarit/app/error.hpp"
#include "gabarit/app/image_io.hpp"
#include "gabarit/app/files.hpp"
#include "gabarit/app/scratch.hpp"
#include "gabarit/host/detection_run.hpp"
#include "gabarit/host/particle_run.hpp"
#include "gabarit/host/tracking_run.hpp"

namespace gabarit::cli {

int track(const std::vector<std::string>& argv) {
  app::Args args("track", "--table T --frames SEQ [--init X,Y[,THETA[,DEPTH]]] [--plain | --tracker particle] [-o POSES.csv] [--stats STATS.json]",
            "Tracks the table's model through a sequence (a Y4M file, Cmono or 4:2:0, luma used; or a directory of\n"
            "PGM frames), streamed frame by frame. Writes frame,x,y,theta_deg,depth,votes,score,status per frame\n"
            "(to stdout without -o).\n"
            "By default the tracking session runs (docs/tracking.md): the motion filter (a Kalman filter placing\n"
            "the ROI, gating candidates and grading confidence), sub-cell refinement, recovery once lost, and depth\n"
            "and angle by intensity with the focus stack the table carries (tables built from images). --plain\n"
            "runs the thesis's loop instead: each frame's best cell, nothing added. --tracker particle runs the\n"
            "thesis's other tracker, its particle filter (chapter 3), on the table's model points.",
            {{"--table", "T", "table file", false, true},
             {"--frames", "SEQ", "Y4M file or directory of .pgm frames", false, true},
             {"--init", "X,Y[,THETA[,DEPTH]]", "pose before the first frame (image position of the reference point); without it\n"
              "                          the model is found by detection (gabarit detect) in the first frames: rows\n"
              "                          before it is found are lost, at 0,0"},
             {"--theta-range", "A:B", "detection (no --init, --recovery detect): absolute angles searched (default -180:180)"},
             {"--min-score", "S", "detection: the lowest verified score accepted, 0..1 (default 0.5)"},
             {"--detect-after", "N", "--recovery detect: the first N lost frames search with the grid, the later ones\n"
              "                          by detection (default 2; 0: detection from the first)"},
             {"--plain", "", "the thesis's loop: the best cell of each frame, no filter, refinement, recovery or\n"
              "                          focus stack (add --motion-filter, --refine or --recover to it one by one)"},
             {"--binary", "", "use the binary detector on frames whatever the table says"},
             {"--voter", "auto|csr|dense", "voting method (default auto: the one dense_voter.hpp's cost model expects faster); same results"},
             {"--motion-filter", "", "with --plain: predict the ROI, gate candidates, grade confidence (default on)"},
             {"--refine", "", "with --plain: sub-cell x, y, theta from the neighbouring cells' scores (default on)"},
             {"--recover", "", "with --plain: once lost, search around the last confident pose (default on)"},
             {"--subcell", "parabola|alignment", "how refinement places the pose within the cell: a parabola through the\n"
              "                          neighbouring cells' scores (default), or a least-squares alignment of the\n"
              "                          matched features (docs/tracking.md compares them)"},
             {"--coarse", "T", "table for the recovery search (larger cells, wider window): its 8 best cells\n"
                                  "are checked by the table instead of the search grid (implies --recover)"},
             {"--search-budget", "N", "recovery grid placements per search beyond the nearest 9, 1..558 (default: all\n"
                                     "558; fewer cost less and cover the grid over several searches)"},
             {"--screen-stride", "N", "recovery placements are screened with every N-th feature, 1..16 (default 2)"},
             {"--search-interval", "N", "search every N-th lost frame, 1..100 (default 1; the frames between only\n"
                                       "predict, so a lost period costs about 1/N)"},
             {"--threads", "N", "vote each frame on N threads, 1..64 (default 1): the plain loop only (implies --plain;\n"
              "                          same output as one thread)"},
             {"--focus-stack", "A.pgm,B.pgm,...", "model images, one per depth, instead of those the table carries: each\n"
                                                  "frame's depth (and the reported angle) by intensity (normalised\n"
                                                  "cross-correlation) at the tracked pose"},
             {"--no-focus-stack", "", "ignore the table's model images: depth from the winning stencils only"},
             {"--recovery", "grid|detect|particle", "how the session re-acquires a lost target: the grid search around where it\n"
              "                          was last seen (default), detection over the whole frame (docs/detection.md),\n"
              "                          or a particle filter over the whole frame (docs/particle-filter.md)"},
             {"--tracker", "stencil|particle", "stencil (default): the stencil session above; particle: the thesis's\n"
              "                          particle filter (chapter 3, docs/particle-filter.md) with the table's model"},
             {"--particles", "N", "--tracker particle, --recovery particle: particles, 1..1000000 (default 1000)"},
             {"--seed", "S", "--tracker particle, --recovery particle: the generator's seed (default 1); same seed,\n"
              "                          same output"},
             {"--measure", "edges|stencil", "--tracker particle: edge correlation over the table's model points\n"
              "                          (default), or the stencil vote of each particle's cell"},
             {"--edge-stride", "N", "the particle filter's edge measure: every N-th model point, 1..64 (default 2)"},
             {"--edge-tolerance", "PX", "the particle filter's edge measure: a point within PX pixels of an edge\n"
              "                          counts, 0..3 (default 0)"},
             {"--without", "LIST", "the particle filter's improvements to switch off, comma-separated: modes,\n"
              "                          disambiguation, narrowing, kinematics, reinit, mode-filter, velocity;\n"
              "                          all: plain CONDENSATION"},
             {"-o", "POSES.csv", "pose output (default stdout)"},
             {"--stats", "STATS.json", "per-frame timing and vote statistics"}});
  if (!args.parse(argv)) return 0;
  const app::TableFile table_file(args.get("--table"));
  const TableView& table = table_file.view();
  const bool detect_first = !args.has("--init");
  const Pose pose = detect_first ? Pose{} : app::parse_init_pose(args.get("--init"), table, "--init");
  const std::string tracker = args.get_or("--tracker", "stencil");
  if (tracker != "stencil" && tracker != "particle") throw app::UsageError("--tracker '" + tracker + "': want stencil or particle");
  const bool particle = tracker == "particle";
  const bool particle_recovery = args.get_or("--recovery", "grid") == "particle";
  for (const char* option : {"--particles", "--seed", "--without", "--edge-stride", "--edge-tolerance"})
    if (!particle && !particle_recovery && args.has(option))
      throw app::UsageError(std::string(option) + " applies to --tracker particle and --recovery particle");
  if (!particle && args.has("--measure")) throw app::UsageError("--measure applies to --tracker particle");
  if (particle) {
    for (const char* option : {"--plain", "--motion-filter", "--refine", "--recover", "--recovery", "--subcell", "--coarse", "--search-budget",
                               "--screen-stride", "--search-interval", "--threads", "--focus-stack", "--no-focus-stack"})
      if (args.has(option)) throw app::UsageError(std::string(option) + " applies to the stencil tracker, not --tracker particle");
  }
  const app::VoterChoice voter = app::parse_voter(args.get_or("--voter", "auto"), "--voter");
  host::TrackingOptions options;
  options.voter = voter;
  if (args.has("--binary")) options.detector = Detector{table_format::DetectorKind::kBinary, 0};
  options.threads = static_cast<unsigned>(args.integer("--threads", 1, 1, 64));
  const bool session_flags = args.has("--motion-filter") || args.has("--refine") || args.has("--recover") || args.has("--coarse");
  if (options.threads > 1 && (session_flags || args.has("--focus-stack")))
    throw app::UsageError("--threads applies to the plain loop, without --motion-filter, --refine, --recover, --coarse or --focus-stack");
  const bool plain = args.has("--plain") || options.threads > 1;
  if (args.has("--focus-stack") && args.has("--no-focus-stack")) throw app::UsageError("give one of --focus-stack and --no-focus-stack");
  options.session = app::session_options(plain, args.has("--motion-filter"), args.has("--refine"),
                                         args.has("--recover") || args.has("--coarse"));
  options.table_focus_stack = !plain && !args.has("--no-focus-stack");
  if (const std::string subcell = args.get_or("--subcell", "parabola"); subcell == "alignment") {
    options.session.align_features = true;
  } else if (subcell != "parabola") {
    throw app::UsageError("--subcell '" + subcell + "': want parabola or alignment");
  }
  if (args.has("--subcell") && !options.session.refine) throw app::UsageError("--subcell needs refinement: drop --plain or add --refine");
  if (args.has("--subcell") && options.threads > 1) throw app::UsageError("--subcell applies to the session, not --threads");
  if (const std::string recovery = args.get_or("--recovery", "grid"); recovery == "particle") {
    if (!options.session.recover) throw app::UsageError("--recovery particle needs recovery: drop --plain or add --recover");
    if (args.has("--coarse")) throw app::UsageError("--recovery particle replaces the --coarse search; give one of them");
    options.particle_recovery = true;
    host::ParticleRunOptions& po = options.particles;
    po.particles = static_cast<std::uint32_t>(args.integer("--particles", po.particles, 1, 1000000));
    po.seed = static_cast<std::uint64_t>(args.integer("--seed", 1, 0, std::numeric_limits<std::int64_t>::max()));
    po.edge_stride = static_cast<std::uint32_t>(args.integer("--edge-stride", po.edge_stride, 1, 64));
    po.edge_tolerance = static_cast<std::uint32_t>(args.integer("--edge-tolerance", po.edge_tolerance, 0, 3));
    if (args.has("--without")) host::switch_off_improvements(args.get("--without"), po.filter, "--without");
  } else if (recovery == "detect") {
    if (!options.session.recover) throw app::UsageError("--recovery detect needs recovery: drop --plain or add --recover");
    if (args.has("--coarse")) throw app::UsageError("--recovery detect replaces the --coarse search; give one of them");
    options.detection_recovery = true;
  } else if (recovery != "grid") {
    throw app::UsageError("--recovery '" + recovery + "': want grid, detect or particle");
  }
  options.detect_first = detect_first;
  if (args.has("--detect-after") && !options.detection_recovery) throw app::UsageError("--detect-after applies to --recovery detect");
  options.session.recovery.detect_after =
      static_cast<std::uint32_t>(args.integer("--detect-after", RecoveryOptions{}.detect_after, 0, 1000));
  if ((args.has("--theta-range") || args.has("--min-score")) && !options.detection_recovery && !detect_first)
    throw app::UsageError("--theta-range and --min-score apply to detection: without --init, or with --recovery detect");
  if (detect_first && (particle || options.threads > 1))
    throw app::UsageError("--tracker particle and --threads need --init");
  options.finder = host::finder_options_from(args, table);
  options.finder.max_count = 1;
  options.finder.candidates = FinderOptions{}.candidates;
  options.session.recovery.budget = static_cast<std::uint32_t>(args.integer("--search-budget", 0, 1, 558));
  options.session.recovery.interval = static_cast<std::uint32_t>(args.integer("--search-interval", 1, 1, 100));
  options.session.recovery.screen_stride = static_cast<std::uint32_t>(args.integer("--screen-stride", 2, 1, 16));
  std::vector<std::string> focus_stack_paths;
  if (args.has("--focus-stack")) {
    std::string list = args.get("--focus-stack");
    for (std::size_t start = 0; start <= list.size();) {
      const std::size_t comma = std::min(list.find(',', start), list.size());
      const std::string path = list.substr(start, comma - start);
      if (path.empty()) throw app::UsageError("--focus-stack: an empty image path");
      options.focus_stack.push_back(app::read_pgm(path));
      focus_stack_paths.push_back(path);
      start = comma + 1;
    }
  }
  if (options.threads > 1 && args.has("--voter")) throw app::UsageError("--threads votes with its own (multi-threaded CSR) voter; drop --voter");
  std::optional<app::TableFile> coarse_file;
  if (args.has("--coarse")) {
    const TableView& coarse = coarse_file.emplace(args.get("--coarse")).view();
    if (coarse.depth_count() != table.depth_count())
      throw app::UsageError("--coarse: the coarse table has " + std::to_string(coarse.depth_count()) + " depths, the table " +
                       std::to_string(table.depth_count()));
    options.coarse = &coarse;
  }

  // Outputs never name an input, and replace their file only when the run
  // is complete: any error leaves a previous output as it was.
  std::vector<std::string> inputs = {args.get("--table"), args.get("--frames"), args.get_or("--coarse", "")};
  for (const std::string& path : focus_stack_paths) inputs.push_back(path);
  for (const char* option : {"-o", "--stats"}) {
    if (args.has(option)) app::refuse_same_file(args.get(option), option, inputs);
  }
  if (args.has("-o") && args.has("--stats")) app::refuse_same_file(args.get("--stats"), "--stats", {args.get("-o")});
  auto frames = app::open_frames(args.get("--frames"));
  std::optional<app::OutputFile> file_out;
  if (args.has("-o")) file_out.emplace(args.get("-o"));
  std::string rows = std::string(app::kPoseCsvHeader) + '\n';
  const auto emit = [&](bool last) {  // to the file as it grows, to stdout line by line
    if (file_out) {
      if (rows.size() >= 65536 || last) file_out->write(rows), rows.clear();
    } else {
      std::fputs(rows.c_str(), stdout);
      rows.clear();
    }
  };
  std::vector<double> micros;
  double features = 0, votes = 0;
  std::uint64_t dropped = 0;
  std::size_t lost = 0, uncertain = 0;
  const auto on_row = [&](const app::TrackRow& row) {
    rows += app::pose_csv_row(row);
    rows += '\n';
    emit(false);
    micros.push_back(row.micros);
    features += row.step.features;
    votes += static_cast<double>(row.step.votes);
    dropped += row.step.features_dropped;
    lost += row.step.state == TrackState::kLost;
    uncertain += row.step.state == TrackState::kUncertain;
  };
  if (particle) {
    host::ParticleRunOptions po;
    po.particles = static_cast<std::uint32_t>(args.integer("--particles", 1000, 1, 1000000));
    po.seed = static_cast<std::uint64_t>(args.integer("--seed", 1, 0, std::numeric_limits<std::int64_t>::max()));
    po.detector = options.detector;
    po.voter = voter;
    if (const std::string m = args.get_or("--measure", "edges"); m == "stencil") {
      po.measure = host::ParticleMeasureKind::kStencil;
      po.finer = false;  // one vote per frame and no edge map: modes ranked by weight, confidence from the vote
    } else if (m != "edges") {
      throw app::UsageError("--measure '" + m + "': want edges or stencil");
    }
    po.edge_stride = static_cast<std::uint32_t>(args.integer("--edge-stride", 2, 1, 64));
    po.edge_tolerance = static_cast<std::uint32_t>(args.integer("--edge-tolerance", 0, 0, 3));
    if (args.has("--without")) host::switch_off_improvements(args.get("--without"), po.filter, "--without");
    host::run_particle_tracking(table, *frames, pose, po, on_row);
  } else {
    host::run_tracking(table, *frames, pose, options, on_row);
  }
  emit(true);
  if (file_out) file_out->commit();
  if (!file_out && (std::fflush(stdout) != 0 || std::ferror(stdout))) throw app::Error("pose output (stdout): write failed");
  const host::TimingSummary t = host::summarise_timing(micros);
  const double n = t.frames ? static_cast<double>(t.frames) : 1.0;
  if (args.has("--stats")) {
    std::ostringstream stats;
    stats << "{\n  \"frames\": " << t.frames << ",\n  \"per_frame_us\": {\"mean\": " << t.mean << ", \"p50\": " << t.p50
          << ", \"p99\": " << t.p99 << ", \"max\": " << t.max << "},\n  \"features_per_frame\": " << features / n
          << ",\n  \"votes_per_frame\": " << votes / n << ",\n  \"features_dropped\": " << dropped
          << ",\n  \"lost_frames\": " << lost << ",\n  \"uncertain_frames\": " << uncertain
          << ",\n  \"table_bytes\": " << table.size_bytes() << ",\n  \"cells\": " << table.cell_count() << "\n}\n";
    app::write_file(args.get("--stats"), stats.str());
  }
  std::fprintf(stderr, "tracked %zu frames: %.1f us/frame mean (p50 %.1f, p99 %.1f, max %.1f), %.0f features and %.0f votes per frame, %zu lost\n",
               t.frames, t.mean, t.p50, t.p99, t.max, features / n, votes / n, lost);
  return 0;
}

}  // namespace gabarit::cli
