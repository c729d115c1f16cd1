#include "suite.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

#include "gabarit/app/error.hpp"
#include "gabarit/host/runs/detection_run.hpp"
#include "gabarit/app/evaluation.hpp"
#include "gabarit/host/tables/model.hpp"
#include "gabarit/app/particle_run.hpp"
#include "gabarit/features.hpp"
#include "gabarit/host/scenes/scene_synth.hpp"
#include "gabarit/host/tables/table_builder.hpp"
#include "gabarit/host/runs/tracking_run.hpp"
#include "scene_io.hpp"
#include "suite_ledger.hpp"
#include "suite_results.hpp"
#include "suite_section64.hpp"

namespace gabarit::bench {
namespace {

using Clock = std::chrono::steady_clock;

bool detection_hit(const app::PoseSample& t, const Pose& p, bool depth_counts) {
  const double dt = std::remainder(static_cast<double>(p.theta_deg) - t.theta_deg, 360.0);
  return std::hypot(p.x - t.x, p.y - t.y) <= 2.0 && std::abs(dt) <= 1.0 && (!depth_counts || p.depth == t.depth);
}

// Scores a detector's poses (best first, per frame) against the truth.
template <class Detect>
DetectionMeasure measure_detection(const std::vector<app::GrayImage>& frames, const std::vector<app::PoseSample>& truth,
                                   bool depth_counts, Detect&& detect) {
  DetectionMeasure m;
  m.ran = true;
  for (std::size_t f = 0; f < frames.size() && f < truth.size(); ++f) {
    const auto t = Clock::now();
    const std::vector<Pose> poses = detect(frames[f]);
    m.mean_us += std::chrono::duration<double, std::micro>(Clock::now() - t).count() / static_cast<double>(frames.size());
    if (!truth[f].visible) {
      ++m.invisible;
      m.false_frames += !poses.empty();
      continue;
    }
    ++m.visible;
    m.top1 += !poses.empty() && detection_hit(truth[f], poses[0], depth_counts);
    bool any = false;
    for (std::size_t k = 0; k < poses.size() && k < 5; ++k) any = any || detection_hit(truth[f], poses[k], depth_counts);
    m.top5 += any;
  }
  return m;
}

// For each return to visibility after hidden frames (in order, as
// Accuracy::reacquired_after): whether the target reappears where the
// recovery grid reaches (recovery_search.hpp: the table's x, y and theta
// range around each of the grid's positions and turns) from either of its
// centres, where the target was last seen and where it would be had it kept
// its velocity then (taken here from the truth). Beyond is the detection
// issue's.
std::vector<bool> occlusions_in_reach(const std::vector<app::PoseSample>& truth, const TableView& table) {
  const RecoveryOptions recovery;
  const Axis ax = table.axis_x(), ay = table.axis_y(), at = table.axis_theta();
  const double reach_x = kSearchRings * search_step(ax) + ax.max, reach_y = kSearchRings * search_step(ay) + ay.max;
  const double reach_theta = kSearchTurns * recovery.turn_deg + at.max;
  const auto within = [&](const app::PoseSample& t, double x, double y, double theta) {
    return std::fabs(t.x - x) <= reach_x && std::fabs(t.y - y) <= reach_y && std::fabs(t.theta_deg - theta) <= reach_theta;
  };
  std::vector<bool> out;
  const app::PoseSample *last_seen = nullptr, *before = nullptr;
  bool hidden = false;
  for (const app::PoseSample& t : truth) {
    if (!t.visible) {
      hidden = true;
      continue;
    }
    if (hidden) {
      bool reach = false;
      if (last_seen != nullptr) {
        reach = within(t, last_seen->x, last_seen->y, last_seen->theta_deg);
        if (before != nullptr) {
          const double n = static_cast<double>(t.frame) - last_seen->frame;
          reach = reach || within(t, last_seen->x + n * (last_seen->x - before->x), last_seen->y + n * (last_seen->y - before->y),
                                  last_seen->theta_deg + n * (last_seen->theta_deg - before->theta_deg));
        }
      }
      out.push_back(reach);
    }
    hidden = false;
    before = last_seen;
    last_seen = &t;
  }
  return out;
}

Measure measure(const std::vector<app::PoseSample>& poses, const std::vector<app::PoseSample>& truth, std::vector<double> micros,
                bool depth_counts, const std::vector<bool>& in_reach) {
  const app::Accuracy a = app::evaluate(poses, truth);
  Measure m;
  const double n = a.frames ? static_cast<double>(a.frames) : 1.0;
  m.within_1px = 100.0 * static_cast<double>(a.within_1px) / n;
  m.within_2px = 100.0 * static_cast<double>(a.within_2px) / n;
  m.within_5px = 100.0 * static_cast<double>(a.within_5px) / n;
  m.failures_per_100 = 100.0 * static_cast<double>(a.failures) / n;
  m.within_1deg = 100.0 * static_cast<double>(a.within_1deg) / n;
  if (depth_counts) m.depth = 100.0 * static_cast<double>(a.depth_exact) / n;
  for (int r : a.reacquired_after) {
    m.reacquired = (r < 0 || m.reacquired < 0) ? -1 : std::max(m.reacquired, r);
    ++m.returns;
    m.back_within_5 += r >= 0 && r <= 5;
    m.back_within_10 += r >= 0 && r <= 10;
  }
  m.reacquired_in_reach = -2;
  for (std::size_t i = 0; i < a.reacquired_after.size() && i < in_reach.size(); ++i) {
    if (!in_reach[i]) continue;
    const int r = a.reacquired_after[i];
    m.reacquired_in_reach = (r < 0 || m.reacquired_in_reach == -1) ? -1 : std::max(m.reacquired_in_reach, r);
  }
  std::map<std::uint32_t, const app::PoseSample*> by_frame;
  for (const app::PoseSample& p : poses) by_frame[p.frame] = &p;
  double error_sum = 0;
  std::size_t close = 0;
  for (const app::PoseSample& g : truth) {
    const auto it = by_frame.find(g.frame);
    if (!g.visible || it == by_frame.end()) continue;
    const double e = std::hypot(it->second->x - g.x, it->second->y - g.y);
    if (e < 1.0) error_sum += e, ++close;
  }
  if (close > 0) m.subpixel_error = error_sum / static_cast<double>(close);
  m.frames = a.frames, m.mean_error_px = a.mean_error_px, m.timed_frames = micros.size();
  m.below_6px = a.below_6px, m.below_12px = a.below_12px, m.above_12px = a.above_12px;
  m.above_20px = a.above_20px, m.above_40px = a.above_40px;
  const host::TimingSummary t = host::summarise_timing(std::move(micros));
  m.mean_us = t.mean;
  m.p50_us = t.p50;
  m.p99_us = t.p99;
  m.max_us = t.max;
  return m;
}

// gabarit track --tracker particle's defaults (seed 1, and with
// particle_seeds > 1 seeds 2.. too, kept apart), and beside them --without
// proposals, on one scene's frames.
void run_particle_filters(const TableView& table, const std::vector<app::GrayImage>& frames, const std::vector<app::PoseSample>& truth,
                          const Pose& init, bool depth_counts, const std::vector<bool>& in_reach, std::uint32_t particle_seeds,
                          SceneResult& out) {
  for (std::uint32_t run = 0; run < particle_seeds + 1; ++run) {
    const bool guided = run < particle_seeds;
    const std::uint64_t seed = guided ? run + 1 : 1;
    std::vector<app::PoseSample> poses;
    std::vector<double> micros, search_micros;
    MemoryFrames src(frames);
    app::ParticleRunOptions po;
    po.seed = seed;
    if (!guided) po.proposals = 0;
    LedgerTally ledger;
    app::run_particle_tracking(table, src, init, po, [&](const app::TrackRow& row) {
      poses.push_back({row.frame, row.step.pose.x, row.step.pose.y, row.step.pose.theta_deg, row.step.pose.depth, true});
      micros.push_back(row.micros);
      ledger.add(row);
      // The frames its detection stage searched (after a lost frame).
      if (row.ledger.work[static_cast<std::uint32_t>(FramePhase::kRecovery)] > 0) search_micros.push_back(row.micros);
    });
    Measure m = measure(poses, truth, micros, depth_counts, in_reach);
    m.ledger = ledger.means();
    m.search_frames = search_micros.size();
    for (double v : search_micros) m.search_us += v / static_cast<double>(search_micros.size());
    if (guided && particle_seeds > 1) out.particle_seeds.push_back(m);
    if (seed != 1) continue;  // the other seeds count in issue 31's targets only
    out.methods.push_back(m);
    out.names.push_back(guided ? kParticle : kParticleUnguided);
  }
}

SceneResult run_scene(std::uint32_t index, std::uint32_t frames_per_scene, const std::filesystem::path& dir, bool peer, bool particles,
                      bool detection, std::uint32_t orientation_channels, std::uint32_t detect_after, std::uint32_t particle_seeds) {
  const host::SceneOptions so = host::suite_scene(index, frames_per_scene);
  char sub[16];
  std::snprintf(sub, sizeof sub, "%02u", index);
  const std::filesystem::path seq = dir / sub;
  host::write_scene_sequence(so, seq.string());
  const std::vector<app::GrayImage> frames = read_all_frames(seq / "frames.y4m");
  const auto truth = app::read_pose_csv((seq / "gt.csv").string());
  const std::vector<std::string> paths = scene_model_paths(seq, so.depths);
  std::vector<app::GrayImage> models;
  for (const std::string& p : paths) models.push_back(app::read_pgm(p));
  // The table every method's window matches: +-5 px in 1-px cells, +-1.5 deg
  // in 0.5-deg cells, every depth of the stack (the microscope bench's, one
  // pixel wider for the random walk's 2.5 px/frame plus reversals), built as
  // `gabarit tables build` does by default (Canny detector, images stored).
  host::BuildOptions bo;
  bo.space.x = host::parse_axis("-5:5:11", "x");
  bo.space.y = host::parse_axis("-5:5:11", "y");
  bo.space.theta = host::parse_axis("-1.5:1.5:7", "theta");
  bo.orientation_channels = orientation_channels;
  host::ImageModelOptions mo;
  mo.canny = true;  // gabarit tables build's default detector
  const std::vector<std::byte> bytes = host::build_table(host::model_from_images(paths, mo), bo);
  TableView table;
  if (TableView::open(bytes, table) != Status::kOk) throw app::Error("suite: table of scene " + std::to_string(index) + " invalid");
  const Pose init{static_cast<float>(truth[0].x), static_cast<float>(truth[0].y), static_cast<float>(truth[0].theta_deg),
                  static_cast<std::uint16_t>(truth[0].depth)};
  const bool depth_counts = so.depths > 1 && so.stack == host::FocusStackKind::kTilted;
  const std::vector<bool> in_reach = occlusions_in_reach(truth, table);

  SceneResult out;
  out.index = index;
  out.name = host::scene_name(so);
  out.family = host::suite_family(index);
  out.held_out = host::suite_held_out(index);
  // The defaults of gabarit track, of gabarit track --plain, and (with
  // particles) of gabarit track --recovery particle.
  const auto session_run = [&](bool robust, bool particle_recovery, const char* name, bool detection_recovery = false) {
    host::TrackingOptions options;
    options.profile = robust ? app::SessionProfile{} : app::plain_profile();
    if (detection_recovery) options.profile.recovery = app::RecoveryKind::kDetection;
    if (detection_recovery) options.profile.detect_after = detect_after;
    if (particle_recovery) options.profile.recovery = app::RecoveryKind::kParticles;
    std::vector<app::PoseSample> poses;
    std::vector<double> micros, lost_micros;
    MemoryFrames src(frames);
    LedgerTally ledger;
    host::run_tracking(table, src, init, options, [&](const app::TrackRow& row) {
      poses.push_back({row.frame, row.step.pose.x, row.step.pose.y, row.step.pose.theta_deg, row.step.pose.depth, true});
      micros.push_back(row.micros);
      ledger.add(row);
      if (row.step.state == TrackState::kLost || row.reacquired) lost_micros.push_back(row.micros);  // the frames that searched
    });
    out.methods.push_back(measure(poses, truth, micros, depth_counts, in_reach));
    Measure& m = out.methods.back();
    m.search_frames = lost_micros.size();
    for (double v : lost_micros) m.search_us += v / static_cast<double>(lost_micros.size());
    m.ledger = ledger.means();
    out.names.push_back(name);
  };
  session_run(false, false, kPlain);
  session_run(true, false, kSession);
  if (peer) {
    NccBank ncc(models, 5, 0.5, 3);
    Pose pose = init;
    std::vector<app::PoseSample> poses;
    std::vector<double> micros;
    for (std::uint32_t f = 0; f < frames.size(); ++f) {
      const auto t = Clock::now();
      pose = ncc.track(frames[f], pose);
      micros.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t).count());
      poses.push_back({f, pose.x, pose.y, pose.theta_deg, pose.depth, true});
    }
    out.methods.push_back(measure(poses, truth, micros, depth_counts, in_reach));
    out.names.push_back(kNcc);
  }
  if (particles) session_run(true, true, kSessionParticles);
  if (detection) {
    session_run(true, false, kSessionDetection, true);
    // Detection in every frame, no starting pose: gabarit detect's defaults.
    host::FrameDetector finder(table, detector_of(table), FinderOptions{});
    out.detection = measure_detection(frames, truth, depth_counts, [&](const app::GrayImage& frame) {
      std::vector<Pose> poses;
      for (const Detection& d : finder.detect(frame.view()).detections) poses.push_back(d.pose);
      return poses;
    });
    if (peer) {
      PyramidMatcher matcher(models, 2, 5.0, 5);
      out.opencv_detection = measure_detection(frames, truth, depth_counts, [&](const app::GrayImage& frame) {
        std::vector<Pose> poses;
        for (const PyramidDetection& d : matcher.detect(frame)) poses.push_back(d.pose);
        return poses;
      });
    }
  }
  if (particles) run_particle_filters(table, frames, truth, init, depth_counts, in_reach, particle_seeds, out);
  return out;
}

