#include "microscope.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include "gabarit/features.hpp"
#include "gabarit/app/error.hpp"
#include "gabarit/app/evaluation.hpp"
#include "gabarit/app/image_io.hpp"
#include "gabarit/host/tables/model.hpp"
#include "gabarit/host/runs/parallel_voter.hpp"
#include "gabarit/app/rng.hpp"
#include "gabarit/host/scenes/scene_synth.hpp"
#include "gabarit/host/tables/stencil.hpp"
#include "gabarit/host/scenes/synth.hpp"
#include "gabarit/host/tables/table_builder.hpp"
#include "gabarit/host/runs/tracking_run.hpp"
#include "gabarit/tracking_session.hpp"
#include "scene_io.hpp"
#include "gabarit/app/svg_plot.hpp"

namespace gabarit::bench {
namespace {

using Clock = std::chrono::steady_clock;
double micros_since(Clock::time_point t) { return std::chrono::duration<double, std::micro>(Clock::now() - t).count(); }

std::string fmt(double v, int digits = 1) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", digits, v);
  return b;
}

using Run = MethodRun;  // scene_io.hpp

// The scene and its fine table, shared by the accuracy tables.
struct Scene {
  host::SceneOptions options;
  std::vector<app::GrayImage> frames;
  std::vector<app::PoseSample> truth;
  std::vector<app::GrayImage> model_images;
  host::BuildOptions build;        // the fine table's state space
  std::vector<std::byte> table_bytes;
  TableView table;
  Pose init;
};

// 1, 2. The scene, and the fine table of the tracker, timed.
Scene make_scene(const std::string& dir, bool quick, std::ostringstream& md) {
  namespace fs = std::filesystem;
  Scene sc;
  host::SceneOptions& so = sc.options;
  std::vector<app::GrayImage>& frames = sc.frames;
  host::BuildOptions& bo = sc.build;
  std::vector<app::GrayImage>& model_images = sc.model_images;
  so.depths = 5;
  so.frames = quick ? 140 : 240;
  const std::string seq = (fs::path(dir) / "scene").string();
  const host::SceneSummary scene = host::write_scene_sequence(so, seq);
  frames = read_all_frames(fs::path(seq) / "frames.y4m");
  sc.truth = app::read_pose_csv((fs::path(seq) / "gt.csv").string());
  md << "Scene: " << frames.size() << " frames " << so.width << "x" << so.height << " (" << scene.visible_frames
     << " visible; occlusion " << so.occlusion_start << ".." << so.occlusion_start + so.occlusion_frames - 1
     << "), camera.png cog over gravel.png, " << so.depths << " focus-stack depths, illumination +-" << so.illumination * 100
     << "%, noise sigma " << so.noise_sigma << ", motion blur every " << so.blur_every << " frames.\n\n";

  // 2. Tables: the fine table of the tracker, timed.
  const std::vector<std::string> model_paths = scene_model_paths(seq, so.depths);
  for (const std::string& path : model_paths) model_images.push_back(app::read_pgm(path));
  host::ImageModelOptions canny;  // gabarit tables build's default detector
  canny.canny = true;
  const host::ModelStack model = host::model_from_images(model_paths, canny);
  bo.space.x = host::parse_axis("-4:4:9", "x");
  bo.space.y = host::parse_axis("-4:4:9", "y");
  bo.space.theta = host::parse_axis("-1.5:1.5:7", "theta");
  auto t0 = Clock::now();
  sc.table_bytes = host::build_table(model, bo);
  const double build_fine_ms = micros_since(t0) / 1000;
  if (TableView::open(sc.table_bytes, sc.table) != Status::kOk) throw app::Error("microscope: fine table invalid");
  md << "Fine table (the Canny variant, `tables build`'s default, unless said): x, y -4..4 px in 1-px cells, theta -1.5..1.5 deg in 0.5-deg cells, " << so.depths << " depths = "
     << sc.table.cell_count() << " cells, " << sc.table.reference_count() << " references, " << sc.table_bytes.size() << " bytes, "
     << model.depths[0].size() << " model features at depth 0 (Canny variant, threshold " << model.detector.threshold
     << " from the model), built in " << fmt(build_fine_ms) << " ms.\n\n";

  const auto& truth = sc.truth;
  sc.init = {static_cast<float>(truth[0].x), static_cast<float>(truth[0].y), static_cast<float>(truth[0].theta_deg),
             static_cast<std::uint16_t>(truth[0].depth)};
  return sc;
}

// The session settings of the cheaper recovery rows.
SessionOptions every_second_search() {
  SessionOptions o;
  o.recovery.interval = 2;
  return o;
}
SessionOptions cheap_search() {
  SessionOptions o = every_second_search();
  o.recovery.screen_stride = 3;
  return o;
}

// 3. Accuracy and time per frame: the tracker's settings, the NCC bank and
// OpenCV's box trackers on the scene.
// The accuracy table (visible frames), the pose files and the trajectory plots.
void report_accuracy(const Scene& sc, const std::string& dir, const std::vector<Run>& runs, std::size_t ncc_run,
                     std::size_t focus_stack_run, std::ostringstream& md) {
  namespace fs = std::filesystem;
  const auto& truth = sc.truth;
  const double ncc_us = runs[ncc_run].mean_us, ncc_median = runs[ncc_run].median_us();
  md << "## Accuracy and time per frame\n\n";
  md << "Visible frames only. Targets: position within 1 px in >= 98%, angle within 1 deg in >= 98%, depth exact in >= 95%, "
        "reacquired within 10 frames after the occlusion, time <= 1/30 of the NCC bank.\n\n";
  md << "| method | within 1 px | 2 px | 6 px | 12 px | 20 px | 40 px | angle within 1 deg | depth exact | reacquired after | us/frame mean | median | NCC time / this, mean | median |\n";
  md << "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const Run& r : runs) {
    const app::Accuracy a = app::evaluate(r.poses, truth);
    const auto share = [&](double limit) {
      std::size_t n = 0;
      for (const auto& t : truth) {
        if (!t.visible) continue;
        const auto& p = r.poses[t.frame];
        n += std::hypot(p.x - t.x, p.y - t.y) <= limit;
      }
      return fmt(100.0 * static_cast<double>(n) / static_cast<double>(a.frames)) + "%";
    };
    std::string reacq;
    for (int v : a.reacquired_after) reacq += (reacq.empty() ? "" : ", ") + (v < 0 ? std::string("never") : std::to_string(v) + " frames");
    md << "| " << r.name << " | " << share(1) << " | " << share(2) << " | " << share(6) << " | " << share(12) << " | " << share(20)
       << " | " << share(40) << " | "
       << (r.position_only ? std::string("n/a") : fmt(100.0 * static_cast<double>(a.within_1deg) / static_cast<double>(a.frames)) + "%")
       << " | " << (r.position_only ? std::string("n/a") : fmt(100.0 * static_cast<double>(a.depth_exact) / static_cast<double>(a.frames)) + "%")
       << " | " << reacq << " | "
       << fmt(r.mean_us) << " | " << fmt(r.median_us()) << " | " << fmt(ncc_us / r.mean_us) << "x | "
       << fmt(ncc_median / r.median_us()) << "x |\n";
    std::ofstream csv(fs::path(dir) / ("poses-" + std::to_string(&r - runs.data()) + ".csv"));
    csv << "frame,x,y,theta_deg,depth\n";
    for (const auto& p : r.poses) csv << p.frame << ',' << p.x << ',' << p.y << ',' << p.theta_deg << ',' << p.depth << '\n';
  }
  md << "\nThe mean includes the lost frames, where the recovery search places the fine table 147 times (detecting "
        "features once and voting every second one at each placement, unless said) and votes the best three again; "
        "the median is a tracking frame.\n\nPose files: poses-N.csv in table order. Trajectories: trajectory-x.svg, trajectory-theta.svg.\n\n";
  for (const char* axis : {"x", "theta"}) {
    std::vector<app::svg::Series> series;
    app::svg::Series t{"truth", {}, {}};
    for (const auto& p : truth) {
      t.x.push_back(p.frame);
      t.y.push_back(axis[0] == 'x' ? p.x : p.theta_deg);
    }
    series.push_back(t);
    for (std::size_t i : {std::size_t{0}, focus_stack_run, ncc_run}) {
      app::svg::Series s{runs[i].name, {}, {}};
      for (const auto& p : runs[i].poses) {
        s.x.push_back(p.frame);
        s.y.push_back(axis[0] == 'x' ? p.x : p.theta_deg);
      }
      series.push_back(s);
    }
    app::svg::write((fs::path(dir) / (std::string("trajectory-") + axis + ".svg")).string(),
               app::svg::lines(std::string("Tracked and true ") + axis + " (thesis Figs. 6.55-6.59)", "frame",
                          axis[0] == 'x' ? "x (px)" : "theta (deg)", series, false, false));
  }

}

