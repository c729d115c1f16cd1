// Builds a table (docs/table-format.md) from a model and a state space: one
// stencil per cell, the ROI that holds them all, decimation, and the
// pixel -> cells lists in compressed-sparse-row form. Same inputs and seed,
// same bytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "gabarit/host/decimation.hpp"
#include "gabarit/host/model.hpp"
#include "gabarit/host/stencil.hpp"
#include "gabarit/host/state_space.hpp"

namespace gabarit::host {

struct BuildOptions {
  StateSpace space;      // space.depths is taken from the model
  double keep = 1.0;     // fraction of references kept by decimation
  Decimation decimation = Decimation::kOverlap;
  TranslationPolicy translations = TranslationPolicy::kInsideElseClosest;
  std::uint64_t seed = 1;
  // Called now and then with (cells done, cells total) while stencils are built.
  std::function<void(std::size_t, std::size_t)> progress;
};

std::vector<std::byte> build_table(const ModelStack& model, const BuildOptions& options);

}  // namespace gabarit::host
