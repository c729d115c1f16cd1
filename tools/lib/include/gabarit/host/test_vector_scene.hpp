// The scene behind the cross-target test vectors (`gabarit vectors`): a
// ~1000-feature 4-DOF model (x, y, theta, focus-stack depth) moving through a
// short noisy sequence, the table built for it, and the host's tracking
// results recorded frame by frame (platform/common/.../test_vectors.hpp).
// The firmware embeds the same files, so the defaults are sized for an
// STM32H7-class part (2 MiB flash, 512 KiB RAM) with the table decimated.
#pragma once

#include <cstdint>
#include <string>

namespace gabarit::host {

struct VectorSceneOptions {
  std::uint32_t model_points = 1000;  // approximate feature count of depth 0
  std::uint16_t depths = 4;           // focus-stack images (each a slightly larger model)
  std::uint32_t frames = 8;
  double keep = 0.2;                  // decimation: fraction of references kept
  double noise = 0.02;                // salt-and-pepper rate
  std::uint64_t seed = 1;
};

struct VectorSceneSummary {
  std::size_t model_points = 0;       // depth 0
  std::size_t table_bytes = 0;
  std::size_t vector_bytes = 0;
  std::uint32_t cells = 0;
  std::uint32_t width = 0, height = 0;
  std::uint32_t frames_on_truth = 0;  // frames within 1.5 px and 1.5 deg of the truth, depth exact
};

// Writes DIR/table.gbt and DIR/vectors.gbv. Same options, same bytes.
VectorSceneSummary write_test_vectors(const VectorSceneOptions& options, const std::string& dir);

}  // namespace gabarit::host
