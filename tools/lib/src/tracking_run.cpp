#include "gabarit/host/tracking_run.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>

#include "gabarit/dense_voter.hpp"
#include "gabarit/host/error.hpp"
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

TrackerBuffers::TrackerBuffers(const TableView& table, VoterChoice voter)
    : features_(tracker_feature_capacity(table)),
      counters_(voter_counter_count(table.cell_count())),
      mask_(tracker_mask_bytes(table)) {
  const bool fits = table.cell_count() <= kDenseMaxCells;
  if (voter == VoterChoice::kDense && !fits) {
    throw Error("the dense voter takes at most " + std::to_string(kDenseMaxCells) + " cells; this table has " +
                std::to_string(table.cell_count()));
  }
  if (voter != VoterChoice::kCsr && fits) {
    masks_.resize(dense_mask_words(table.roi_pixels(), table.cell_count()));
    dense_scratch_.resize(dense_scratch_words(table.cell_count()));
    if (build_dense_masks(table, masks_) != Status::kOk) throw Error("internal error: building dense masks failed");
  }
}

TrackerScratch TrackerBuffers::scratch() { return {features_, counters_, mask_, masks_, dense_scratch_}; }

namespace {

// The plain loop with each frame's vote on several threads: prepare_frame,
// the parallel voter, finish_frame (tracker.hpp).
void run_plain_parallel(const TableView& table, FrameSource& frames, const Pose& init, const TrackingOptions& options,
                        const std::function<void(const TrackRow&)>& on_row) {
  TrackerBuffers buffers(table, VoterChoice::kCsr);
  const TrackerScratch scratch = buffers.scratch();
  ParallelVoter voter(options.threads, ParallelVoter::Split::kFeatures);
  const Detector detector = options.detector ? *options.detector : detector_of(table);
  GrayImage frame;
  TrackRow row;
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
    if (status != Status::kOk) throw Error("frame " + std::to_string(index) + ": tracking failed: " + status_name(status));
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

void run_tracking(const TableView& table, FrameSource& frames, const Pose& init, const TrackingOptions& options,
                  const std::function<void(const TrackRow&)>& on_row) {
  if (options.threads > 1) {
    const SessionOptions& s = options.session;
    if (s.motion_filter || s.refine || s.recover || options.coarse != nullptr || !options.focus_stack.empty())
      throw Error("voting on several threads applies to the plain loop (no motion filter, refinement, recovery or focus stack)");
    run_plain_parallel(table, frames, init, options, on_row);
    return;
  }
  TrackerBuffers buffers(table, options.voter);
  std::optional<TrackerBuffers> coarse_buffers;
  SessionScratch scratch{buffers.scratch(), {}};
  std::vector<RoiPoint> search_features;
  if (options.coarse != nullptr) {
    coarse_buffers.emplace(*options.coarse, options.voter);
    scratch.coarse = coarse_buffers->scratch();
  } else if (options.session.recover && options.shared_search_features) {
    // The grid search detects once per lost frame (tracking_session.hpp).
    search_features.resize(search_feature_capacity(table));
    scratch.search_features = search_features;
  }
  TrackingSession session(table, options.coarse, options.detector ? *options.detector : detector_of(table));
  if (const Status s = session.start(options.session, init); s != Status::kOk) {
    throw Error(std::string("tracking options or initial pose rejected: ") + status_name(s));
  }
  std::vector<ImageView> stack_views;
  FocusStack stack;
  if (!options.focus_stack.empty()) {
    if (options.focus_stack.size() != table.depth_count()) {
      throw Error("the focus stack has " + std::to_string(options.focus_stack.size()) + " images; the table has " +
                  std::to_string(table.depth_count()) + " depths");
    }
    for (const GrayImage& image : options.focus_stack) {
      if (image.width != options.focus_stack[0].width || image.height != options.focus_stack[0].height) {
        throw Error("the focus stack's images differ in size");
      }
      stack_views.push_back(image.view());
    }
    stack = FocusStack{stack_views, table.model_ref_x(), table.model_ref_y(), 2};
    session.use_focus_stack(&stack);
  }
  GrayImage frame;
  TrackRow row;
  SessionResult result;
  for (std::uint32_t index = 0; frames.next(frame); ++index) {
    const auto start = std::chrono::steady_clock::now();
    const Status status = session.step(frame.view(), scratch, result);
    const auto stop = std::chrono::steady_clock::now();
    if (status != Status::kOk) {
      throw Error("frame " + std::to_string(index) + ": tracking failed: " + status_name(status));
    }
    row.frame = index;
    row.micros = std::chrono::duration<double, std::micro>(stop - start).count();
    fill_row(row, result);
    on_row(row);
  }
}

void fill_row(TrackRow& row, const SessionResult& result) {
  row.step = result.step;
  row.step.pose = result.pose;
  row.step.state = result.state;
  row.step.score = result.score;
  row.confidence = result.confidence;
  row.reacquired = result.reacquired;
}

std::string pose_csv_row(const TrackRow& row) {
  char line[192];
  std::snprintf(line, sizeof line, "%u,%.3f,%.3f,%.3f,%u,%u,%.6f,%s", row.frame, static_cast<double>(row.step.pose.x),
                static_cast<double>(row.step.pose.y), static_cast<double>(row.step.pose.theta_deg), row.step.pose.depth,
                row.step.best.votes, static_cast<double>(row.step.score), track_state_name(row.step.state));
  return line;
}

}  // namespace gabarit::host