void accuracy_table(const Scene& sc, const std::string& dir, std::ostringstream& md) {
  namespace fs = std::filesystem;
  const auto& frames = sc.frames;
  const auto& model_images = sc.model_images;
  const TableView& table = sc.table;
  const Pose& init = sc.init;
  const std::vector<std::string> model_paths = scene_model_paths(fs::path(dir) / "scene", sc.options.depths);
  const host::BuildOptions& bo = sc.build;
  std::vector<Run> runs;
  const auto track = [&](const std::string& name, const SessionOptions& session, const TableView& with,
                         bool focus_stack = false, bool shared_search_features = true) {
    host::TrackingOptions options;
    options.extras.research_options = session;
    options.profile.shared_search = shared_search_features;
    if (focus_stack) options.extras.focus_stack = model_images;
    Run r{name, {}, 0, {}};
    MemoryFrames src(frames);
    double total = 0;
    host::run_tracking(with, src, init, options, [&](const app::TrackRow& row) {
      r.poses.push_back({row.frame, row.step.pose.x, row.step.pose.y, row.step.pose.theta_deg, row.step.pose.depth, true});
      total += row.micros;
      r.micros.push_back(row.micros);
    });
    r.mean_us = total / static_cast<double>(frames.size());
    runs.push_back(r);
  };
  track("gabarit, thesis loop (cell centres)", kPlainSession, table);
  SessionOptions refine_only = kPlainSession;
  refine_only.refine = true;
  track("gabarit + sub-cell refinement", refine_only, table);
  track("gabarit + motion filter + refinement + recovery", SessionOptions{}, table);
  // The same with the thesis's gradient-rows detector (model and frames).
  const std::vector<std::byte> rows_bytes = host::build_table(host::model_from_images(model_paths, {}), bo);
  TableView rows_table;
  if (TableView::open(rows_bytes, rows_table) != Status::kOk) throw app::Error("microscope: gradient-rows table invalid");
  track("the same, gradient-rows detector (the thesis's)", SessionOptions{}, rows_table);
  // Depth by intensity at the tracked pose (depth_by_intensity.hpp), and the
  // recovery search spread over lost frames (RecoveryOptions::budget).
  track("filter + refinement + recovery + depth and angle by intensity", SessionOptions{}, table, true);
  // The recovery grid as it was: features detected again and every feature
  // voted at each placement.
  track("the same, each recovery placement a full track_step", SessionOptions{}, table, true, false);
  // Cheaper lost periods, traded against how soon the target is found again.
  track("the same, searching every 2nd lost frame", every_second_search(), table, true);
  track("the same, every 2nd lost frame, screening with every 3rd feature", cheap_search(), table, true);
  SessionOptions budgeted;
  budgeted.recovery.budget = 100;
  track("the same, 100 of the 558 outer placements per search", budgeted, table, true);
  {
    NccBank ncc(model_images, 4, 0.5, 3);
    Run r{"OpenCV NCC bank (TM_CCOEFF_NORMED, same 4-DOF window)", {}, 0, {}};
    Pose pose = init;
    double total = 0;
    for (std::uint32_t f = 0; f < frames.size(); ++f) {
      const auto t = Clock::now();
      pose = ncc.track(frames[f], pose);
      r.micros.push_back(micros_since(t));
      total += r.micros.back();
      r.poses.push_back({f, pose.x, pose.y, pose.theta_deg, pose.depth, true});
    }
    r.mean_us = total / static_cast<double>(frames.size());
    runs.push_back(r);
  }
  const std::size_t ncc_run = runs.size() - 1, focus_stack_run = 4;
  opencv_box_trackers(frames, model_images, init, runs);
  report_accuracy(sc, dir, runs, ncc_run, focus_stack_run, md);
}

