// Tables built to a budget (tables build --max-bytes / --min-margin): the
// thesis's open "automatic stop criterion" for decimation. The stencils are
// computed once; the keep ratio is then searched by bisection (decimation
// and serialisation only), so
//   max_bytes   gives the table with the most references kept (the most
//               robust, margins growing with what is kept) that fits in
//               max_bytes (and max_references, a hardware voter's
//               reference memory, when given), and
//   min_margin  gives the smallest table whose estimator margin of error
//               (table_analysis.hpp) is at least min_margin pixels.
// Both together: the smallest table meeting the margin, refused if it does
// not fit the bytes. The report says what was reached; the search is
// deterministic (same inputs, same table).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "gabarit/host/tables/model.hpp"
#include "gabarit/host/tables/table_builder.hpp"

namespace gabarit::host {

struct Budget {
  std::uint64_t max_bytes = 0;       // 0: no byte budget
  std::uint32_t max_references = 0;  // 0: no reference budget (a voter's reference RAM, hdl/)
  std::uint32_t min_margin = 0;      // 0: no margin requirement
};

struct BudgetReport {
  double keep = 1;            // the keep ratio chosen (BuildOptions::keep is ignored)
  std::size_t bytes = 0;
  std::uint32_t references = 0;
  std::uint32_t margin = 0;   // the table's estimator margin of error
  bool margin_exact = false;  // 1-pixel translation cells (else estimated at cell centres)
  std::size_t builds = 0;     // tables serialised by the search
};

// Throws app::Error when no keep ratio meets the budget, naming the closest
// (the smallest table's bytes, or the full table's margin).
std::vector<std::byte> build_table_to_budget(const ModelStack& model, const BuildOptions& options, const Budget& budget,
                                             BudgetReport& report);

// The highest salt-and-pepper rate (0 to 50% in 2% steps) at which `trials`
// one-step trials of a binary point model (voter_trials.hpp) all come out on
// the true pixel; -1 when even 0% fails. Only for tables of 1-pixel
// translation cells over the thesis's +-5 px window.
double measured_noise_tolerance(const std::vector<std::byte>& table, const std::vector<Point>& model_points, std::size_t trials,
                                std::uint64_t seed);

}  // namespace gabarit::host
