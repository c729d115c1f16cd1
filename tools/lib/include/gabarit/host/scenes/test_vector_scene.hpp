// The scene behind the cross-target test vectors (`gabarit vectors`): a
// ~1000-feature 4-DOF model (x, y, theta, focus-stack depth) moving through a
// short noisy sequence, the table built for it, and the host's tracking
// results recorded frame by frame (app/include/gabarit/app/test_vectors.hpp):
// track_step's (vectors.gbv), and a TrackingSession's over a longer sequence
// in which the object is hidden for a while, with the model images as its
// focus stack (session.gbs), and the particle tracker's over the session's
// sequence: with the edge measure on that table (particle.gbp), and with the
// intensity measure on the same model's table with images
// (particle-table.gbt, particle-intensity.gbp).
// The firmware embeds the same files, so the defaults are sized for an
// STM32H7-class part (2 MiB flash, 512 KiB RAM): the table is built to a
// budget of half the flash (table_budget.hpp), the other half holding the
// code and one vector file.
#pragma once

#include <cstdint>
#include <string>

namespace gabarit::host {

struct VectorSceneOptions {
  std::uint32_t model_points = 1000;  // approximate feature count of depth 0
  std::uint16_t depths = 4;           // focus-stack images (each a slightly larger model)
  std::uint32_t frames = 8;
  std::uint64_t table_budget_bytes = 1u << 20;  // the table: the most references that fit
  double keep = 0;                    // > 0: this fraction of references instead of the budget
  double noise = 0.02;                // salt-and-pepper rate
  std::uint64_t seed = 1;
  // The session's sequence: session_frames frames, the object hidden from
  // hidden_from for hidden_frames (long enough for the session to become
  // lost and search).
  std::uint32_t session_frames = 16;
  std::uint32_t hidden_from = 4;
  std::uint32_t hidden_frames = 8;
  std::uint32_t particles = 1000;  // the particle tracker's (particle.gbp), 1..kMaxVectorParticles
  // particle-table.gbt: the same model with its images, to this budget
  // (with `keep`, that keep ratio instead).
  std::uint64_t particle_table_budget_bytes = 256u << 10;
};

struct VectorSceneSummary {
  std::size_t model_points = 0;       // depth 0
  std::size_t table_bytes = 0;
  double keep = 0;                    // the fraction of references the table kept
  std::uint32_t margin = 0;           // its margin of error (estimated at cell centres)
  std::size_t vector_bytes = 0;
  std::uint32_t cells = 0;
  std::uint32_t width = 0, height = 0;
  std::uint32_t frames_on_truth = 0;  // frames within 1.5 px and 1.5 deg of the truth, depth exact
  std::size_t session_bytes = 0;
  std::uint32_t session_lost_frames = 0;  // frames the session reported lost
  bool session_reacquired = false;        // it found the object again after the occlusion
  std::size_t particle_bytes = 0;
  std::uint32_t particle_frames_tracking = 0;  // frames the particle tracker reported tracking
  std::size_t particle_table_bytes = 0;
  std::uint32_t particle_intensity_frames_tracking = 0;  // the same with the intensity measure
};

// Writes DIR/table.gbt, DIR/vectors.gbv, DIR/session.gbs, DIR/session-screened.gbs,
// DIR/particle.gbp, DIR/particle-table.gbt and DIR/particle-intensity.gbp.
// Same options, same bytes.
VectorSceneSummary write_test_vectors(const VectorSceneOptions& options, const std::string& dir);

}  // namespace gabarit::host