// 3b. The same tracker on other scenes (other trajectories, occlusions and
// object placements), so the figures above are not one sequence's luck.
void other_scenes_table(const Scene& sc, const std::string& dir, std::ostringstream& md) {
  namespace fs = std::filesystem;
  const host::SceneOptions& so = sc.options;
  const host::BuildOptions& bo = sc.build;
  const SessionOptions cheap = cheap_search();
  md << "## The same tracker on other scenes\n\n"
        "Filter + refinement + recovery + depth and angle by intensity on the scene drawn with other seeds "
        "(`gabarit synth --scene microscope --depths 5 --seed N`), each with its own table built as above: with the "
        "defaults, and searching every 2nd lost frame with every 3rd feature screening.\n\n"
        "| seed | recovery | within 1 px | angle within 1 deg | depth exact | reacquired after | lost frames | us/frame mean | median |\n"
        "|---:|---|---:|---:|---:|---:|---:|---:|---:|\n";
  for (std::uint64_t seed = 2; seed <= 5; ++seed) {
    host::SceneOptions other = so;
    other.seed = seed;
    const std::string other_dir = (fs::path(dir) / ("scene-seed" + std::to_string(seed))).string();
    host::write_scene_sequence(other, other_dir);
    const std::vector<app::GrayImage> other_frames = read_all_frames(fs::path(other_dir) / "frames.y4m");
    const auto other_truth = app::read_pose_csv((fs::path(other_dir) / "gt.csv").string());
    const std::vector<std::string> paths = scene_model_paths(other_dir, other.depths);
    host::TrackingOptions options;
    for (const std::string& path : paths) options.extras.focus_stack.push_back(app::read_pgm(path));
    host::ImageModelOptions canny_seed;
    canny_seed.canny = true;
    const std::vector<std::byte> bytes = host::build_table(host::model_from_images(paths, canny_seed), bo);
    TableView other_table;
    if (TableView::open(bytes, other_table) != Status::kOk) throw app::Error("microscope: table for seed " + std::to_string(seed) + " invalid");
    const Pose start{static_cast<float>(other_truth[0].x), static_cast<float>(other_truth[0].y),
                     static_cast<float>(other_truth[0].theta_deg), static_cast<std::uint16_t>(other_truth[0].depth)};
    for (const bool cheaper : {false, true}) {
      options.extras.research_options = cheaper ? cheap : SessionOptions{};
      Run r{"seed " + std::to_string(seed), {}, 0, {}};
      std::size_t lost = 0;
      MemoryFrames src(other_frames);
      host::run_tracking(other_table, src, start, options, [&](const app::TrackRow& row) {
        r.poses.push_back({row.frame, row.step.pose.x, row.step.pose.y, row.step.pose.theta_deg, row.step.pose.depth, true});
        r.micros.push_back(row.micros);
        r.mean_us += row.micros / static_cast<double>(other_frames.size());
        lost += row.step.state == TrackState::kLost;
      });
      const app::Accuracy a = app::evaluate(r.poses, other_truth);
      std::string reacq;
      for (int v : a.reacquired_after) reacq += (reacq.empty() ? "" : ", ") + (v < 0 ? std::string("never") : std::to_string(v) + " frames");
      const auto pct = [&](std::size_t n) { return fmt(100.0 * static_cast<double>(n) / static_cast<double>(a.frames)) + "%"; };
      md << "| " << seed << " | " << (cheaper ? "every 2nd frame, 3rd feature" : "defaults") << " | " << pct(a.within_1px) << " | "
         << pct(a.within_1deg) << " | " << pct(a.depth_exact) << " | " << reacq << " | " << lost << " | " << fmt(r.mean_us) << " | "
         << fmt(r.median_us()) << " |\n";
    }
  }
  md << "\n";
}