std::string reacq(int r) { return r == -2 ? "-" : r < 0 ? "never" : std::to_string(r); }

// The bar, scene by scene: the default session within 1 point of a
// peer (the NCC bank, the plain loop) on 1 px, 1 deg and depth exact; lists
// the scenes and metrics where it falls short.
void shortfalls_against(const std::vector<SceneResult>& scenes, std::size_t peer, std::ostringstream& md) {
  if (scenes.empty() || peer >= scenes[0].methods.size()) return;
  std::size_t level = 0;
  std::string list;
  for (const SceneResult& s : scenes) {
    const Measure &d = s.methods[1], &p = s.methods[peer];
    const std::pair<const char*, std::pair<double, double>> metrics[] = {
        {"1 px", {d.within_1px, p.within_1px}}, {"1 deg", {d.within_1deg, p.within_1deg}}, {"depth", {d.depth, p.depth}}};
    bool short_here = false;
    for (const auto& [metric, v] : metrics) {
      if (v.second < 0 || v.first >= v.second - 1.0) continue;
      list += (short_here ? ", " : std::string(list.empty() ? "" : "; ") + s.name + ": ") + metric + " " + fmt(v.first) + " vs " +
              fmt(v.second);
      short_here = true;
    }
    level += !short_here;
  }
  md << "Default session at least " << scenes[0].names[peer] << "'s figure minus 1 point (1 px, 1 deg, depth) on " << level << " of "
     << scenes.size() << " scenes" << (list.empty() ? "." : "; short on " + list + ".") << "\n\n";
}

