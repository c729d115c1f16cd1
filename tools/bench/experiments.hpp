// The thesis's synthetic experiments (section 6.2), re-measured: the trial
// generator, the estimators of Table 6.1, the wrong-frame grid of Figs.
// 6.16-6.19, and the stencil statistics of Figs. 6.20/6.26/6.27. No OpenCV
// here: the OpenCV peer lives in bench_main.cpp only.
//
// Protocol ("one-step"): every trial is independent. The object sits at a
// known previous position, moves by a random integer step within +-4 px per
// axis, the frame gets salt-and-pepper noise, and an estimator is asked for
// the new position from the previous one. A trial is wrong when the estimate
// is not the true pixel. Tracking errors therefore never cascade, and each
// grid point counts independent failures.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "gabarit/app/image_io.hpp"
#include "gabarit/host/tables/model.hpp"
#include "gabarit/host/scenes/synth.hpp"
#include "gabarit/host/tables/table_analysis.hpp"
#include "gabarit/host/runs/tracking_run.hpp"
#include "gabarit/host/runs/voter_trials.hpp"
#include "gabarit/table_view.hpp"
#include "gabarit/tracker.hpp"

namespace gabarit::bench {

using app::GrayImage;
using host::Point;

// The trials and tables of the protocol above (gabarit/host/runs/voter_trials.hpp).
using host::kCellAxis;
using host::kMaxStep;
using host::make_shape;
using host::make_trials;
using host::Shape;
using host::shape_table;
using host::Trial;

class Estimator {
 public:
  virtual ~Estimator() = default;
  virtual std::string name() const = 0;
  virtual Point estimate(const Trial& trial) = 0;
};

// (a) cross-correlation with the rectangular template (the model's bounding
//     box) at every translation of the window;
std::unique_ptr<Estimator> rect_xcorr(const Shape& shape);
// (b) cross-correlation with the shape template (model points only);
std::unique_ptr<Estimator> shape_xcorr(const Shape& shape);
// (c) the exhaustive stencil estimator (thesis Algorithm 3): every cell
//     counts the feature pixels of its stencil, reading the frame directly;
std::unique_ptr<Estimator> exhaustive_stencil(const std::vector<std::byte>& table, std::size_t frame_stride);
// (d), (e) the bounded Hough transform (the kernel's track_step) with the
//     given table (full or decimated stencils) and voter.
std::unique_ptr<Estimator> hough(std::vector<std::byte> table, const std::string& name,
                                 app::VoterChoice voter = app::VoterChoice::kAuto);

struct GridRow {
  std::string shape;
  std::string policy;  // host::describe(the decimation policy)
  double noise = 0;
  double keep = 1;
  std::size_t frames = 0;
  std::size_t wrong = 0;
};
struct GridSpec {
  std::vector<double> noises;
  std::vector<double> keeps;
  // Decimation policies compared on the same trials (one by default).
  std::vector<host::DecimationPolicy> policies = {host::DecimationPolicy{}};
  std::size_t frames = 100;
  std::uint64_t seed = 1;
  unsigned threads = 1;
  std::function<void(std::size_t done, std::size_t total)> progress;
};
// Wrong frames of the Hough tracker for every shape x noise x policy x keep. Jobs run
// on `threads` threads; results do not depend on the thread count.
std::vector<GridRow> run_grid(const std::vector<Shape>& shapes, const GridSpec& spec);

// The small grid the regression test and its baseline use.
GridSpec regression_grid_spec();

struct Robustness {
  double mean = 0;  // over stencils of |S_U| - max_{V != U} |S_U ∩ S_V|
  std::int64_t min = 0;
};
Robustness stencil_robustness(const TableView& table);

// refs-per-pixel histogram: result[n] = ROI pixels listing n cells.
using host::refs_per_pixel;

}  // namespace gabarit::bench