// 4. Voting on two threads: the same features, counters compared, interleaved timing.
void two_threads_table(const Scene& sc, std::ostringstream& md) {
  const auto& frames = sc.frames;
  const auto& truth = sc.truth;
  const TableView& table = sc.table;
  const Pose& init = sc.init;
  std::vector<std::vector<RoiPoint>> per_frame;
  const Detector det = detector_of(table);
  for (std::size_t f = 0; f < frames.size(); ++f) {
    if (!truth[f].visible) continue;
    const ImageWindow w{static_cast<std::int32_t>(std::lround(truth[f].x)) + table.roi_origin_x(),
                        static_cast<std::int32_t>(std::lround(truth[f].y)) + table.roi_origin_y(), table.roi_width(), table.roi_height()};
    std::vector<RoiPoint> feats(static_cast<std::size_t>(table.roi_width()) * table.roi_height());
    FeatureCount n;
    if (extract_features(frames[f].view(), w, det.kind, det.threshold, feats, n) != Status::kOk) continue;
    feats.resize(n.written);
    per_frame.push_back(std::move(feats));
  }
  // One voter at a time: an idle voter's worker spins, and two of them
  // would compete for the cores. Each is timed interleaved with the reference.
  std::vector<VoteCounter> a(table.cell_count()), b(table.cell_count());
  bool identical = true;
  const auto measure = [&](host::ParallelVoter::Split split, double& one_us, double& two_us) {
    host::ParallelVoter voter(2, split);
    one_us = two_us = 1e30;
    for (int rep = 0; rep < 3; ++rep) {
      double t1 = 0, t2 = 0;
      for (const auto& feats : per_frame) {
        std::fill(a.begin(), a.end(), 0);
        std::fill(b.begin(), b.end(), 0);
        VoteTally ta, tb;
        auto t = Clock::now();
        if (accumulate_votes(table, feats, a, ta) != Status::kOk) throw app::Error("voting failed");
        t1 += micros_since(t);
        t = Clock::now();
        if (voter.accumulate(table, feats, b, tb) != Status::kOk) throw app::Error("parallel voting failed");
        t2 += micros_since(t);
        identical = identical && a == b && ta.votes == tb.votes;
      }
      one_us = std::min(one_us, t1 / static_cast<double>(per_frame.size()));
      two_us = std::min(two_us, t2 / static_cast<double>(per_frame.size()));
    }
  };
  double one_us = 0, cells_us = 0, one_b = 0, features_us = 0;
  measure(host::ParallelVoter::Split::kCells, one_us, cells_us);
  measure(host::ParallelVoter::Split::kFeatures, one_b, features_us);
  one_us = std::min(one_us, one_b);
  // The whole plain loop (features, vote, pose) with the vote on 1 and 2 threads.
  const auto loop_us = [&](unsigned threads) {
    host::TrackingOptions o;
    o.extras.voter = app::VoterChoice::kCsr;
    o.threads = threads;
    MemoryFrames src(frames);
    double total = 0;
    host::run_tracking(table, src, init, o, [&](const app::TrackRow& row) { total += row.micros; });
    return total / static_cast<double>(frames.size());
  };
  double loop_one = 1e30, loop_two = 1e30;
  for (int rep = 0; rep < 3; ++rep) {
    loop_one = std::min(loop_one, loop_us(1));
    loop_two = std::min(loop_two, loop_us(2));
  }
  // A control: two threads summing private arrays, no sharing at all. On a
  // machine that really runs two threads at once this approaches 2x.
  std::vector<double> xa(1 << 18, 1.0), xb(1 << 18, 1.0);
  const auto sum = [](const std::vector<double>& v) {
    double s = 0;
    for (int r = 0; r < 100; ++r)
      for (double x : v) s += x;
    return s;
  };
  auto t = Clock::now();
  volatile double sink = sum(xa) + sum(xb);
  const double serial = micros_since(t);
  t = Clock::now();
  double other = 0;
  std::thread helper([&] { other = sum(xb); });
  sink = sum(xa);
  helper.join();
  sink = sink + other;
  const double parallel = micros_since(t);
  md << "## Voting on two threads\n\nThe visible frames' features (" << per_frame.size()
     << " frames, best of 3, interleaved), the thesis reached 1.59x = 79% efficiency:\n\n"
     << "| voter | us/frame | speed-up | efficiency |\n|---|---:|---:|---:|\n"
     << "| 1 thread (reference) | " << fmt(one_us) << " | 1.00x | |\n"
     << "| 2 threads, cells split | " << fmt(cells_us) << " | " << fmt(one_us / cells_us, 2) << "x | "
     << fmt(50.0 * one_us / cells_us) << "% |\n"
     << "| 2 threads, features split, counters added | " << fmt(features_us) << " | **" << fmt(one_us / features_us, 2)
     << "x** | " << fmt(50.0 * one_us / features_us) << "% |\n\nCounters bit-identical: " << (identical ? "yes" : "NO")
     << ".\n\nThe whole plain loop (`gabarit track --threads 2`; features and pose update stay on one thread): "
     << fmt(loop_one) << " us/frame on 1 thread, " << fmt(loop_two) << " us/frame with the vote on 2: "
     << fmt(loop_one / loop_two, 2) << "x (best of 3)"
     << ".\n\nControl, two threads with nothing shared (private sums): " << fmt(serial / parallel, 2)
     << "x. Below about 1.8x the machine does not give two threads two cores' worth of time, and no voting speed-up can "
        "show.\n\n";
}

