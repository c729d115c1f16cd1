// gabarit tables build | inspect
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <iostream>

#include "gabarit/app/args.hpp"
#include "commands.hpp"
#include "gabarit/host/hdl_export.hpp"
#include "gabarit/app/files.hpp"
#include "gabarit/host/model.hpp"
#include "gabarit/host/table_builder.hpp"
#include "gabarit/host/table_inspect.hpp"
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

int tables_build(const std::vector<std::string>& argv) {
  app::Args args("tables build", "(--model IMG.pgm [IMG.pgm ...] | --model-points PTS.csv) --x MIN:MAX:CELLS --y MIN:MAX:CELLS [options] -o OUT",
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
             {"--decimation", "overlap|uniform", "which references go: the most overlapped first (the thesis's, default)\n"
              "                          or each with the same probability (for coarse recovery tables at a few percent)"},
             {"--translations", "inside|enclosing", "integer translations of a cell with non-integer bounds: those inside\n"
              "                          it, else the closest (default), or the smallest enclosing range (docs/tracking.md)"},
             {"--seed", "N", "decimation seed (default 1)"},
             {"--binary", "", "binary detector: a non-zero pixel is a feature (model images and frames)"},
             {"--detector", "canny|gradient-rows", "edge detector for grey images (default canny: non-maximum suppression\n"
              "                          and a double threshold, threshold/2..threshold; gradient-rows: the thesis's fast one,\n"
              "                          which keeps one pixel per run along a row and so misses edges near horizontal)"},
             {"--no-model-images", "", "leave the model images out of the table (format 1.0; the tracker then has no\n"
              "                          focus stack of its own: depth from the stencils, or gabarit track --focus-stack)"},
             {"--threshold", "N", "gradient detector threshold 1..2040 (default: a quarter of the model's strongest edge)"},
             {"-o", "OUT", "output table file", false, true}},
            "IMG.pgm");
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

  host::BuildOptions bo;
  bo.store_model_images = !args.has("--no-model-images");
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
  if (const std::string d = args.get_or("--decimation", "overlap"); d == "uniform") {
    bo.decimation = host::Decimation::kUniform;
  } else if (d != "overlap") {
    throw app::UsageError("--decimation '" + d + "': want overlap or uniform");
  }
  if (isatty(STDERR_FILENO)) {
    bo.progress = [](std::size_t done, std::size_t total) {
      std::fprintf(stderr, "\rstencils: %zu/%zu cells", done, total);
      if (done == total) std::fputc('\n', stderr);
    };
  }
  const std::vector<std::byte> bytes = host::build_table(model, bo);
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
  host::HdlCapacities cap;
  cap.cells = static_cast<std::uint32_t>(args.integer("--cells", 0, 1, table_format::kMaxCells));
  cap.pixels = static_cast<std::uint32_t>(args.integer("--pixels", 0, 1, table_format::kMaxRoiPixels));
  cap.refs_per_lane = static_cast<std::uint32_t>(args.integer("--refs-per-lane", 0, 1, table_format::kMaxReferences));
  cap.range_count = static_cast<std::uint32_t>(args.integer("--range-count", 0, 1, table_format::kMaxCells));
  std::fprintf(stderr, "%s\n", host::write_hdl_export(host::hdl_layout(view, lanes), args.get("--out"), cap).c_str());
  return 0;
}

}  // namespace gabarit::cli
