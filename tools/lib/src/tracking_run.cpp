#include "gabarit/host/tracking_run.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <optional>

#include "gabarit/app/error.hpp"
#include "gabarit/host/parallel_voter.hpp"

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
  const Detector detector = options.detector ? *options.detector : detector_of(table);
  app::GrayImage frame;
  app::TrackRow row;
  Pose pose = init;
  for (std::uint32_t index = 0; frames.next(frame); ++index) {
    const auto start = std::chrono::steady_clock::now();
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
    const SessionOptions& s = options.session;
    if (s.motion_filter || s.refine || s.recover || options.coarse != nullptr || !options.focus_stack.empty())
      throw app::Error("voting on several threads applies to the plain loop (no motion filter, refinement, recovery or focus stack)");
    run_plain_parallel(table, frames, init, options, on_row);
    return;
  }
  // The grid search detects once per lost frame (recovery_search.hpp).
  app::SessionBuffers buffers(table, options.coarse, options.voter,
                              options.session.recover && options.shared_search_features);
  const SessionScratch scratch = buffers.scratch();
  const Detector detector = options.detector ? *options.detector : detector_of(table);
  TrackingSession session(table, options.coarse, detector);
  if (const Status s = session.start(options.session, init); s != Status::kOk) {
    throw app::Error(std::string("tracking options or initial pose rejected: ") + status_name(s));
  }
  std::vector<ImageView> stack_views;
  FocusStack stack;
  if (!options.focus_stack.empty()) {
    if (options.focus_stack.size() != table.depth_count()) {
      throw app::Error("the focus stack has " + std::to_string(options.focus_stack.size()) + " images; the table has " +
                  std::to_string(table.depth_count()) + " depths");
    }
    for (const app::GrayImage& image : options.focus_stack) {
      if (image.width != options.focus_stack[0].width || image.height != options.focus_stack[0].height) {
        throw app::Error("the focus stack's images differ in size");
      }
      stack_views.push_back(image.view());
    }
    stack = FocusStack{stack_views, table.model_ref_x(), table.model_ref_y(), 2};
    session.use_focus_stack(&stack);
  }
  const app::TableFocusStack stored(table);
  if (options.focus_stack.empty() && options.table_focus_stack) session.use_focus_stack(stored.get());
  app::GrayImage frame;
  app::TrackRow row;
  SessionResult result;
  // The particle recovery stage, made at the first frame (its edge map is the frame's size).
  std::unique_ptr<ParticleTracker> particles;
  std::optional<ParticleRecovery> particle_recovery;
  if (options.particle_recovery && !options.session.recover) throw app::Error("particle recovery needs recovery on");
  if (options.particle_recovery && !valid(options.particle_recovery_options)) throw app::Error("particle recovery: invalid options");
  if (options.detection_recovery && !options.session.recover) throw app::Error("detection recovery needs recovery on");
  if ((options.detection_recovery || options.detect_first) && !valid(options.finder)) throw app::Error("detection: invalid options");
  // The finder and its buffers, made at the first frame (they are the frame's size).
  ModelFinder finder(table, detector);
  if (options.table_focus_stack) finder.use_focus_stack(stored.get());
  std::optional<app::FinderBuffers> finder_buffers;
  std::optional<DetectionRecovery> detection_recovery;
  bool started = !options.detect_first;
  double detect_micros = 0;  // the first frame's detection, counted in its time
  for (std::uint32_t index = 0; frames.next(frame); ++index) {
    if ((options.detection_recovery || options.detect_first) &&
        (!finder_buffers || finder_buffers->width() != frame.width || finder_buffers->height() != frame.height)) {
      finder_buffers.emplace(table, detector, options.finder, frame.width, frame.height);
      if (options.detection_recovery) {
        detection_recovery.emplace(finder, options.finder, finder_buffers->scratch(scratch.fine), options.detection_interval);
        session.use_detection_recovery(&*detection_recovery);
      }
    }
    if (!started) {
      // Detect until found; the session starts at the detection and tracks this frame from it.
      FinderOptions one = options.finder;
      one.max_count = 1;
      Detection found[1];
      std::uint32_t count = 0;
      const auto t0 = std::chrono::steady_clock::now();
      if (const Status s = finder.find(frame.view(), one, finder_buffers->scratch(scratch.fine), found, count); s != Status::kOk)
        throw app::Error("frame " + std::to_string(index) + ": detection failed: " + status_name(s));
      if (count == 0) {
        row = app::TrackRow{};
        row.frame = index;
        row.micros = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
        on_row(row);
        continue;
      }
      if (const Status s = session.start(options.session, found[0].pose); s != Status::kOk)
        throw app::Error(std::string("the session rejected the detected pose: ") + status_name(s));
      started = true;
      detect_micros = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
    }
    if (options.particle_recovery && !particles) {
      particles = std::make_unique<ParticleTracker>(table, frame.width, frame.height, options.particles);
      particles->start(init);
      particle_recovery.emplace(table, options.detector ? *options.detector : detector_of(table), particles->edge_filter(),
                                options.particle_recovery_options);
      session.use_particle_recovery(&*particle_recovery);
    }
    const auto start = std::chrono::steady_clock::now();
    const Status status = session.step(frame.view(), scratch, result);
    const auto stop = std::chrono::steady_clock::now();
    if (status != Status::kOk) {
      throw app::Error("frame " + std::to_string(index) + ": tracking failed: " + status_name(status));
    }
    row.frame = index;
    row.micros = std::chrono::duration<double, std::micro>(stop - start).count() + detect_micros;
    detect_micros = 0;
    app::fill_row(row, result);
    on_row(row);
  }
}

}  // namespace gabarit::host