// 5. The translation policy for cells with non-integer bounds, on the
// thesis's binary curve sequence (30% noise, +-4 px per frame) with cells of
// 10/6 px, so no cell bound is an integer.
void translation_policy_table(const std::string& dir, bool quick, std::ostringstream& md) {
  namespace fs = std::filesystem;
  host::SynthOptions syn;
  syn.shape = host::random_closed_curve(200, 1);
  syn.frames = quick ? 120 : 300;
  syn.noise = 0.3;
  host::fit_image_to_shape(syn);
  const std::string bin_dir = (fs::path(dir) / "curve").string();
  const auto gt = host::write_synthetic_sequence(syn, bin_dir);
  std::vector<app::PoseSample> bin_truth;
  for (const auto& row : gt) bin_truth.push_back({row.frame, static_cast<double>(row.x), static_cast<double>(row.y), 0, 0, true});
  host::ModelStack curve;
  curve.depths.push_back(syn.shape);
  md << "## Translations of cells with non-integer bounds\n\nThe thesis's binary curve (200 points, 30% noise, "
     << syn.frames << " frames, +-4 px per frame), cells of 10/6 px over +-5 px (no integer bound), plain loop:\n\n"
     << "| policy | references | within 1 px | mean error px |\n|---|---:|---:|---:|\n";
  for (const auto policy : {host::TranslationPolicy::kInsideElseClosest, host::TranslationPolicy::kEnclosing}) {
    host::BuildOptions cb;
    cb.space.x = host::parse_axis("-5:5:7", "x");
    cb.space.y = host::parse_axis("-5:5:7", "y");
    cb.translations = policy;
    const auto bytes = host::build_table(curve, cb);
    TableView t;
    if (TableView::open(bytes, t) != Status::kOk) throw app::Error("microscope: curve table invalid");
    auto src = app::open_frames((fs::path(bin_dir) / "frames.y4m").string());
    std::vector<app::PoseSample> poses;
    host::run_tracking(t, *src, Pose{static_cast<float>(gt[0].x), static_cast<float>(gt[0].y), 0, 0}, std::nullopt,
                       [&](const app::TrackRow& row) { poses.push_back({row.frame, row.step.pose.x, row.step.pose.y, 0, 0, true}); });
    const app::Accuracy a = app::evaluate(poses, bin_truth);
    md << "| " << (policy == host::TranslationPolicy::kEnclosing ? "smallest enclosing integer range" : "inside, else closest (default)")
       << " | " << t.reference_count() << " | " << fmt(100.0 * static_cast<double>(a.within_1px) / static_cast<double>(a.frames))
       << "% | " << fmt(a.mean_error_px, 2) << " |\n";
  }
  md << "\n";
}