// The particle filter, guided by the vote and not: how soon it finds the
// target again after an occlusion (issue 31: within 5 frames), per half.
void particle_reacquisition_table(const std::vector<SceneResult>& scenes, std::ostringstream& md) {
  const int guided = index_of(scenes, kParticle), unguided = index_of(scenes, kParticleUnguided);
  if (guided < 0 || unguided < 0) return;
  md << "| particle filter | half | occlusions re-acquired within 5 frames | within 10 | within 2 px: mean | within 1 deg: mean | "
        "us/frame: mean |\n|---|---|---:|---:|---:|---:|---:|\n";
  for (const int m : {guided, unguided}) {
    for (const bool held : {true, false}) {
      int returns = 0, within_5 = 0, within_10 = 0;
      double px2 = 0, deg1 = 0, us = 0, count = 0;
      for (const SceneResult& sr : scenes) {
        if (sr.held_out != held) continue;
        const Measure& r = sr.methods[static_cast<std::size_t>(m)];
        returns += r.returns, within_5 += r.back_within_5, within_10 += r.back_within_10;
        px2 += r.within_2px, deg1 += r.within_1deg, us += r.mean_us, ++count;
      }
      if (count == 0) continue;
      md << "| " << (m == guided ? "with vote proposals (default)" : "without (--without proposals)") << " | "
         << (held ? "held out" : "tuning") << " | " << within_5 << " of " << returns << " | " << within_10 << " of " << returns << " | "
         << fmt(px2 / count) << "% | " << fmt(deg1 / count) << "% | " << fmt(us / count) << " |\n";
    }
  }
  md << "\n";
}

