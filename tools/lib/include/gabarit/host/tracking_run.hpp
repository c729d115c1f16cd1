// Runs the kernel's tracker over a frame source, one frame at a time, timing
// only the kernel's work per frame (features + voting + pose update; not
// decoding or I/O).
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "gabarit/app/image_io.hpp"
#include "gabarit/app/pose_row.hpp"
#include "gabarit/app/scratch.hpp"
#include "gabarit/host/particle_run.hpp"
#include "gabarit/model_finder.hpp"
#include "gabarit/particle_recovery.hpp"
#include "gabarit/table_view.hpp"
#include "gabarit/tracker.hpp"
#include "gabarit/tracking_session.hpp"

namespace gabarit::host {

struct TimingSummary {
  std::size_t frames = 0;
  double mean = 0, p50 = 0, p99 = 0, max = 0;  // microseconds
};
TimingSummary summarise_timing(std::vector<double> micros);

struct TrackingOptions {
  std::optional<Detector> detector;        // overrides the table's detector
  app::VoterChoice voter = app::VoterChoice::kAuto;
  SessionOptions session = kPlainSession;  // motion filter, refinement, recovery
  const TableView* coarse = nullptr;       // the recovery search's table (else the fine one)
  // Threads voting each frame (parallel_voter.hpp, features split). Above 1,
  // only for the plain loop (kPlainSession, no coarse table); the rows are
  // the same bytes as with one thread.
  unsigned threads = 1;
  // The focus stack's images (one per depth, the table's model images): when
  // given, each frame's depth is chosen by intensity at the tracked pose
  // (depth_by_intensity.hpp). Only with a session (not the --threads loop).
  std::vector<app::GrayImage> focus_stack;
  // Without focus_stack: use the model images the table carries (format
  // 1.1), if any, with a session that has the motion filter.
  bool table_focus_stack = false;
  // The grid search detects features once per lost frame (scratch for it,
  // SessionScratch::search_features); false: a full track_step per placement,
  // as before (kept for the bench's comparison).
  bool shared_search_features = true;
  // Re-acquire with the particle filter over the whole frame
  // (particle_recovery.hpp) instead of the grid search; with recovery on.
  bool particle_recovery = false;
  ParticleRunOptions particles = recovery_particles();
  ParticleRecoveryOptions particle_recovery_options;
  // Re-acquire by detection over the whole frame (model_finder.hpp) instead
  // of the grid search; with recovery on. Takes precedence over particles.
  bool detection_recovery = false;
  // No initial pose: the first frames are searched by detection until the
  // model is found (rows before are lost, at 0,0), then the session starts there.
  bool detect_first = false;
  FinderOptions finder;
  std::uint32_t detection_interval = 1;  // with detection_recovery: detect every n-th lost frame
  static ParticleRunOptions recovery_particles() {
    ParticleRunOptions o;
    o.edge_tolerance = 0;
    return o;
  }
};

// Calls on_row for every frame. row.step is the frame's vote with the
// session's decision in pose, state and score (tracking_session.hpp).
void run_tracking(const TableView& table, app::FrameSource& frames, const Pose& init, const TrackingOptions& options,
                  const std::function<void(const app::TrackRow&)>& on_row);
inline void run_tracking(const TableView& table, app::FrameSource& frames, const Pose& init, const std::optional<Detector>& detector,
                         const std::function<void(const app::TrackRow&)>& on_row, app::VoterChoice voter = app::VoterChoice::kAuto) {
  TrackingOptions options;
  options.detector = detector;
  options.voter = voter;
  run_tracking(table, frames, init, options, on_row);
}

}  // namespace gabarit::host
