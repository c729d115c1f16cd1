// gabarit tables build | inspect
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <cstdio>
#include <iostream>

#include "gabarit/app/args.hpp"
#include "commands.hpp"
#include "gabarit/app/hdl_export.hpp"
#include "gabarit/app/files.hpp"
#include "gabarit/host/tables/model.hpp"
#include "gabarit/app/svg_plot.hpp"
#include "gabarit/host/tables/table_analysis.hpp"
#include "gabarit/host/tables/table_budget.hpp"
#include "gabarit/host/tables/table_builder.hpp"
#include "gabarit/host/tables/template_reduction.hpp"
#include "gabarit/host/tables/table_inspect.hpp"
#include "gabarit/features.hpp"
#include "gabarit/table_view.hpp"

namespace gabarit::cli {
namespace {

// A malformed axis is bad usage (exit 2), not a failed build.
Axis axis_argument(const app::Args& args, const std::string& name, const std::string& fallback) {
  try {
    return host::parse_axis(args.get_or(name, fallback), name);
  } catch (const app::UsageError&) {
    throw;
  } catch (const app::Error& e) {
    throw app::UsageError(e.what());
  }
}

}  // namespace

namespace {

app::Args declare_tables_build() {
  return app::Args("tables build", "(--model IMG.pgm [IMG.pgm ...] | --model-points PTS.csv) --x MIN:MAX:CELLS --y MIN:MAX:CELLS [options] -o OUT",
                   "Builds a stencil look-up table (docs/table-format.md) for a model over a bounded motion space.\n"
                   "Several --model images form a focus stack ordered by depth index. Same inputs and seed give\n"
                   "byte-identical output.",
                   {{"--model", "IMG.pgm", "model image (repeat for a focus stack, in depth order)", true},
                    {"--model-points", "PTS.csv", "integer x,y feature positions relative to the reference point"},
                    {"--ref", "X,Y", "reference point in model-image pixels (default: floor(w/2),floor(h/2))"},
                    {"--x", "MIN:MAX:CELLS", "x translations: CELLS cells with centres evenly from MIN to MAX", false, true},
                    {"--y", "MIN:MAX:CELLS", "y translations, as --x", false, true},
                    {"--theta", "MIN:MAX:CELLS", "rotation in degrees, as --x (default 0:0:1)"},
                    {"--keep", "RATIO", "fraction of stencil references kept by decimation, (0,1] (default 1)"},
                    {"--decimation", "stencil|global|uniform", "which references go (docs/experiments.md, \"Decimation\"): stencil by\n"
                     "                          stencil, the most overlapped pixels first (the thesis's Algorithm 2, default); in one\n"
                     "                          global pass by overlap; or each with the same probability"},
                    {"--weight", "identity|power:K|greedy|rival", "stencil decimation: removal probability against overlap n: n\n"
                     "                          (default), n^K (K = 2, 3), always the most overlapped pixel, or by how alike\n"
                     "                          the stencils sharing the pixel are"},
                    {"--most-overlapping", "", "stencil decimation: remove first the pixels shared with the most overlapping stencil"},
                    {"--spread", "", "stencil decimation: spread removals evenly (a neighbourhood map)"},
                    {"--min-area", "N", "stencil decimation: keep at least N references per stencil (default 0: keep x size, at least 1)"},
                    {"--max-bytes", "N", "build to a budget instead of --keep: the table keeping the most references that fits\n"
                     "                          in N bytes (a flash or BRAM budget); reports its margin of error"},
                    {"--max-references", "N", "with or instead of --max-bytes: at most N references (a hardware voter's reference\n"
                     "                          memory, hdl/)"},
                    {"--min-margin", "K", "build to a margin instead of --keep: the smallest table whose margin of error (gabarit\n"
                     "                          tables analyse) is at least K pixels; with --max-bytes, refused if it does not fit"},
                    {"--reduce-template", "K", "template reduction first (docs/experiments.md): keep the fewest model points whose\n"
                     "                          characterising value (every other translation puts >= K of them off the model) is\n"
                     "                          at least K; translation spaces only (no --theta)"},
                    {"--reduce-order", "greedy|random", "--reduce-template's search: least useful points first (default), or the best of\n"
                     "                          --reduce-restarts seeded random orders (default 16)"},
                    {"--reduce-restarts", "N", "random orders tried by --reduce-order random"},
                    {"--offsets", "compact|wide", "pixel offsets: compact (format 1.2, default, when smaller) or one u32 per pixel\n"
                     "                          (format 1.0/1.1, for readers older than 1.2)"},
                    {"--translations", "inside|enclosing", "integer translations of a cell with non-integer bounds: those inside\n"
                     "                          it, else the closest (default), or the smallest enclosing range (docs/tracking.md)"},
                    {"--seed", "N", "decimation seed (default 1)"},
                    {"--binary", "", "binary detector: a non-zero pixel is a feature (model images and frames)"},
                    {"--detector", "canny|gradient-rows", "edge detector for grey images (default canny: non-maximum suppression\n"
                     "                          and a double threshold, threshold/2..threshold; gradient-rows: the thesis's fast one,\n"
                     "                          which keeps one pixel per run along a row and so misses edges near horizontal)"},
                    {"--orientation-channels", "N", "split each ROI pixel into N channels of edge orientation, 2, 4, 8 or 16 (format\n"
                     "                          1.3): a feature votes only the cells whose stencil covers it with a model\n"
                     "                          point of its orientation (docs/table-format.md); needs --model images and a\n"
                     "                          gradient detector; 0 (default): position only"},
                    {"--no-model-images", "", "leave the model images out of the table (format 1.0; the tracker then has no\n"
                     "                          focus stack of its own: depth from the stencils, or gabarit track --focus-stack)"},
                    {"--threshold", "N", "gradient detector threshold 1..2040 (default: a quarter of the model's strongest edge)"},
                    {"-o", "OUT", "output table file", false, true}},
                   "IMG.pgm");
}

// The model: images (a focus stack) or a points CSV with the detector frames need.
host::ModelStack read_model(const app::Args& args, const std::vector<std::string>& images, bool has_images) {
  host::ModelStack model;
  if (has_images) {
    host::ImageModelOptions mo;
    mo.binary = args.has("--binary");
    const std::string detector = args.get_or("--detector", "canny");
    if (detector != "gradient-rows" && detector != "canny") throw app::UsageError("--detector '" + detector + "': want gradient-rows or canny");
    if (mo.binary && args.has("--detector")) throw app::UsageError("--detector has no meaning with --binary");
    mo.canny = detector == "canny";
    mo.threshold = static_cast<int>(args.integer("--threshold", -1, 1, kMaxGradientMagnitude));
    if (mo.binary && args.has("--threshold")) throw app::UsageError("--threshold has no meaning with --binary");
    if (args.has("--ref")) {
      const auto ref = app::parse_number_list(args.get("--ref"), "--ref", 2, 2);
      if (ref[0] != std::floor(ref[0]) || ref[1] != std::floor(ref[1]) || std::fabs(ref[0]) > 16384 || std::fabs(ref[1]) > 16384) {
        throw app::UsageError("--ref: X,Y must be integer pixel positions");
      }
      mo.has_ref = true;
      mo.ref_x = static_cast<std::int32_t>(ref[0]);
      mo.ref_y = static_cast<std::int32_t>(ref[1]);
    }
    model = host::model_from_images(images, mo);
  } else {
    if (args.has("--ref")) throw app::UsageError("--ref applies to --model images; point CSVs are already relative to it");
    model.depths.push_back(host::read_points_csv(args.get("--model-points")));
    if (args.has("--binary")) {
      model.detector.kind = table_format::DetectorKind::kBinary;
      if (args.has("--threshold")) throw app::UsageError("--threshold has no meaning with --binary");
    } else if (args.has("--threshold")) {
      model.detector.kind = args.get_or("--detector", "canny") == "canny" ? table_format::DetectorKind::kCanny
                                                                               : table_format::DetectorKind::kGradientRows;
      model.detector.threshold = static_cast<std::uint16_t>(args.integer("--threshold", 1, 1, kMaxGradientMagnitude));
    } else {
      throw app::UsageError("--model-points: say which detector frames need: --binary or --threshold N");
    }
  }

  return model;
}

host::BuildOptions read_build_options(const app::Args& args, bool has_images) {
  host::BuildOptions bo;
  bo.store_model_images = !args.has("--no-model-images");
  bo.orientation_channels = static_cast<std::uint32_t>(args.integer("--orientation-channels", 0, 0, 16));
  if (bo.orientation_channels != 0 && !table_format::valid_orientation_channels(bo.orientation_channels))
    throw app::UsageError("--orientation-channels: want 2, 4, 8 or 16 (or 0 for none)");
  if (bo.orientation_channels != 0 && !has_images) throw app::UsageError("--orientation-channels needs --model images");
  if (!has_images && args.has("--no-model-images")) throw app::UsageError("--no-model-images applies to --model images");
  bo.space.x = axis_argument(args, "--x", "");
  bo.space.y = axis_argument(args, "--y", "");
  bo.space.theta = axis_argument(args, "--theta", "0:0:1");
  bo.keep = args.number("--keep", 1.0, 0.0, 1.0);
  if (!(bo.keep > 0)) throw app::UsageError("--keep must be above 0");
  bo.seed = static_cast<std::uint64_t>(args.integer("--seed", 1, 0, INT64_MAX));
  if (const std::string t = args.get_or("--translations", "inside"); t == "enclosing") {
    bo.translations = host::TranslationPolicy::kEnclosing;
  } else if (t != "inside") {
    throw app::UsageError("--translations '" + t + "': want inside or enclosing");
  }
  bo.decimation.method = host::parse_decimation(args.get_or("--decimation", "stencil"));
  if (args.has("--weight")) host::parse_removal_weight(args.get("--weight"), bo.decimation);
  bo.decimation.most_overlapping = args.has("--most-overlapping");
  bo.decimation.spread = args.has("--spread");
  bo.decimation.min_area = static_cast<std::uint32_t>(args.integer("--min-area", 0, 0, 1 << 24));
  if (isatty(STDERR_FILENO)) {
    bo.progress = [](std::size_t done, std::size_t total) {
      std::fprintf(stderr, "\rstencils: %zu/%zu cells", done, total);
      if (done == total) std::fputc('\n', stderr);
    };
  }
  if (const std::string offsets = args.get_or("--offsets", "compact"); offsets == "wide") {
    bo.compact_offsets = false;
  } else if (offsets != "compact") {
    throw app::UsageError("--offsets '" + offsets + "': want compact or wide");
  }
  return bo;
}

// --reduce-template: the fewest model points that keep every translation apart by K.
void reduce_template_if_asked(const app::Args& args, const host::BuildOptions& bo, host::ModelStack& model) {
  if (args.has("--reduce-template")) {
    if (bo.space.theta.cells != 1 || bo.space.theta.min != 0.0f)
      throw app::UsageError("--reduce-template works on translation spaces (leave --theta out)");
    const auto centres = [](const Axis& a) {
      std::vector<std::int32_t> c;
      for (std::uint32_t i = 0; i < a.cells; ++i) {
        const double v = a.cells == 1 ? a.min : a.min + (a.max - a.min) * i / (a.cells - 1);
        c.push_back(static_cast<std::int32_t>(std::lround(v)));
      }
      return c;
    };
    const auto k = static_cast<std::uint32_t>(args.integer("--reduce-template", 1, 1, 1 << 20));
    const std::string order = args.get_or("--reduce-order", "greedy");
    if (order != "greedy" && order != "random") throw app::UsageError("--reduce-order '" + order + "': want greedy or random");
    const auto restarts = static_cast<std::uint32_t>(args.integer("--reduce-restarts", 16, 1, 10000));
    const std::vector<host::Point> shifts = host::translation_differences(centres(bo.space.x), centres(bo.space.y));
    for (std::size_t d = 0; d < model.depths.size(); ++d) {
      const host::ReductionResult r = host::reduce_template(model.depths[d], shifts, k,
                                                            order == "greedy" ? host::ReductionOrder::kGreedy : host::ReductionOrder::kRandom,
                                                            restarts, bo.seed + d);
      std::fprintf(stderr, "template reduction: depth %zu, %zu -> %zu points, characterising value %u (the whole model's: %u)\n", d,
                   model.depths[d].size(), r.points.size(), r.characterising_value, r.full_value);
      model.depths[d] = r.points;
    }
  } else if (args.has("--reduce-order") || args.has("--reduce-restarts")) {
    throw app::UsageError("--reduce-order and --reduce-restarts go with --reduce-template");
  }
}

// The table: to a budget (--max-bytes, --max-references, --min-margin) or with --keep.
std::vector<std::byte> build_tables(const app::Args& args, const host::ModelStack& model, const host::BuildOptions& bo) {
  host::Budget budget;
  if (args.has("--max-bytes")) budget.max_bytes = static_cast<std::uint64_t>(args.integer("--max-bytes", 0, 1, table_format::kMaxTableBytes));
  if (args.has("--max-references"))
    budget.max_references = static_cast<std::uint32_t>(args.integer("--max-references", 0, 1, table_format::kMaxReferences));
  if (args.has("--min-margin")) budget.min_margin = static_cast<std::uint32_t>(args.integer("--min-margin", 0, 1, 1 << 24));
  const bool budgeted = budget.max_bytes > 0 || budget.max_references > 0 || budget.min_margin > 0;
  if (budgeted && args.has("--keep"))
    throw app::UsageError("--keep and a budget (--max-bytes, --max-references, --min-margin) exclude each other");
  std::vector<std::byte> bytes;
  if (budgeted) {
    host::BudgetReport report;
    std::fprintf(stderr, "searching the keep ratio for the budget...\n");
    bytes = host::build_table_to_budget(model, bo, budget, report);
    std::fprintf(stderr, "budget: keep %.4g%%, %zu bytes, %u references", report.keep * 100, report.bytes, report.references);
    if (budget.max_bytes) std::fprintf(stderr, " (%.1f%% of %llu)", 100.0 * static_cast<double>(report.bytes) / static_cast<double>(budget.max_bytes),
                                        static_cast<unsigned long long>(budget.max_bytes));
    std::fprintf(stderr, ", margin of error %u px (%s), %zu tables tried\n", report.margin,
                 report.margin_exact ? "exact: 1-pixel translation cells" : "estimated at the cell centres", report.builds);
    if (report.margin_exact && model.detector.kind == table_format::DetectorKind::kBinary && model.depths.size() == 1) {
      const double tolerance = host::measured_noise_tolerance(bytes, model.depths[0], 50, bo.seed);
      if (tolerance < 0) std::fprintf(stderr, "noise tolerance: wrong even without noise (50 one-step trials)\n");
      else std::fprintf(stderr, "noise tolerance: no wrong frame in 50 one-step trials per level up to %.0f%% salt-and-pepper\n", tolerance * 100);
    }
  } else {
    bytes = host::build_table(model, bo);
  }
  return bytes;
}

}  // namespace

int tables_build(const std::vector<std::string>& argv) {
  app::Args args = declare_tables_build();
  if (!args.parse(argv)) return 0;
  // `--model a.pgm b.pgm c.pgm`: images after the first are positionals.
  std::vector<std::string> images = args.all("--model");
  if (!args.positionals().empty() && images.empty()) {
    throw app::UsageError("unexpected argument '" + args.positionals()[0] + "' (model images follow --model)");
  }
  images.insert(images.end(), args.positionals().begin(), args.positionals().end());
  const bool has_images = args.has("--model");
  if (has_images == args.has("--model-points")) throw app::UsageError("give either --model or --model-points");
  {
    std::vector<std::string> inputs = images;
    if (args.has("--model-points")) inputs.push_back(args.get("--model-points"));
    app::refuse_same_file(args.get("-o"), "-o", inputs);
  }
  host::ModelStack model = read_model(args, images, has_images);
  const host::BuildOptions bo = read_build_options(args, has_images);
  reduce_template_if_asked(args, bo, model);
  const std::vector<std::byte> bytes = build_tables(args, model, bo);
  TableView view;
  if (const Status s = TableView::open(bytes, view); s != Status::kOk) {
    throw app::Error(std::string("internal error: built table does not validate: ") + status_name(s));
  }
  app::write_file(args.get("-o"), bytes);
  std::fprintf(stderr, "%s: %zu bytes, %u cells, %u references (%u-byte), ROI %ux%u\n", args.get("-o").c_str(), bytes.size(),
               view.cell_count(), view.reference_count(), unsigned{view.reference_bytes()}, unsigned{view.roi_width()},
               unsigned{view.roi_height()});
  return 0;
}

int tables_analyse(const std::vector<std::string>& argv) {
  app::Args args("tables analyse", "TABLE [-o ANALYSIS.json] [--plots DIR]",
                 "What the table withstands (docs/table-format.md, \"Analysis\"): every stencil's margin of error (the fewest\n"
                 "flipped ROI pixels that make another cell win; exact for 1-pixel translation cells, else estimated at\n"
                 "each cell's centre), the estimator's margin (the minimum), the robustness indicators (size minus the\n"
                 "largest overlap), the refs-per-pixel histogram with cumulative and vote-weighted columns, and the\n"
                 "characterising value of random subsets of the model's points. JSON to stdout or -o; SVG plots with --plots.",
                 {{"-o", "FILE", "write the JSON here instead of stdout"},
                  {"--plots", "DIR", "write DIR/overlap_map.svg (the weakest stencil) and DIR/margins.svg"},
                  {"--samples", "N", "random subsets per size for the characterising value (default 200; 0 skips it)"},
                  {"--seed", "N", "seed of those subsets (default 1)"}},
                 "TABLE");
  if (!args.parse(argv)) return 0;
  if (args.positionals().size() != 1) throw app::UsageError("give exactly one TABLE");
  const auto samples = static_cast<std::uint32_t>(args.integer("--samples", 200, 0, 100000));
  const auto seed = static_cast<std::uint64_t>(args.integer("--seed", 1, 0, INT64_MAX));
  const app::TableFile file(args.positionals()[0]);
  const TableView& view = file.view();
  std::function<void(std::size_t, std::size_t)> progress;
  if (isatty(STDERR_FILENO)) {
    progress = [](std::size_t done, std::size_t total) {
      std::fprintf(stderr, "\rmargins: %zu/%zu cells", done, total);
      if (done == total) std::fputc('\n', stderr);
    };
  }
  const host::TableAnalysis analysis = host::analyse_table(view, progress);
  std::vector<host::Characterisation> chars;
  if (samples > 0) {
    std::vector<host::Point> model;
    for (std::uint32_t i = 0; i < view.model_point_count(0); ++i) model.push_back({view.model_point(i).x, view.model_point(i).y});
    std::vector<std::uint32_t> sizes;
    for (std::uint32_t k = 1; k < model.size(); k = k < 4 ? k + 1 : k * 2) sizes.push_back(k);
    sizes.push_back(static_cast<std::uint32_t>(model.size()));
    chars = host::characterise(model, host::table_shifts(view), sizes, samples, seed);
  }
  const std::string json = host::analysis_json(view, analysis, chars);
  if (args.has("--plots")) {
    const std::string dir = args.get("--plots");
    std::filesystem::create_directories(dir);
    app::svg::write(dir + "/overlap_map.svg", host::overlap_map_svg(view, analysis.weakest_cell));
    app::svg::write(dir + "/margins.svg", host::margins_svg(analysis));
  }
  if (args.has("-o")) app::write_file(args.get("-o"), json);
  else std::cout << json;
  std::fprintf(stderr, "margin of error %u px (%s; weakest cell %u), mean %.1f; robustness mean %.1f, min %lld\n", analysis.overall_margin,
               analysis.exact ? "exact" : "estimated at cell centres", analysis.weakest_cell, analysis.mean_margin, analysis.robustness_mean,
               static_cast<long long>(analysis.robustness_min));
  return 0;
}

int tables_inspect(const std::vector<std::string>& argv) {
  app::Args args("tables inspect", "TABLE", "Validates a table and prints it as JSON: sizes, space, refs-per-pixel histogram, stencil sizes.",
            {}, "TABLE");
  if (!args.parse(argv)) return 0;
  if (args.positionals().size() != 1) throw app::UsageError("give exactly one TABLE");
  const std::string& path = args.positionals()[0];
  const app::TableFile file(path);
  const TableView& view = file.view();
  std::cout << host::inspect_json(view);
  return 0;
}

}  // namespace gabarit::cli