// Median and worst over the scenes of one half, per method.
void summary_table(const std::vector<SceneResult>& scenes, const std::string& title, std::ostringstream& md) {
  if (scenes.empty()) return;
  const std::size_t methods = scenes[0].methods.size();
  md << "### " << title << " (" << scenes.size() << " scenes)\n\n"
     << "| method | within 1 px: median | worst | 2 px: median | worst | 5 px: median | worst | 1 deg: median | worst "
        "| depth exact: median | worst | failures per 100 frames: median | worst | reacquired: worst | in reach: worst "
        "| us/frame: mean | p99 (median over scenes) | max / p50: worst scene |\n"
     << "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (std::size_t m = 0; m < methods; ++m) {
    std::vector<double> px1, px2, px5, deg, depth, mean_us, p99, failures;
    double worst_spike = 0;
    int worst_reacq = 0, worst_in_reach = -2;
    for (const SceneResult& s : scenes) {
      const Measure& r = s.methods[m];
      px1.push_back(r.within_1px), px2.push_back(r.within_2px), px5.push_back(r.within_5px), deg.push_back(r.within_1deg);
      failures.push_back(r.failures_per_100);
      worst_spike = std::max(worst_spike, r.max_us / std::max(1e-9, r.p50_us));
      if (r.depth >= 0) depth.push_back(r.depth);
      mean_us.push_back(r.mean_us), p99.push_back(r.p99_us);
      worst_reacq = (r.reacquired < 0 || worst_reacq < 0) ? -1 : std::max(worst_reacq, r.reacquired);
      if (r.reacquired_in_reach != -2)
        worst_in_reach = (r.reacquired_in_reach == -1 || worst_in_reach == -1) ? -1 : std::max(worst_in_reach, r.reacquired_in_reach);
    }
    const auto worst = [](const std::vector<double>& v) { return v.empty() ? 0.0 : *std::min_element(v.begin(), v.end()); };
    double mean_all = 0;
    for (double v : mean_us) mean_all += v / static_cast<double>(mean_us.size());
    md << "| " << scenes[0].names[m] << " | " << fmt(median(px1)) << "% | " << fmt(worst(px1)) << "% | " << fmt(median(px2)) << "% | "
       << fmt(worst(px2)) << "% | " << fmt(median(px5)) << "% | " << fmt(worst(px5)) << "% | " << fmt(median(deg)) << "% | "
       << fmt(worst(deg)) << "% | " << (depth.empty() ? "-" : fmt(median(depth)) + "%") << " | "
       << (depth.empty() ? "-" : fmt(worst(depth)) + "%") << " | " << fmt(median(failures)) << " | "
       << fmt(*std::max_element(failures.begin(), failures.end())) << " | " << reacq(worst_reacq) << " | " << reacq(worst_in_reach)
       << " | " << fmt(mean_all) << " | " << fmt(median(p99)) << " | " << fmt(worst_spike) << " |\n";
  }
  // The promise: the default session never worse than the plain loop.
  double worst_gap = 1e9;
  std::string worst_scene, worst_metric;
  std::size_t better_median = 0;
  for (const SceneResult& s : scenes) {
    const Measure &p = s.methods[0], &d = s.methods[1];
    const std::pair<const char*, double> gaps[] = {{"1 px", d.within_1px - p.within_1px}, {"2 px", d.within_2px - p.within_2px},
                                                   {"1 deg", d.within_1deg - p.within_1deg},
                                                   {"depth", p.depth >= 0 ? d.depth - p.depth : 0.0}};
    for (const auto& [metric, gap] : gaps)
      if (gap < worst_gap) worst_gap = gap, worst_scene = s.name, worst_metric = metric;
    better_median += d.within_1px >= p.within_1px;
  }
  std::size_t in_reach = 0, within_10 = 0;
  for (const SceneResult& sr : scenes) {
    if (sr.methods[1].reacquired_in_reach == -2) continue;
    ++in_reach;
    within_10 += sr.methods[1].reacquired_in_reach >= 0 && sr.methods[1].reacquired_in_reach <= 10;
  }
  md << "\nDefault session minus plain loop, the worst scene and metric: " << fmt(worst_gap) << " points (" << worst_metric << ", "
     << worst_scene << "); the session is at least as good within 1 px on " << better_median << " of " << scenes.size()
     << " scenes; it reacquires within 10 frames on " << within_10 << " of the " << in_reach
     << " scenes whose occlusion ends within the recovery search's reach.";
  for (std::size_t m = 2; m < methods; ++m) {
    double other = 0, session = 0;
    for (const SceneResult& s : scenes) other += s.methods[m].mean_us, session += s.methods[1].mean_us;
    md << " " << scenes[0].names[m] << " time / default session time (mean over frames of all scenes): "
       << fmt(other / std::max(1e-9, session)) << "x.";
  }
  md << "\n\n";
  shortfalls_against(scenes, 0, md);
  for (std::size_t m = 2; m < methods; ++m)
    if (scenes[0].names[m] == std::string(kNcc)) shortfalls_against(scenes, m, md);
  // The two re-acquisition stages side by side, over every occlusion (not only those within the grid's reach).
  const int grid = index_of(scenes, kSession), particle = index_of(scenes, kSessionParticles);
  const int detect = index_of(scenes, kSessionDetection);
  if (grid >= 0 && (particle >= 0 || detect >= 0)) {
    md << "| re-acquisition | occlusions re-acquired within 10 frames | search frames | mean us per search frame |\n|---|---:|---:|---:|\n";
    for (const int m : {grid, particle, detect}) {
      if (m < 0) continue;
      int occlusions = 0, within = 0;
      std::size_t frames = 0;
      double us = 0;
      for (const SceneResult& sr : scenes) {
        const Measure& r = sr.methods[static_cast<std::size_t>(m)];
        occlusions += r.returns, within += r.back_within_10;
        us += r.search_us * static_cast<double>(r.search_frames);
        frames += r.search_frames;
      }
      md << "| " << (m == grid ? "grid search (default)" : m == particle ? "particle filter over the frame" : "detection over the frame")
         << " | " << within << " of " << occlusions
         << " | " << frames << " | " << fmt(frames ? us / static_cast<double>(frames) : 0.0) << " |\n";
    }
    md << "\n";
  }
  particle_reacquisition_table(scenes, md);
  // Detection: every frame searched with no starting pose.
  if (scenes[0].detection.ran) {
    md << "| detection (every frame, no pose) | top 1: median | worst | top 5: median | worst | frames without the target with a "
          "detection | us per frame: mean | median over scenes |\n|---|---:|---:|---:|---:|---:|---:|---:|\n";
    for (int which = 0; which < 2; ++which) {
      std::vector<double> t1, t5, us;
      int invisible = 0, false_frames = 0;
      double mean = 0;
      std::size_t n = 0;
      for (const SceneResult& sr : scenes) {
        const DetectionMeasure& d = which == 0 ? sr.detection : sr.opencv_detection;
        if (!d.ran) continue;
        t1.push_back(100.0 * d.top1 / std::max(1, d.visible));
        t5.push_back(100.0 * d.top5 / std::max(1, d.visible));
        us.push_back(d.mean_us);
        mean += d.mean_us;
        ++n;
        invisible += d.invisible, false_frames += d.false_frames;
      }
      if (n == 0) continue;
      const auto worst = [](const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); };
      md << "| " << (which == 0 ? "gabarit detect (defaults)" : "OpenCV pyramid matchTemplate (2 levels, 5 deg, 5 peaks refined)") << " | "
         << fmt(median(t1)) << "% | " << fmt(worst(t1)) << "% | " << fmt(median(t5)) << "% | " << fmt(worst(t5)) << "% | " << false_frames
         << " of " << invisible << " | " << fmt(mean / static_cast<double>(n), 0) << " | " << fmt(median(us), 0) << " |\n";
    }
    md << "\nA hit: the true pose within 2 px and 1 deg (and the depth, on tilted stacks), over the visible frames.\n\n";
  }
}