// A binary focus stack of `depths` depths: depth n is the curve scaled by 1 + 0.01 n.
host::ModelStack scaled_stack(const std::vector<host::Point>& curve, int depths) {
  host::ModelStack m;
  for (int d = 0; d < depths; ++d) {
    std::vector<host::Point> scaled;
    for (const auto& p : curve)
      scaled.push_back({static_cast<std::int32_t>(std::lround(p.x * (1 + 0.01 * d))), static_cast<std::int32_t>(std::lround(p.y * (1 + 0.01 * d)))});
    std::sort(scaled.begin(), scaled.end());
    scaled.erase(std::unique(scaled.begin(), scaled.end()), scaled.end());
    m.depths.push_back(scaled);
  }
  return m;
}

// 7. The thesis's Fig. 6.6: pre-processing time, references stored and
// tracking time against the model's feature count, for four state spaces.
void complexity_table(bool quick, std::ostringstream& md) {
  struct Setting {
    const char* name;
    const char* xy;
    const char* theta;
    int depths;
  };
  const Setting settings[] = {{"x, y +-5 px (121 cells)", "-5:5:11", "0:0:1", 1},
                              {"+ theta +-2 deg in 1-deg cells (605)", "-5:5:11", "-2:2:5", 1},
                              {"+ 4 depths (2,420)", "-5:5:11", "-2:2:5", 4},
                              {"x, y +-10 px, theta, 4 depths (8,820)", "-10:10:21", "-2:2:5", 4}};
  const std::vector<std::size_t> counts = quick ? std::vector<std::size_t>{250, 1000} : std::vector<std::size_t>{250, 500, 1000, 2000};
  md << "## Complexity (thesis Fig. 6.6)\n\nBinary models (random closed curves), plain loop on 30 frames of the "
        "model moving +-4 px with 5% noise; depth n is the model scaled by 1 + 0.01 n.\n\n"
     << "| state space | features | build ms | references | table MB | us/frame |\n|---|---:|---:|---:|---:|---:|\n";
  for (const Setting& st : settings) {
    for (const std::size_t n : counts) {
      const std::vector<host::Point> curve = host::random_closed_curve(n, 9);
      const host::ModelStack m = scaled_stack(curve, st.depths);
      host::BuildOptions b;
      b.space.x = host::parse_axis(st.xy, "x");
      b.space.y = host::parse_axis(st.xy, "y");
      b.space.theta = host::parse_axis(st.theta, "theta");
      const auto tb = Clock::now();
      const std::vector<std::byte> bytes = host::build_table(m, b);
      const double build_ms = micros_since(tb) / 1000;
      TableView t;
      if (TableView::open(bytes, t) != Status::kOk) throw app::Error("complexity: table invalid");
      host::SynthOptions syn;
      syn.shape = curve;
      syn.frames = 30;
      syn.noise = 0.05;
      syn.seed = 4;
      host::fit_image_to_shape(syn);
      app::Rng rng(syn.seed);
      std::vector<app::GrayImage> seq;
      std::int32_t x = static_cast<std::int32_t>(syn.width / 2), y = static_cast<std::int32_t>(syn.height / 2);
      const Pose start{static_cast<float>(x), static_cast<float>(y), 0, 0};
      for (std::uint32_t f = 0; f < syn.frames; ++f) {
        x += rng.uniform_int(-4, 4);
        y += rng.uniform_int(-4, 4);
        seq.push_back(host::render_frame(syn, x, y, syn.seed * 1000 + f));
      }
      MemoryFrames src(seq);
      double total = 0;
      host::run_tracking(t, src, start, std::nullopt, [&](const app::TrackRow& row) { total += row.micros; });
      md << "| " << st.name << " | " << curve.size() << " | " << fmt(build_ms) << " | " << t.reference_count() << " | "
         << fmt(static_cast<double>(bytes.size()) / 1e6, 2) << " | " << fmt(total / static_cast<double>(seq.size())) << " |\n";
    }
  }
  md << "\n";
}

