// Proof that the kernel's entry points never allocate: malloc, calloc,
// realloc, free and every operator new/delete are replaced in this binary;
// while `armed`, any call is counted. Tables and buffers are prepared (with
// the host allocator) before arming. A positive control proves the
// interposer itself sees allocations, so this test can fail.
//
// Plain main() instead of GoogleTest: GoogleTest allocates in its assertions.

#include <cstdio>
#include <cstdlib>
#include <new>
#include <vector>

#include "gabarit/app/scratch.hpp"
#include "gabarit/dense_voter.hpp"
#include "gabarit/features.hpp"
#include "gabarit/app/image_io.hpp"
#include "gabarit/tracker.hpp"
#include "gabarit/depth_by_intensity.hpp"
#include "gabarit/particle_measures.hpp"
#include "gabarit/tracking_session.hpp"
#include "gabarit/voter.hpp"
#include "test_tables.hpp"

extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void __libc_free(void*);
}

namespace {
volatile bool armed = false;
volatile unsigned long allocations = 0;
void note() {
  if (armed) allocations = allocations + 1;
}
}  // namespace

extern "C" void* malloc(std::size_t n) {
  note();
  return __libc_malloc(n);
}
extern "C" void* calloc(std::size_t a, std::size_t b) {
  note();
  return __libc_calloc(a, b);
}
extern "C" void* realloc(void* p, std::size_t n) {
  note();
  return __libc_realloc(p, n);
}
extern "C" void free(void* p) {
  if (p) note();
  __libc_free(p);
}
void* operator new(std::size_t n) {
  note();
  if (void* p = __libc_malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void operator delete(void* p) noexcept { free(p); }
void operator delete[](void* p) noexcept { free(p); }
void operator delete(void* p, std::size_t) noexcept { free(p); }
void operator delete[](void* p, std::size_t) noexcept { free(p); }

namespace {

int failures = 0;

template <class F>
void expect_no_allocation(const char* what, F&& f) {
  allocations = 0;
  armed = true;
  const bool ok = f();
  armed = false;
  if (!ok || allocations != 0) {
    std::printf("FAIL %s: ok=%d allocations=%lu\n", what, ok, allocations);
    ++failures;
  } else {
    std::printf("ok   %s\n", what);
  }
}

}  // namespace

int main() {
  using namespace gabarit;
  app::Rng rng(1);
  const auto pts = testing::random_points(rng, 50, 12);
  const auto bytes = testing::build(testing::point_model(pts), "-4:4:9", "-4:4:9", "-4:4:3");
  TableView table;
  if (TableView::open(bytes, table) != Status::kOk) return 2;
  app::GrayImage frame(64, 64);
  for (const auto& p : pts) frame.at(static_cast<std::uint32_t>(32 + p.x), static_cast<std::uint32_t>(32 + p.y)) = 255;
  std::vector<RoiPoint> features(tracker_feature_capacity(table));
  std::vector<VoteCounter> counters(voter_counter_count(table.cell_count()));
  std::vector<std::uint8_t> mask(tracker_mask_bytes(table));
  std::vector<CellScore> top(5);
  std::vector<std::uint64_t> masks(dense_mask_words(table.roi_slots(), table.cell_count()));
  std::vector<std::uint64_t> dense_scratch(dense_scratch_words(table.cell_count()));
  if (build_dense_masks(table, masks) != Status::kOk) return 2;
  std::vector<std::uint32_t> expanded(expanded_offsets_count(table));
  const TrackerScratch scratch{features, counters, mask};
  const TrackerScratch dense{features, counters, mask, masks, dense_scratch};
  const ImageView view = frame.view();
  const app::GrayImage blank(64, 64);  // allocated here, before any check
  const ImageWindow window{0, 0, 64, 64};

  // Positive control: the interposer must see a plain allocation.
  allocations = 0;
  armed = true;
  int* probe = new int(7);
  armed = false;
  delete probe;
  if (allocations == 0) {
    std::printf("FAIL interposer did not observe operator new\n");
    return 1;
  }

  expect_no_allocation("TableView::open", [&] { TableView t; return TableView::open(bytes, t) == Status::kOk; });
  expect_no_allocation("extract_binary", [&] { FeatureCount c; return extract_binary(view, window, features, c) == Status::kOk; });
  expect_no_allocation("extract_gradient_rows", [&] {
    FeatureCount c;
    return extract_gradient_rows(view, window, 100, features, c) == Status::kOk;
  });
  std::vector<std::uint16_t> magnitude_rows(canny_scratch_entries(window.width));
  expect_no_allocation("extract_canny", [&] {
    FeatureCount c, rows_c;
    return extract_canny(view, window, 100, features, c) == Status::kOk &&
           extract_canny(view, window, 100, features, rows_c, magnitude_rows) == Status::kOk && rows_c.written == c.written;
  });
  expect_no_allocation("voting and ranking", [&] {
    FeatureCount c;
    if (extract_binary(view, {32 + table.roi_origin_x(), 32 + table.roi_origin_y(), table.roi_width(), table.roi_height()},
                       features, c) != Status::kOk) return false;
    VoteTally tally;
    return clear_counters(table, counters) == Status::kOk &&
           accumulate_votes(table, std::span(features).first(c.written), counters, tally) == Status::kOk &&
           accumulate_votes_dense(table, masks, std::span(features).first(c.written), counters, dense_scratch, tally) == Status::kOk &&
           build_dense_masks(table, masks) == Status::kOk &&
           expand_offsets(table, expanded) == Status::kOk &&
           accumulate_votes_expanded(table, expanded, std::span(features).first(c.written), counters, tally) == Status::kOk &&
           select_top_cells(table, counters, top) == Status::kOk;
  });
  expect_no_allocation("track_step", [&] { StepResult r; return track_step(table, view, Pose{32, 32, 0, 0}, scratch, r) == Status::kOk; });
  expect_no_allocation("track_step, rotated", [&] {
    StepResult r;
    return track_step(table, view, Pose{32, 32, 3.5f, 0}, scratch, r) == Status::kOk;
  });
  expect_no_allocation("track_step, dense voter", [&] { StepResult r; return track_step(table, view, Pose{32, 32, 0, 0}, dense, r) == Status::kOk; });
  expect_no_allocation("track_step, dense voter, rotated", [&] {
    StepResult r;
    return track_step(table, view, Pose{32, 32, -2.0f, 0}, dense, r) == Status::kOk;
  });
  // The session: start, a tracking frame, then lost frames (the recovery
  // search places the table 567 times) on an empty image.
  TrackingSession session(table, nullptr, detector_of(table));
  expect_no_allocation("tracking session start", [&] { return session.start(SessionOptions{}, Pose{32, 32, 0, 0}) == Status::kOk; });
  expect_no_allocation("tracking session, filter + refine + recovery", [&] {
    SessionResult r;
    bool ok = session.step(view, {scratch, {}}, r) == Status::kOk;
    for (int i = 0; i < 12 && ok; ++i) ok = session.step(blank.view(), {scratch, {}}, r) == Status::kOk;
    return ok && session.lost();
  });
  // The same with the recovery grid screened from features detected once per
  // lost frame (map_features), and searching every 2nd lost frame.
  std::vector<RoiPoint> search_features(search_feature_capacity(table));
  TrackingSession screened(table, nullptr, detector_of(table));
  expect_no_allocation("tracking session, recovery screened from shared features", [&] {
    SessionOptions o;
    o.recovery.interval = 2;
    SessionResult r;
    bool ok = screened.start(o, Pose{32, 32, 0, 0}) == Status::kOk && screened.step(view, {scratch, {}, search_features}, r) == Status::kOk;
    for (int i = 0; i < 12 && ok; ++i) ok = screened.step(blank.view(), {scratch, {}, search_features}, r) == Status::kOk;
    return ok && screened.lost();
  });
  expect_no_allocation("map_features", [&] {
    PreparedFrame prepared;
    const ImageWindow window{0, 0, 64, 64};
    FeatureCount c;
    return extract_features(view, window, detector_of(table).kind, detector_of(table).threshold, search_features, c) == Status::kOk &&
           map_features(table, view, std::span<const RoiPoint>(search_features).first(c.written), window, Pose{32, 32, 4.0f, 0}, scratch,
                        prepared) == Status::kOk;
  });
  // Depth by intensity, inside a session and on its own.
  const ImageView stack_views[2] = {view, view};
  const FocusStack stack{std::span<const ImageView>(stack_views, 2), 16.0f, 16.0f, 2};
  expect_no_allocation("depth by intensity", [&] {
    std::uint16_t depth = 0;
    return depth_by_intensity(view, Pose{32, 32, 5.0f, 0}, stack, depth) == Status::kOk;
  });
  expect_no_allocation("tracking session with a focus stack", [&] {
    TrackingSession with_stack(table, nullptr, detector_of(table));
    with_stack.use_focus_stack(&stack);
    SessionResult r;
    return with_stack.start(SessionOptions{}, Pose{32, 32, 0, 0}) == Status::kOk && with_stack.step(view, {scratch, {}}, r) == Status::kOk;
  });
  // Refinement by aligning the features (fixed-size Eigen) in a session.
  expect_no_allocation("tracking session, sub-cell by feature alignment", [&] {
    TrackingSession aligned(table, nullptr, detector_of(table));
    SessionOptions o;
    o.align_features = true;
    SessionResult r;
    bool ok = aligned.start(o, Pose{32, 32, 0, 0}) == Status::kOk;
    for (int i = 0; i < 3 && ok; ++i) ok = aligned.step(view, {scratch, {}}, r) == Status::kOk;
    return ok;
  });
  // The particle filter's memory, static as on an MCU.
  static std::uint64_t bits[edge_map_words(64, 64)];
  static RoiPoint strip[64 * 4];
  static Particle cloud[256], next[256];
  static std::uint32_t order[512];
  // The particle filter with both measures, every improvement on (vote proposals too), a scatter and lost frames.
  {
    EdgeMapLoader loader(detector_of(table), bits, strip, 64, 64);
    EdgeCorrelationMeasure edges(table, loader, 2, 0), fine(table, loader, 1, 0);
    StencilVoteMeasure stencil(table, detector_of(table), scratch);
    const auto run = [&](const char* name, auto& filter) {
      expect_no_allocation(name, [&] {
        ParticleEstimate e;
        bool ok = filter.start(ParticleFilterOptions{}, Pose{32, 32, 0, 0}, table.depth_count(), 7, {cloud, next, order}) == Status::kOk;
        for (int i = 0; i < 3 && ok; ++i) ok = filter.step(view, e) == Status::kOk;
        ok = ok && filter.scatter(10, 50, 10, 50, -5, 5) == Status::kOk;
        for (int i = 0; i < 3 && ok; ++i) ok = filter.step(blank.view(), e) == Status::kOk;
        filter.reinitialise_around(Pose{32, 32, 0, 0}, 0.5f);
        return ok && filter.step(view, e) == Status::kOk;
      });
    };
    EdgeParticleFilter with_edges(edges, &fine, &loader);
    run("particle filter, edge measure", with_edges);
    ParticleFilter<StencilVoteMeasure, EdgeCorrelationMeasure, EdgeMapLoader> with_votes(stencil, &fine, &loader);
    run("particle filter, stencil measure", with_votes);
    StencilVoteProposer proposer(table, detector_of(table), scratch);  // the stencil measure's scratch: not run together
    EdgeParticleFilter guided(edges, &fine, &loader);
    guided.propose_with(&proposer);
    run("particle filter, edge measure, vote proposals", guided);
  }
  // A session re-acquiring through the particle filter.
  {
    EdgeMapLoader loader(detector_of(table), bits, strip, 64, 64);
    EdgeCorrelationMeasure edges(table, loader, 2, 0), fine(table, loader, 1, 0);
    EdgeParticleFilter filter(edges, &fine, &loader);
    ParticleRecovery stage(table, detector_of(table), filter);
    TrackingSession with_particles(table, nullptr, detector_of(table));
    with_particles.use_particle_recovery(&stage);
    expect_no_allocation("tracking session, particle re-acquisition", [&] {
      SessionResult r;
      bool ok = filter.start(ParticleFilterOptions{}, Pose{32, 32, 0, 0}, table.depth_count(), 7, {cloud, next, order}) == Status::kOk;
      ok = ok && with_particles.start(SessionOptions{}, Pose{32, 32, 0, 0}) == Status::kOk;
      ok = ok && with_particles.step(view, {scratch, {}}, r) == Status::kOk;
      for (int i = 0; i < 12 && ok; ++i) ok = with_particles.step(blank.view(), {scratch, {}}, r) == Status::kOk;
      ok = ok && with_particles.lost();
      for (int i = 0; i < 3 && ok; ++i) ok = with_particles.step(view, {scratch, {}}, r) == Status::kOk;
      return ok && stage.frames() > 0;
    });
  }
  // Detection over the whole frame, and a session re-acquiring by detection.
  {
    const FinderOptions fo;
    app::FinderBuffers finder_buffers(table, detector_of(table), fo, 64, 64);
    ModelFinder finder(table, detector_of(table));
    Detection found[8];
    expect_no_allocation("model finder", [&] {
      std::uint32_t count = 0;
      return finder.find(view, fo, finder_buffers.scratch(scratch), found, count) == Status::kOk;
    });
    DetectionRecovery stage(finder, fo, finder_buffers.scratch(scratch));
    TrackingSession with_detection(table, nullptr, detector_of(table));
    with_detection.use_detection_recovery(&stage);
    expect_no_allocation("tracking session, re-acquisition by detection", [&] {
      SessionResult r;
      bool ok = with_detection.start(SessionOptions{}, Pose{32, 32, 0, 0}) == Status::kOk;
      ok = ok && with_detection.step(view, {scratch, {}}, r) == Status::kOk;
      for (int i = 0; i < 12 && ok; ++i) ok = with_detection.step(blank.view(), {scratch, {}}, r) == Status::kOk;
      ok = ok && with_detection.lost();
      for (int i = 0; i < 3 && ok; ++i) ok = with_detection.step(view, {scratch, {}}, r) == Status::kOk;
      return ok;
    });
  }
  std::printf("%d passed, %d failed\n", 20 - failures, failures);
  return failures == 0 ? 0 : 1;
}