// Where each session's time goes, per phase (suite_ledger.hpp), and the
// NCC bank's time over the default session's.
void ledger_table(const std::vector<SceneResult>& scenes, const std::string& title, std::ostringstream& md) {
  if (scenes.empty()) return;
  std::vector<std::pair<std::string, std::vector<LedgerMeans>>> methods;
  for (std::size_t m = 0; m < scenes[0].methods.size(); ++m) {
    methods.push_back({scenes[0].names[m], {}});
    for (const SceneResult& s : scenes) methods.back().second.push_back(s.methods[m].ledger);
  }
  bench::ledger_table(title, methods, md);
  // The speed target (issue: the default session at most 1/30 of the NCC
  // bank's time on every scene): the ratio scene by scene.
  for (std::size_t m = 2; m < scenes[0].methods.size(); ++m) {
    if (scenes[0].names[m] != std::string(kNcc)) continue;
    std::vector<double> ratios;
    double worst = 1e300;
    std::string worst_scene;
    for (const SceneResult& s : scenes) {
      const double r = s.methods[m].mean_us / std::max(1e-9, s.methods[1].mean_us);
      ratios.push_back(r);
      if (r < worst) worst = r, worst_scene = s.name;
    }
    md << "NCC bank time / default session time, scene by scene (means over frames): median " << fmt(median(ratios), 2)
       << "x, worst " << fmt(worst, 2) << "x (" << worst_scene << ").\n\n";
  }
}

}  // namespace