// 6. Building a ~1000-feature 4-DOF table: 20x20 px x 10 depths x 4 deg.
void build_time_section(bool quick, std::ostringstream& md) {
  const host::ModelStack big = scaled_stack(host::random_closed_curve(1000, 5), 10);
  host::BuildOptions b;
  b.space.x = host::parse_axis("-10:10:21", "x");
  b.space.y = host::parse_axis("-10:10:21", "y");
  b.space.theta = host::parse_axis("-2:2:5", "theta");
  double best_ms = 1e30;
  std::size_t bytes = 0;
  for (int rep = 0; rep < (quick ? 1 : 3); ++rep) {
    const auto t = Clock::now();
    bytes = host::build_table(big, b).size();
    best_ms = std::min(best_ms, micros_since(t) / 1000);
  }
  md << "## Building a 4-DOF table\n\n" << big.depths[0].size() << " model features, x and y over 20 px in 1-px cells, "
     << "theta over 4 deg in 1-deg cells, 10 depths (22,050 cells): " << fmt(best_ms) << " ms on one core (best of "
     << (quick ? 1 : 3) << "), " << bytes << " bytes. Target: <= 2 s (the thesis: 12-167 s).\n";
}

}  // namespace

int run_microscope(const std::string& dir, bool quick) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  std::ostringstream md;
  md << "# The 4-DOF microscope experiment\n\n";
  md << "Machine: " << std::thread::hardware_concurrency() << " hardware threads. Reproduce: `gabarit bench --microscope"
     << (quick ? " --quick" : "") << " --out " << dir << "`.\n\n";
  const Scene scene = make_scene(dir, quick, md);
  accuracy_table(scene, dir, md);
  if (!quick) other_scenes_table(scene, dir, md);
  two_threads_table(scene, md);
  translation_policy_table(dir, quick, md);
  complexity_table(quick, md);
  build_time_section(quick, md);
  std::ofstream(fs::path(dir) / "microscope.md") << md.str();
  std::fputs(md.str().c_str(), stdout);
  return 0;
}

}  // namespace gabarit::bench
