// What a table can withstand, computed from its lists (gabarit tables
// analyse; the budgets of tables build). The thesis's chapter 4-5 notions,
// as this project computes them:
//
// Margin of error of a stencil (Definitions 3-4, eq. 5.5-5.6). The object
// sits at the centre of cell T with nothing else in the ROI; its feature
// pixels M vote. Each ROI pixel flipped (a feature added where there was
// none, by clutter; or removed, by occlusion) moves the votes. The margin of
// error of T is the fewest flips after which another cell C ranks at least
// as high as T (the voter's rule: votes / stencil size, ties to the lower
// index), over every C. With a = |S_T|, b = |S_C| (decimated stencils) and
// D = votes(T) b - votes(C) a, a flip changes D by a fixed amount per kind
// of pixel: a feature added in S_C outside S_T lowers D by a; one removed in
// S_T outside S_C lowers it by b; one removed in both by b - a; one added in
// both by a - b. Taking the largest changes first is optimal (each flip costs
// one), so the margin is exact for the model at the cell's centre. For
// 1-pixel translation cells (integer centres, no rotation) that pose is the
// cell's only transformation, and the margin is the cell's margin of error;
// elsewhere it is an estimate at the centre (a pose off-centre covers other
// pixels), reported as such.
// The estimator's margin of error is the minimum over cells: up to that many
// flipped pixels anywhere in the ROI, no frame of the (centred) object is
// answered wrong.
//
// Robustness indicators (Figs. 6.26-6.27): per stencil, its size minus its
// largest overlap with another stencil, |S_T| - max_C |S_T n S_C|.
//
// Characterising value (Definition 1, eq. 4.3-4.4). A reduced template R, a
// subset of the model M, is unambiguous when no other transformation tau of
// the space places all of R on M; chi(R) = min over tau != id of
// |tau(R) \ M|, the points that land off the model under the worst other
// transformation (R is unambiguous when chi(R) >= 1). Over translations it
// equals the margin of error of an estimator built from R alone with the
// whole model in the image. Sampled per subset size.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "gabarit/host/tables/model.hpp"
#include "gabarit/table_view.hpp"

namespace gabarit::host {

struct StencilMargin {
  std::uint32_t cell = 0;
  std::uint32_t stencil_size = 0;
  std::uint32_t margin = 0;    // fewest flipped pixels that make `rival` rank at least as high
  std::uint32_t rival = 0;     // the cell that does
  std::int64_t robustness = 0; // |S| - the largest overlap with another stencil
};

struct TableAnalysis {
  bool exact = false;  // 1-pixel translation cells: margins exact, not estimates at the centre
  std::vector<StencilMargin> stencils;  // one per cell analysed, in cell order
  std::uint32_t overall_margin = 0;     // the minimum
  std::uint32_t weakest_cell = 0;
  double mean_margin = 0;
  double robustness_mean = 0;
  std::int64_t robustness_min = 0;
  std::vector<std::uint64_t> pixels_with;  // [n] = ROI pixels listing n cells
};

// Every cell's margin (progress(done, total) now and then). O(sum over
// pixels of |list|^2 + cells^2).
TableAnalysis analyse_table(const TableView& table, const std::function<void(std::size_t, std::size_t)>& progress = {});

// The estimator's margin of error alone (what tables build's budgets ask).
std::uint32_t overall_margin(const TableView& table);

// refs-per-pixel histogram: result[n] = ROI pixels listing n cells.
std::vector<std::uint64_t> refs_per_pixel(const TableView& table);

struct Characterisation {
  std::uint32_t size = 0;       // points in the subsets
  std::uint32_t samples = 0;
  double unambiguous = 0;       // fraction of the sampled subsets with chi >= 1
  double mean_chi = 0;
  std::uint32_t min_chi = 0, max_chi = 0;
};
// chi(R) over the transformations `shifts` (translations; the identity, if
// present, is skipped). Points are integer pixels.
std::uint32_t characterising_value(const std::vector<Point>& model, const std::vector<Point>& subset,
                                   const std::vector<Point>& shifts);
// The table's translations (cell centres of depth 0, rotation ignored when
// the space has none) as the shifts above.
std::vector<Point> table_shifts(const TableView& table);
// Sampled per size (the sizes given), `samples` random subsets each, deterministic per seed.
std::vector<Characterisation> characterise(const std::vector<Point>& model, const std::vector<Point>& shifts,
                                           const std::vector<std::uint32_t>& sizes, std::uint32_t samples, std::uint64_t seed);

// JSON of an analysis (with the histogram's cumulative and vote-weighted
// columns, Fig. 6.20) and its characterisation.
std::string analysis_json(const TableView& table, const TableAnalysis& analysis, const std::vector<Characterisation>& chars);
// SVG: the weakest stencil's pixels coloured by how many stencils list each
// (an overlap map, Figs. 6.22-6.25), and margins per stencil.
std::string overlap_map_svg(const TableView& table, std::uint32_t cell);
std::string margins_svg(const TableAnalysis& analysis);

}  // namespace gabarit::host