int run_suite(const SuiteOptions& o) {
  namespace fs = std::filesystem;
  if (o.first >= host::kSuiteScenes && o.scenes == 0) throw app::Error("--first: the suite's last scene is " + std::to_string(host::kSuiteScenes - 1));
  // Quick: every 5th scene, both halves and some families (60 frames each).
  const std::uint32_t stride = o.quick && o.scenes == 0 ? 5 : 1;
  const std::uint32_t scenes = o.scenes ? o.scenes : (host::kSuiteScenes - o.first + stride - 1) / stride;
  const std::uint32_t frames = o.frames ? o.frames : (o.quick ? 60 : 160);
  const fs::path dir = fs::path(o.out) / "suite";
  fs::create_directories(dir);
  const auto start = Clock::now();
  std::vector<SceneResult> results;
  std::ostringstream csv;
  std::ostringstream detection_csv;
  detection_csv << "index,name,half,detector,visible,top1,top5,invisible,false_frames,mean_us\n";
  csv << "index,name,half,method,within_1px,within_2px,within_1deg,depth_exact,reacquired_after,reacquired_in_reach,mean_us,p99_us,"
         "within_5px,failures_per_100,p50_us,max_us,family";
  csv << ledger_csv_header() << ",subpixel_error_px\n";
  for (std::uint32_t n = 0; n < scenes; ++n) {
    const std::uint32_t i = o.first + n * stride;
    std::fprintf(stderr, "\rsuite: scene %u/%u %-48s", n + 1, scenes, host::scene_name(host::suite_scene(i, frames)).c_str());
    results.push_back(run_scene(i, frames, dir, o.peer, o.particles, o.detection, o.orientation_channels, o.detect_after,
                                o.particle_seeds));
    const SceneResult& r = results.back();
    for (std::size_t m = 0; m < r.methods.size(); ++m) {
      const Measure& x = r.methods[m];
      csv << r.index << "," << r.name << "," << (r.held_out ? "held-out" : "tuning") << "," << r.names[m] << "," << fmt(x.within_1px)
          << "," << fmt(x.within_2px) << "," << fmt(x.within_1deg) << "," << (x.depth < 0 ? "" : fmt(x.depth)) << ","
          << x.reacquired << "," << x.reacquired_in_reach << "," << fmt(x.mean_us) << "," << fmt(x.p99_us) << "," << fmt(x.within_5px)
          << "," << fmt(x.failures_per_100) << "," << fmt(x.p50_us) << "," << fmt(x.max_us) << "," << host::name_of(r.family);
      csv << ledger_csv_columns(x.ledger);  // empty for a method without one (the NCC bank)
      csv << "," << (x.subpixel_error < 0 ? "" : fmt(x.subpixel_error, 3)) << "\n";
    }
    for (int which = 0; which < 2; ++which) {
      const DetectionMeasure& d = which == 0 ? r.detection : r.opencv_detection;
      if (!d.ran) continue;
      detection_csv << r.index << "," << r.name << "," << (r.held_out ? "held-out" : "tuning") << ","
                    << (which == 0 ? "gabarit detect" : "OpenCV pyramid") << "," << d.visible << "," << d.top1 << "," << d.top5 << ","
                    << d.invisible << "," << d.false_frames << "," << fmt(d.mean_us) << "\n";
    }
  }
  std::fprintf(stderr, "\n");
  std::ostringstream md;
  md << "# gabarit bench --suite\n\n" << scenes << " scenes of " << frames
     << " frames (`gabarit synth --suite`, docs/scene-suite.md), each tracked from its first true pose with its own table "
        "(Canny detector, model images stored, x and y -5..5 px in 1-px cells, theta -1.5..1.5 deg in 0.5-deg cells, every depth"
     << (o.orientation_channels ? ", " + std::to_string(o.orientation_channels) + " orientation channels" : std::string()) << "). "
        "Accuracy over the visible frames; depth only on tilted stacks (distinguishable depths); 'reacquired' is the "
        "worst number of frames after an occlusion until the pose is within 2 px again ('in reach': over the occlusions "
        "after which the target reappears within the recovery grid's reach of where it was last seen; '-': none). One thread; "
        "the Canny rows and the dense voter's adders run the "
     << canny_vector_body() << " body.\n\n";
  std::vector<SceneResult> tuning, held_out;
  for (const SceneResult& r : results) (r.held_out ? held_out : tuning).push_back(r);
  md << "## Summary\n\n";
  summary_table(held_out, "Held-out half (never tuned on)", md);
  ledger_table(held_out, "Held-out half", md);
  section64_table(held_out, "held-out half", md);
  summary_table(tuning, "Tuning half", md);
  ledger_table(tuning, "Tuning half", md);
  section64_table(tuning, "tuning half", md);
  md << "## Per scene\n\n| # | scene | family | half | method | 1 px | 2 px | 5 px | 1 deg | depth | failures / 100 | reacquired | in reach "
        "| us/frame mean | p50 | p99 | max |\n|---:|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const SceneResult& r : results)
    for (std::size_t m = 0; m < r.methods.size(); ++m) {
      const Measure& x = r.methods[m];
      md << "| " << r.index << " | " << r.name << " | " << host::name_of(r.family) << " | " << (r.held_out ? "held-out" : "tuning")
         << " | " << r.names[m] << " | " << fmt(x.within_1px) << " | " << fmt(x.within_2px) << " | " << fmt(x.within_5px) << " | "
         << fmt(x.within_1deg) << " | " << (x.depth < 0 ? "-" : fmt(x.depth)) << " | " << fmt(x.failures_per_100) << " | "
         << reacq(x.reacquired) << " | " << reacq(x.reacquired_in_reach) << " | " << fmt(x.mean_us) << " | " << fmt(x.p50_us) << " | "
         << fmt(x.p99_us) << " | " << fmt(x.max_us) << " |\n";
    }
  md << "\nWhole run: " << fmt(std::chrono::duration<double>(Clock::now() - start).count()) << " s.\n";
  std::ofstream(fs::path(o.out) / "suite.md") << md.str();
  std::ofstream(fs::path(o.out) / "suite-scenes.csv") << csv.str();
  if (o.detection) std::ofstream(fs::path(o.out) / "suite-detection.csv") << detection_csv.str();
  std::cerr << "wrote " << (fs::path(o.out) / "suite.md").string() << "\n";
  return 0;
}

}  // namespace gabarit::bench
