// gabarit track: declare the options, read them into a session profile and
// the run's extras (validated once), run, report.
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <sstream>

#include "commands.hpp"
#include "gabarit/app/args.hpp"
#include "gabarit/app/error.hpp"
#include "gabarit/app/files.hpp"
#include "gabarit/app/image_io.hpp"
#include "gabarit/app/particle_run.hpp"
#include "gabarit/app/scratch.hpp"
#include "gabarit/app/session_profile_io.hpp"
#include "gabarit/features.hpp"
#include "gabarit/host/runs/detection_run.hpp"
#include "gabarit/host/runs/tracking_run.hpp"

namespace gabarit::cli {

namespace {

app::Args declare_track() {
  std::vector<app::Option> options = {
      {"--table", "T", "table file", false, true},
      {"--frames", "SEQ", "Y4M file or directory of .pgm frames", false, true},
      {"--init", "X,Y[,THETA[,DEPTH]]", "pose before the first frame (image position of the reference point); without it\n"
       "                          the model is found by detection (gabarit detect) in the first frames: rows\n"
       "                          before it is found are lost, at 0,0"},
      {"--theta-range", "A:B", "detection (no --init, --recovery detect): absolute angles searched (default -180:180)"},
      {"--min-score", "S", "detection: the lowest verified score accepted, 0..1 (default 0.5)"},
      {"--binary", "", "use the binary detector on frames whatever the table says"},
      {"--voter", "auto|csr|dense", "voting method (default auto: the one dense_voter.hpp's cost model expects faster); same results"},
      {"--coarse", "T", "table for the recovery search (larger cells, wider window): its 8 best cells\n"
                        "                          are checked by the table instead of the search grid (implies --recover)"},
      {"--threads", "N", "vote each frame on N threads, 1..64 (default 1): the plain loop only (implies --plain;\n"
                         "                          same output as one thread)"},
      {"--focus-stack", "A.pgm,B.pgm,...", "model images, one per depth, instead of those the table carries: each\n"
                                           "                          frame's depth (and the reported angle) by intensity (normalised\n"
                                           "                          cross-correlation) at the tracked pose"},
      {"-o", "POSES.csv", "pose output (default stdout)"},
      {"--stats", "STATS.json", "per-frame timing and vote statistics"}};
  for (app::Option& o : app::session_option_group()) options.push_back(std::move(o));
  return app::Args("track", "--table T --frames SEQ [--init X,Y[,THETA[,DEPTH]]] [--plain | --tracker particle] [-o POSES.csv] [--stats STATS.json]",
                   "Tracks the table's model through a sequence (a Y4M file, Cmono or 4:2:0, luma used; or a directory of\n"
                   "PGM frames), streamed frame by frame. Writes frame,x,y,theta_deg,depth,votes,score,status per frame\n"
                   "(to stdout without -o).\n"
                   "By default the tracking session runs (docs/tracking.md): the motion filter (a Kalman filter placing\n"
                   "the ROI, gating candidates and grading confidence), sub-cell refinement, recovery once lost, and depth\n"
                   "and angle by intensity with the focus stack the table carries (tables built from images). --plain\n"
                   "runs the thesis's loop instead: each frame's best cell, nothing added. --tracker particle runs the\n"
                   "thesis's other tracker, its particle filter (chapter 3), on the table's model points. The session's\n"
                   "options are a session profile (--profile, --save-profile; docs/file-formats.md).",
                   std::move(options));
}

// What gabarit track adds to the profile that only the stencil session takes.
void refuse_for_particle_tracker(const app::Args& args) {
  for (const char* option : {"--coarse", "--threads", "--focus-stack"})
    if (args.has(option)) throw app::UsageError(std::string(option) + " applies to the stencil tracker, not --tracker particle");
}

// The stencil session's run: the profile from the shared option group, and
// what only gabarit track adds (threads, a coarse table, focus-stack images,
// detection without --init).
host::TrackingOptions read_tracking(const app::Args& args, const app::SessionProfile& profile, const TableView& table,
                                    std::optional<app::TableFile>& coarse_file, std::vector<std::string>& inputs) {
  host::TrackingOptions options;
  options.extras.voter = app::parse_voter(args.get_or("--voter", "auto"), "--voter");
  if (args.has("--binary")) options.extras.detector = Detector{table_format::DetectorKind::kBinary, 0};
  options.threads = static_cast<unsigned>(args.integer("--threads", 1, 1, 64));
  const bool session_flags = args.has("--motion-filter") || args.has("--refine") || args.has("--recover") || args.has("--coarse");
  if (options.threads > 1 && (session_flags || args.has("--focus-stack") || args.has("--subcell") || args.has("--profile")))
    throw app::UsageError("--threads applies to the plain loop, without --motion-filter, --refine, --recover, --coarse, "
                          "--subcell, --profile or --focus-stack");
  if (options.threads > 1 && args.has("--voter")) throw app::UsageError("--threads votes with its own (multi-threaded CSR) voter; drop --voter");
  if (args.has("--focus-stack") && args.has("--no-focus-stack")) throw app::UsageError("give one of --focus-stack and --no-focus-stack");
  options.profile = profile;
  if (options.threads > 1) options.profile.plain = true;
  if (options.threads > 1 && options.profile.recovery == app::RecoveryKind::kAuto) options.profile.recovery = app::RecoveryKind::kGrid;
  if (args.has("--coarse") && options.profile.recovery == app::RecoveryKind::kAuto) options.profile.recovery = app::RecoveryKind::kGrid;
  if (options.threads > 1 && options.profile.recovery != app::RecoveryKind::kGrid)
    throw app::UsageError("--threads applies to the plain loop, not --recovery " + args.get("--recovery"));
  if (args.has("--coarse")) {
    if (options.profile.recovery != app::RecoveryKind::kGrid)
      throw app::UsageError(std::string("--recovery ") + args.get("--recovery") + " replaces the --coarse search; give one of them");
    if (options.profile.plain) options.profile.recover = true;  // --coarse implies --recover
    const TableView& coarse = coarse_file.emplace(args.get("--coarse")).view();
    if (coarse.depth_count() != table.depth_count())
      throw app::UsageError("--coarse: the coarse table has " + std::to_string(coarse.depth_count()) + " depths, the table " +
                            std::to_string(table.depth_count()));
    options.extras.coarse = &coarse;
    inputs.push_back(args.get("--coarse"));
  }
  options.detect_first = !args.has("--init");
  if ((args.has("--theta-range") || args.has("--min-score")) && options.profile.recovery != app::RecoveryKind::kDetection &&
      options.profile.recovery != app::RecoveryKind::kAuto &&
      !options.detect_first)
    throw app::UsageError("--theta-range and --min-score apply to detection: without --init, or with --recovery detect");
  if (options.detect_first && options.threads > 1) throw app::UsageError("--threads needs --init");
  options.extras.finder = host::finder_options_from(args, table);
  options.extras.finder.max_count = 1;
  options.extras.finder.candidates = FinderOptions{}.candidates;
  if (args.has("--focus-stack")) {
    const std::string list = args.get("--focus-stack");
    for (std::size_t start = 0; start <= list.size();) {
      const std::size_t comma = std::min(list.find(',', start), list.size());
      const std::string path = list.substr(start, comma - start);
      if (path.empty()) throw app::UsageError("--focus-stack: an empty image path");
      options.extras.focus_stack.push_back(app::read_pgm(path));
      inputs.push_back(path);
      start = comma + 1;
    }
  }
  return options;
}

// The particle tracker's run: the profile's particle numbers and measure.
app::ParticleRunOptions read_particle_tracker(const app::Args& args, const app::SessionProfile& profile) {
  refuse_for_particle_tracker(args);
  if (!args.has("--init")) throw app::UsageError("--tracker particle needs --init");
  app::ParticleRunOptions po = app::particle_run_options(profile);
  if (args.has("--binary")) po.detector = Detector{table_format::DetectorKind::kBinary, 0};
  po.voter = app::parse_voter(args.get_or("--voter", "auto"), "--voter");
  return po;
}

// What a run counts for the summary line and --stats.
struct TrackTally {
  std::vector<double> micros;
  double features = 0, votes = 0;
  std::uint64_t dropped = 0;
  std::size_t lost = 0, uncertain = 0;
  // The frame-cost ledger summed over the run (frame_ledger.hpp): phase
  // ticks in nanoseconds (HostedSession's clock), phase work, raw counts.
  bool ledger = true;  // every row had one
  FrameLedger sum;
  double io_micros = 0;
  void add(const app::TrackRow& row) {
    micros.push_back(row.micros);
    ledger = ledger && row.has_ledger;
    for (std::uint32_t p = 0; p < kFramePhaseCount; ++p) {
      sum.add(static_cast<FramePhase>(p), row.ledger.work[p], row.ledger.ticks[p]);
    }
    sum.pixels_scanned += row.ledger.pixels_scanned;
    sum.features += row.ledger.features;
    sum.votes += row.ledger.votes;
    sum.correlations += row.ledger.correlations;
    io_micros += row.io_micros;
    features += row.step.features;
    votes += static_cast<double>(row.step.votes);
    dropped += row.step.features_dropped;
    lost += row.step.state == TrackState::kLost;
    uncertain += row.step.state == TrackState::kUncertain;
  }
};

// The ledger per frame as JSON (null without one: the plain loop on several threads).
std::string ledger_json(const TrackTally& tally, double n) {
  if (!tally.ledger || tally.micros.empty()) return "null";
  std::ostringstream o;
  o << "{";
  for (std::uint32_t p = 0; p < kFramePhaseCount; ++p) {
    o << "\n    \"" << frame_phase_name(static_cast<FramePhase>(p)) << "\": {\"us_per_frame\": "
      << static_cast<double>(tally.sum.ticks[p]) / 1000.0 / n
      << ", \"work_per_frame\": " << static_cast<double>(tally.sum.work[p]) / n << "},";
  }
  o << "\n    \"io\": {\"us_per_frame\": " << tally.io_micros / n << "},"
    << "\n    \"pixels_scanned_per_frame\": " << static_cast<double>(tally.sum.pixels_scanned) / n
    << ",\n    \"features_per_frame\": " << static_cast<double>(tally.sum.features) / n
    << ",\n    \"votes_per_frame\": " << static_cast<double>(tally.sum.votes) / n
    << ",\n    \"correlations_per_frame\": " << static_cast<double>(tally.sum.correlations) / n << "\n  }";
  return o.str();
}

void report(const app::Args& args, const TableView& table, const TrackTally& tally) {
  const host::TimingSummary t = host::summarise_timing(tally.micros);
  const double n = t.frames ? static_cast<double>(t.frames) : 1.0;
  if (args.has("--stats")) {
    std::ostringstream stats;
    stats << "{\n  \"frames\": " << t.frames << ",\n  \"per_frame_us\": {\"mean\": " << t.mean << ", \"p50\": " << t.p50
          << ", \"p99\": " << t.p99 << ", \"max\": " << t.max << "},\n  \"features_per_frame\": " << tally.features / n
          << ",\n  \"votes_per_frame\": " << tally.votes / n << ",\n  \"features_dropped\": " << tally.dropped
          << ",\n  \"lost_frames\": " << tally.lost << ",\n  \"uncertain_frames\": " << tally.uncertain
          << ",\n  \"canny_vector_body\": \"" << canny_vector_body() << "\""
          << ",\n  \"table_bytes\": " << table.size_bytes() << ",\n  \"cells\": " << table.cell_count()
          << ",\n  \"ledger\": " << ledger_json(tally, n) << "\n}\n";
    app::write_file(args.get("--stats"), stats.str());
  }
  std::fprintf(stderr, "tracked %zu frames: %.1f us/frame mean (p50 %.1f, p99 %.1f, max %.1f), %.0f features and %.0f votes per frame, %zu lost\n",
               t.frames, t.mean, t.p50, t.p99, t.max, tally.features / n, tally.votes / n, tally.lost);
  if (tally.ledger && t.frames > 0) {
    std::string line = "per frame, us:";
    for (std::uint32_t p = 0; p < kFramePhaseCount; ++p) {
      char part[48];
      std::snprintf(part, sizeof part, " %s %.1f", frame_phase_name(static_cast<FramePhase>(p)),
                    static_cast<double>(tally.sum.ticks[p]) / 1000.0 / n);
      line += part;
    }
    char io[40];
    std::snprintf(io, sizeof io, "; reading frames %.1f", tally.io_micros / n);
    std::fprintf(stderr, "%s%s\n", line.c_str(), io);
  }
}

}  // namespace

int track(const std::vector<std::string>& argv) {
  app::Args args = declare_track();
  if (!args.parse(argv)) return 0;
  const app::TableFile table_file(args.get("--table"));
  const TableView& table = table_file.view();
  const Pose pose = args.has("--init") ? app::parse_init_pose(args.get("--init"), table, "--init") : Pose{};
  // The profile (--profile and the options over it) chooses the tracker.
  const app::SessionProfile profile = app::read_session_profile(args);
  const bool particle = profile.tracker == app::TrackerKind::kParticle;

  std::vector<std::string> inputs = {args.get("--table"), args.get("--frames")};
  if (args.has("--profile")) inputs.push_back(args.get("--profile"));
  std::optional<app::TableFile> coarse_file;
  std::optional<host::TrackingOptions> options;
  std::optional<app::ParticleRunOptions> particle_options;
  if (particle) {
    particle_options = read_particle_tracker(args, profile);
  } else {
    options = read_tracking(args, profile, table, coarse_file, inputs);
  }
  // Outputs never name an input, and replace their file only when the run
  // is complete: any error leaves a previous output as it was.
  for (const char* option : {"-o", "--stats", "--save-profile"}) {
    if (args.has(option)) app::refuse_same_file(args.get(option), option, inputs);
  }
  if (args.has("-o") && args.has("--stats")) app::refuse_same_file(args.get("--stats"), "--stats", {args.get("-o")});
  if (args.has("--save-profile")) {
    for (const char* other : {"-o", "--stats"})
      if (args.has(other)) app::refuse_same_file(args.get("--save-profile"), "--save-profile", {args.get(other)});
    app::write_file(args.get("--save-profile"), app::format_profile(particle ? profile : options->profile));
  }

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
  TrackTally tally;
  const auto on_row = [&](const app::TrackRow& row) {
    rows += app::pose_csv_row(row);
    rows += '\n';
    emit(false);
    tally.add(row);
  };
  if (particle) {
    app::run_particle_tracking(table, *frames, pose, *particle_options, on_row);
  } else {
    host::run_tracking(table, *frames, pose, *options, on_row);
  }
  emit(true);
  if (file_out) file_out->commit();
  if (!file_out && (std::fflush(stdout) != 0 || std::ferror(stdout))) throw app::Error("pose output (stdout): write failed");
  report(args, table, tally);
  return 0;
}

}  // namespace gabarit::cli
