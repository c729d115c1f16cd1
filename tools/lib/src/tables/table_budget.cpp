#include "gabarit/host/tables/table_budget.hpp"

#include <algorithm>
#include <string>

#include "gabarit/app/error.hpp"
#include "gabarit/app/scratch.hpp"
#include "gabarit/deterministic_math.hpp"
#include "gabarit/host/tables/table_analysis.hpp"
#include "gabarit/host/runs/voter_trials.hpp"
#include "gabarit/table_view.hpp"
#include "gabarit/tracker.hpp"

namespace gabarit::host {
namespace {

// The keep ratios searched: from this up to 1 (Algorithm 2 keeps at least
// one reference per stencil however small keep is).
constexpr double kSmallestKeep = 1e-6;
constexpr int kBisectionSteps = 40;

TableView open_built(const std::vector<std::byte>& bytes) {
  TableView v;
  if (TableView::open(bytes, v) != Status::kOk) throw app::Error("internal error: a budget table does not validate");
  return v;
}

}  // namespace

std::vector<std::byte> build_table_to_budget(const ModelStack& model, const BuildOptions& options, const Budget& budget,
                                             BudgetReport& report) {
  if (budget.max_bytes == 0 && budget.max_references == 0 && budget.min_margin == 0)
    throw app::Error("budget: give a byte or reference budget, a margin, or both");
  const auto fits = [&](const std::vector<std::byte>& t) {
    return !t.empty() && (budget.max_bytes == 0 || t.size() <= budget.max_bytes) &&
           (budget.max_references == 0 || open_built(t).reference_count() <= budget.max_references);
  };
  const auto budget_text = [&] {
    std::string b;
    if (budget.max_bytes) b += "--max-bytes " + std::to_string(budget.max_bytes);
    if (budget.max_references) b += std::string(b.empty() ? "" : " and ") + "--max-references " + std::to_string(budget.max_references);
    return b;
  };
  report = {};
  BuildOptions base = options;
  base.keep = 1.0;  // the search sets it; options.keep is ignored
  Stencils stencils = compute_stencils(model, base);
  const auto build_at = [&](double keep) {
    BuildOptions o = base;
    o.keep = keep;
    o.progress = {};
    const CsrLists csr = assemble_csr(stencils, o);
    ++report.builds;
    if (csr.cells.empty()) return std::vector<std::byte>{};
    return serialise_table(model, o, stencils, csr);
  };
  const auto margin_of = [](const std::vector<std::byte>& bytes) { return overall_margin(open_built(bytes)); };

  double chosen = 1.0;
  std::vector<std::byte> table;
  if (budget.min_margin > 0) {
    table = build_at(1.0);
    const std::uint32_t full = margin_of(table);
    if (full < budget.min_margin) {
      throw app::Error("even the full table's margin of error is " + std::to_string(full) + " px, below --min-margin " +
                       std::to_string(budget.min_margin) + ": use a larger model or smaller cells");
    }
    // The smallest keep whose margin reaches the requirement: hi always meets it.
    double lo = kSmallestKeep, hi = 1.0;
    std::vector<std::byte> at_lo = build_at(lo);
    if (!at_lo.empty() && margin_of(at_lo) >= budget.min_margin) {
      hi = lo, table = std::move(at_lo);
    } else {
      for (int i = 0; i < kBisectionSteps && hi - lo > 1e-4 * hi; ++i) {
        const double mid = (lo + hi) / 2;
        std::vector<std::byte> t = build_at(mid);
        if (!t.empty() && margin_of(t) >= budget.min_margin) hi = mid, table = std::move(t);
        else lo = mid;
      }
    }
    chosen = hi;
    if ((budget.max_bytes || budget.max_references) && !fits(table)) {
      throw app::Error("the smallest table with a margin of error of at least " + std::to_string(budget.min_margin) + " px takes " +
                       std::to_string(table.size()) + " bytes and " + std::to_string(open_built(table).reference_count()) +
                       " references, above " + budget_text());
    }
  } else {
    table = build_at(1.0);
    if (!fits(table)) {
      std::vector<std::byte> smallest = build_at(kSmallestKeep);
      if (!fits(smallest)) {
        throw app::Error("the smallest table this model and space allow takes " + std::to_string(smallest.size()) + " bytes and " +
                         std::to_string(smallest.empty() ? 0 : open_built(smallest).reference_count()) + " references, above " +
                         budget_text() + ": use fewer cells, a smaller ROI, or leave the model images out (--no-model-images)");
      }
      // The largest keep that fits: lo always fits, hi never does. With one
      // budget the next keep is interpolated (regula falsi, kept a tenth of
      // the bracket away from its ends so it always shrinks): a table's
      // size is close to linear in keep, so a few builds reach the budget.
      // Stops once within 0.1% of it; with both budgets, bisection.
      const bool one_budget = (budget.max_bytes == 0) != (budget.max_references == 0);
      const auto measure = [&](const std::vector<std::byte>& t) {
        return budget.max_bytes ? static_cast<double>(t.size()) : static_cast<double>(open_built(t).reference_count());
      };
      const double limit = budget.max_bytes ? static_cast<double>(budget.max_bytes) : static_cast<double>(budget.max_references);
      double lo = kSmallestKeep, hi = 1.0, at_lo = measure(smallest), at_hi = measure(table);
      table = std::move(smallest);
      for (int i = 0; i < kBisectionSteps && hi - lo > 1e-5; ++i) {
        double mid = (lo + hi) / 2;
        if (one_budget && at_hi > at_lo) {
          const double guess = lo + (limit - at_lo) / (at_hi - at_lo) * (hi - lo);
          mid = std::clamp(guess, lo + 0.1 * (hi - lo), hi - 0.1 * (hi - lo));
        }
        std::vector<std::byte> t = build_at(mid);
        if (fits(t)) {
          lo = mid, at_lo = measure(t), table = std::move(t);
          if (one_budget && at_lo >= limit - limit / 1000) break;
        } else {
          hi = mid, at_hi = t.empty() ? at_hi : measure(t);
        }
      }
      chosen = lo;
    }
  }
  const TableView view = open_built(table);
  const TableAnalysis a = analyse_table(view);
  report.keep = chosen;
  report.bytes = table.size();
  report.references = view.reference_count();
  report.margin = a.overall_margin;
  report.margin_exact = a.exact;
  return table;
}

double measured_noise_tolerance(const std::vector<std::byte>& table, const std::vector<Point>& model_points, std::size_t trials,
                                std::uint64_t seed) {
  const TableView view = open_built(table);
  app::TrackerBuffers buffers(view, app::VoterChoice::kAuto);
  const Shape shape = make_shape("model", model_points);
  double reached = -1;
  for (int level = 0; level <= 25; ++level) {
    const double noise = 0.02 * level;
    for (const Trial& t : make_trials(shape, noise, trials, seed + static_cast<std::uint64_t>(level))) {
      StepResult r;
      const Pose previous{static_cast<float>(t.previous.x), static_cast<float>(t.previous.y), 0, 0};
      if (track_step(view, {table_format::DetectorKind::kBinary, 0}, t.frame.view(), previous, buffers.scratch(), r) != Status::kOk)
        throw app::Error("internal error: track_step failed");
      if (round_to_int(r.pose.x) != t.truth.x || round_to_int(r.pose.y) != t.truth.y) return reached;
    }
    reached = noise;
  }
  return reached;
}

}  // namespace gabarit::host
