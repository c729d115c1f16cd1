// gabarit detect
#include <chrono>
#include <cstdio>
#include <optional>

#include "commands.hpp"
#include "gabarit/app/args.hpp"
#include "gabarit/app/error.hpp"
#include "gabarit/app/files.hpp"
#include "gabarit/app/image_io.hpp"
#include "gabarit/app/scratch.hpp"
#include "gabarit/host/runs/detection_run.hpp"

namespace gabarit::cli {

int detect(const std::vector<std::string>& argv) {
  app::Args args("detect", "--table T IMAGE|SEQ [--max-count N] [--min-score S] [-o DETECTIONS.csv]",
                 "Finds the table's model anywhere in an image (PGM), or in every frame of a sequence (Y4M, or a\n"
                 "directory of PGM frames), at any angle of --theta-range and any depth of the table, with no\n"
                 "starting pose (docs/detection.md). Writes frame,rank,x,y,theta_deg,depth,score,coarse_score,\n"
                 "vote_score, best first (to stdout without -o): score is the fraction of the model's points that\n"
                 "have an edge of their orientation within a pixel at the pose (0..1); detections below --min-score\n"
                 "are not reported, nor any within --min-distance of a better one. A frame without a detection has\n"
                 "no row. A summary (frames, detections, time per frame) goes to stderr.",
                 {{"--table", "T", "table file", false, true},
                  {"--max-count", "N", "detections per frame, 1..64 (default 5)"},
                  {"--min-score", "S", "lowest score reported, 0..1 (default 0.5)"},
                  {"--min-distance", "PX", "closer detections are one, the better kept (default: half the model's radius)"},
                  {"--theta-range", "A:B", "absolute angles searched, degrees (default -180:180, a full turn)"},
                  {"--theta-step", "DEG", "the coarse level's angle step (default: the table's theta reach, at most\n"
                   "                          a radian over the coarse model's radius)"},
                  {"--pyramid", "F", "coarse blocks of FxF pixels, 1..8 (default: from the model's size, 1..4)"},
                  {"--candidates", "N", "coarse peaks checked with the table, 1..64 (default 6, at least --max-count)"},
                  {"--position-only", "", "the coarse vote ignores edge orientation (the thesis's position-only features)"},
                  {"--binary", "", "use the binary detector on frames whatever the table says"},
                  {"--frames-limit", "N", "a sequence: stop after N frames"},
                  {"-o", "DETECTIONS.csv", "output (default stdout); replaced only when complete"}},
                 "IMAGE|SEQ");
  if (!args.parse(argv)) return 0;
  if (args.positionals().size() != 1) throw app::UsageError("want one IMAGE or sequence, got " + std::to_string(args.positionals().size()));
  const std::string input = args.positionals()[0];
  const app::TableFile table_file(args.get("--table"));
  const TableView& table = table_file.view();
  Detector detector = detector_of(table);
  if (args.has("--binary")) detector = Detector{table_format::DetectorKind::kBinary, 0};
  const FinderOptions options = host::finder_options_from(args, table);
  const auto limit = static_cast<std::uint64_t>(args.integer("--frames-limit", 0, 1, std::int64_t{1} << 40));
  if (args.has("-o")) app::refuse_same_file(args.get("-o"), "-o", {args.get("--table"), input});

  std::unique_ptr<app::FrameSource> frames;
  std::optional<app::GrayImage> single;
  if (input.size() > 4 && input.compare(input.size() - 4, 4, ".pgm") == 0) {
    single = app::read_pgm(input);
  } else {
    frames = app::open_frames(input);
  }
  std::optional<app::OutputFile> file_out;
  if (args.has("-o")) file_out.emplace(args.get("-o"));
  std::string text = std::string(host::kDetectionCsvHeader) + '\n';
  const auto emit = [&](bool last) {
    if (file_out) {
      if (text.size() >= 65536 || last) file_out->write(text), text.clear();
    } else {
      std::fputs(text.c_str(), stdout);
      text.clear();
    }
  };
  host::FrameDetector finder(table, detector, options);
  app::GrayImage frame;
  std::uint64_t index = 0, found = 0;
  double micros = 0;
  while (limit == 0 || index < limit) {
    if (single) {
      if (index > 0) break;
      frame = *single;
    } else if (!frames->next(frame)) {
      break;
    }
    const host::FrameDetections d = finder.detect(frame.view());
    micros += d.micros;
    for (std::size_t r = 0; r < d.detections.size(); ++r) text += host::detection_csv_row(index, r, d.detections[r]) + '\n';
    found += d.detections.size();
    emit(false);
    ++index;
    if (!single && index % 50 == 0) std::fprintf(stderr, "gabarit detect: %llu frames\r", static_cast<unsigned long long>(index));
  }
  if (index == 0) throw app::Error(input + ": no frames");
  emit(true);
  if (file_out) file_out->commit();
  std::fprintf(stderr, "gabarit detect: %llu frame%s, %llu detection%s, %.0f us per frame (pyramid %u, %u rotations of %.2f deg%s)\n",
               static_cast<unsigned long long>(index), index == 1 ? "" : "s", static_cast<unsigned long long>(found),
               found == 1 ? "" : "s", micros / static_cast<double>(index), finder.geometry().factor, finder.geometry().rotations,
               finder.geometry().theta_step_deg, finder.geometry().orientation ? ", orientation channels" : ", position only");
  return 0;
}

}  // namespace gabarit::cli