namespace gabarit::cli {

int tables_export_hdl(const std::vector<std::string>& argv) {
  app::Args args("tables export-hdl", "TABLE --out DIR [--lanes N]",
            "Writes the hardware voter's memory images ($readmemh: offsets.mem, refs_<k>.mem, sizes_<k>.mem) and\n"
            "a SystemVerilog package with the table's sizes (gabarit_table_pkg.sv) for hdl/rtl/gbt_voter_table.sv.",
            {{"--out", "DIR", "output directory", false, true},
             {"--lanes", "N", "voting lanes: 1, 2, 4 or 8 (default 1)"},
             {"--cells", "N", "voter CellCapacity the images are for (default: the table's cell count)"},
             {"--pixels", "N", "voter PixelCapacity (default: the table's ROI pixels)"},
             {"--refs-per-lane", "N", "voter RefsPerLane (default: the table's largest lane)"},
             {"--range-count", "N", "voter MaxRangeCount: references of one pixel in one lane (default: all the\n"
                                    "lane's cells); a smaller one narrows the offsets words"}},
            "TABLE");
  if (!args.parse(argv)) return 0;
  if (args.positionals().size() != 1) throw app::UsageError("give exactly one TABLE");
  const auto lanes = static_cast<std::uint32_t>(args.integer("--lanes", 1, 1, 8));
  if (lanes != 1 && lanes != 2 && lanes != 4 && lanes != 8) throw app::UsageError("--lanes must be 1, 2, 4 or 8");
  const std::string& path = args.positionals()[0];
  const app::TableFile file(path);
  const TableView& view = file.view();
  app::HdlCapacities cap;
  cap.cells = static_cast<std::uint32_t>(args.integer("--cells", 0, 1, table_format::kMaxCells));
  cap.pixels = static_cast<std::uint32_t>(args.integer("--pixels", 0, 1, table_format::kMaxRoiPixels));
  cap.refs_per_lane = static_cast<std::uint32_t>(args.integer("--refs-per-lane", 0, 1, table_format::kMaxReferences));
  cap.range_count = static_cast<std::uint32_t>(args.integer("--range-count", 0, 1, table_format::kMaxCells));
  std::fprintf(stderr, "%s\n", app::write_hdl_export(app::hdl_layout(view, lanes), args.get("--out"), cap).c_str());
  return 0;
}

}  // namespace gabarit::cli
