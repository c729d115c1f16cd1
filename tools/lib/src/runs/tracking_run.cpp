#include "gabarit/host/runs/tracking_run.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>

#include "gabarit/app/error.hpp"
#include "gabarit/host/runs/parallel_voter.hpp"

namespace gabarit::host {

TimingSummary summarise_timing(std::vector<double> micros) {
  TimingSummary s;
  s.frames = micros.size();
  if (micros.empty()) return s;
  std::sort(micros.begin(), micros.end());
  double sum = 0;
  for (double m : micros) sum += m;
  s.mean = sum / static_cast<double>(micros.size());
  // Nearest-rank percentiles.
  const auto rank = [&](double q) {
    std::size_t r = static_cast<std::size_t>(q * static_cast<double>(micros.size()) + 0.999999);
    return micros[std::clamp<std::size_t>(r, 1, micros.size()) - 1];
  };
  s.p50 = rank(0.50);
  s.p99 = rank(0.99);
  s.max = micros.back();
  return s;
}

namespace {

// The plain loop with each frame's vote on several threads: prepare_frame,
// the parallel voter, finish_frame (tracker.hpp).
void run_plain_parallel(const TableView& table, app::FrameSource& frames, const Pose& init, const TrackingOptions& options,
                        const std::function<void(const app::TrackRow&)>& on_row) {
  app::TrackerBuffers buffers(table, app::VoterChoice::kCsr);
  const TrackerScratch scratch = buffers.scratch();
  ParallelVoter voter(options.threads, ParallelVoter::Split::kFeatures);
  const Detector detector = options.extras.detector ? *options.extras.detector : detector_of(table);
  app::GrayImage frame;
  app::TrackRow row;
  Pose pose = init;
  for (std::uint32_t index = 0;; ++index) {
    const auto reading = std::chrono::steady_clock::now();
    if (!frames.next(frame)) break;
    const auto start = std::chrono::steady_clock::now();
    row.io_micros = std::chrono::duration<double, std::micro>(start - reading).count();
    PreparedFrame prepared;
    VoteTally tally;
    Status status = prepare_frame(table, detector, frame.view(), pose, scratch, prepared);
    if (status == Status::kOk) status = clear_counters(table, scratch.counters);
    if (status == Status::kOk) status = voter.accumulate(table, scratch.features.first(prepared.features), scratch.counters, tally);
    if (status == Status::kOk) status = finish_frame(table, pose, prepared, scratch.counters, tally, row.step);
    const auto stop = std::chrono::steady_clock::now();
    if (status != Status::kOk) throw app::Error("frame " + std::to_string(index) + ": tracking failed: " + status_name(status));
    if (row.step.state == TrackState::kLost) row.step.pose = pose;  // no evidence to move it (as the plain session)
    pose = row.step.pose;
    row.frame = index;
    row.micros = std::chrono::duration<double, std::micro>(stop - start).count();
    row.confidence = Confidence::kNone;  // not graded: the plain loop has no reference score
    row.reacquired = false;
    on_row(row);
  }
}

}  // namespace

void run_tracking(const TableView& table, app::FrameSource& frames, const Pose& init, const TrackingOptions& options,
                  const std::function<void(const app::TrackRow&)>& on_row) {
  if (options.threads > 1) {
    const app::SessionProfile& p = options.profile;
    if (!p.plain || p.motion_filter || p.refine || p.recover || options.extras.coarse != nullptr ||
        !options.extras.focus_stack.empty() || options.extras.research_options || options.detect_first)
      throw app::Error("voting on several threads applies to the plain loop (no motion filter, refinement, recovery or focus stack)");
    run_plain_parallel(table, frames, init, options, on_row);
    return;
  }
  app::HostedSession session(table, options.profile, options.extras);
  if (!options.detect_first && !session.start(init)) throw app::Error("tracking options or initial pose rejected");
  app::GrayImage frame;
  app::TrackRow row;
  SessionResult result;
  double detect_micros = 0;  // the frame that found the start: its detection counted in its time
  for (std::uint32_t index = 0;; ++index) {
    const auto reading = std::chrono::steady_clock::now();
    if (!frames.next(frame)) break;
    const double io_micros = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - reading).count();
    if (!session.started()) {
      const auto t0 = std::chrono::steady_clock::now();
      bool found = false;
      try {
        found = session.start_by_detection(frame.view());
      } catch (const app::Error& e) {
        throw app::Error("frame " + std::to_string(index) + ": " + e.what());
      }
      detect_micros = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
      if (!found) {
        row = app::TrackRow{};
        row.frame = index;
        row.micros = detect_micros;
        row.has_ledger = true;  // nothing tracked: the whole frame was the search
        row.ledger.ticks[static_cast<std::uint32_t>(FramePhase::kRecovery)] = static_cast<std::uint64_t>(detect_micros * 1000.0);
        row.io_micros = io_micros;
        on_row(row);
        continue;
      }
    }
    const auto start = std::chrono::steady_clock::now();
    const Status status = session.step(frame.view(), result);
    const auto stop = std::chrono::steady_clock::now();
    if (status != Status::kOk) {
      throw app::Error("frame " + std::to_string(index) + ": tracking failed: " + status_name(status));
    }
    row.frame = index;
    row.micros = std::chrono::duration<double, std::micro>(stop - start).count() + detect_micros;
    app::fill_row(row, result);
    // The detection that found the start is that frame's search: the
    // ledger's recovery (its ticks are nanoseconds, HostedSession's clock).
    row.ledger.ticks[static_cast<std::uint32_t>(FramePhase::kRecovery)] += static_cast<std::uint64_t>(detect_micros * 1000.0);
    detect_micros = 0;
    row.io_micros = io_micros;
    on_row(row);
  }
}

}  // namespace gabarit::host
