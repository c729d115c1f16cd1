// Re-acquisition near the last sighting by intensity: a lost target that
// reappears close to where it was hidden, over a texture whose edges drown
// its own (a dark silhouette on brick), is found neither by the detector
// (edge orientations: the brick's win) nor by the vote (the brick's edge
// pixels fill every stencil), but the model image still correlates there.
// So, each lost frame, the session may score a grid of poses around the
// last sighting with the particle filter's intensity measure (its sparse,
// fixed list of model samples: about a microsecond a pose) and hand the
// best to its verification, which refines it and takes it only where it
// correlates as a tracked frame must (tracking_session.hpp). Every pose is
// screened on a quarter of the samples, and the best few are scored again
// on all of them (a finer grid of angles for the same time).
// The grid: positions every step_px within the reach (the table's x/y
// bound per frame times the frames since the sighting, at most
// max_radius_px), angles every step_deg within the table's angle bound
// times those frames (at most max_turn_deg), at the sighting's depth.
// No heap: the measures' lists live in the object (about 17 KB).
#pragma once

#include <cstdint>

#include "gabarit/image_view.hpp"
#include "gabarit/particle_measures.hpp"
#include "gabarit/pose.hpp"
#include "gabarit/recovery_search.hpp"
#include "gabarit/table_view.hpp"

namespace gabarit {

inline constexpr std::uint32_t kMaxScanKept = 32;

struct IntensityScanOptions {
  float step_px = 6.0f;         // the grid's spacing along x and y
  float step_deg = 4.0f;        // and in angle
  float max_radius_px = 44.0f;  // the reach's cap (the grid search's, kSearchRings steps of +-5 px)
  float max_turn_deg = 24.0f;   // the angles' cap either side of the sighting's
  std::uint32_t screen_samples = 64;                 // every pose scored on this many samples first,
  std::uint32_t kept = 16;                           // the best this many (1..kMaxScanKept) of them
  std::uint32_t samples = kIntensityMeasureSamples;  // again on this many
};
// Steps and caps finite, positive and at most 1000 (px or degrees); both
// sample counts 16..kMaxIntensityMeasureSamples; kept 1..kMaxScanKept.
bool valid(const IntensityScanOptions& options) noexcept;

struct IntensityScanResult {
  bool scored = false;  // a pose of the grid scored above 0
  Pose best;
  float score = 0.0f;        // its correlation (0..1)
  std::uint32_t poses = 0;   // poses of the grid (each screened)
  std::uint64_t work = 0;    // samples read: the screen's and the kept poses'
};

class IntensityScan {
 public:
  // Static storage a firmware fills once it knows its table: a scan of
  // nothing until reset (every byte zero, so .bss).
  constexpr IntensityScan() noexcept = default;
  // `stack` (its images must outlive the scan) is the table's focus stack;
  // the bounds per frame are the table's.
  void reset(const TableView& table, const FocusStack& stack, const IntensityScanOptions& options) noexcept;
  // One lost frame: the grid around `last` (see above). kInvalidArgument for
  // an invalid frame or a scan never reset with a valid stack.
  [[nodiscard]] Status run(const ImageView& frame, const LastSighting& last, IntensityScanResult& out) noexcept;

 private:
  IntensityCorrelationMeasure screen_, measure_;
  IntensityScanOptions options_{};
  float per_frame_px_ = 0.0f, per_frame_deg_ = 0.0f;
  bool ready_ = false;
};

}  // namespace gabarit
