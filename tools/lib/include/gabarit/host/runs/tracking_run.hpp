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
#include "gabarit/app/hosted_session.hpp"
#include "gabarit/app/session_profile.hpp"
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
  // What runs: the thesis's loop unless a profile says otherwise (gabarit
  // track reads its options into one, session_profile_io.hpp).
  app::SessionProfile profile = app::plain_profile();
  app::SessionExtras extras;  // voter, detector, coarse table, focus-stack images, detection options
  // Threads voting each frame (parallel_voter.hpp, features split). Above 1,
  // only for the plain loop (a plain profile with no parts, no coarse table
  // or focus stack); the rows are the same bytes as with one thread.
  unsigned threads = 1;
  // No initial pose: the first frames are searched by detection until the
  // model is found (rows before are lost, at 0,0), then the session starts there.
  bool detect_first = false;
};

// Calls on_row for every frame. row.step is the frame's vote with the
// session's decision in pose, state and score (tracking_session.hpp).
void run_tracking(const TableView& table, app::FrameSource& frames, const Pose& init, const TrackingOptions& options,
                  const std::function<void(const app::TrackRow&)>& on_row);
inline void run_tracking(const TableView& table, app::FrameSource& frames, const Pose& init, const std::optional<Detector>& detector,
                         const std::function<void(const app::TrackRow&)>& on_row, app::VoterChoice voter = app::VoterChoice::kAuto) {
  TrackingOptions options;
  options.extras.detector = detector;
  options.extras.voter = voter;
  run_tracking(table, frames, init, options, on_row);
}

}  // namespace gabarit::host
