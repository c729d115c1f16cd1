#include "decimation_study.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>

#include "experiments.hpp"
#include "gabarit/app/scratch.hpp"
#include "gabarit/dense_voter.hpp"
#include "gabarit/app/error.hpp"
#include "gabarit/host/tables/decimation.hpp"
#include "gabarit/host/tables/state_space.hpp"
#include "gabarit/host/scenes/synth.hpp"
#include "gabarit/host/tables/table_budget.hpp"
#include "gabarit/host/tables/table_builder.hpp"
#include "gabarit/host/tables/template_reduction.hpp"
#include "gabarit/host/scenes/thesis_shapes.hpp"
#include "gabarit/app/svg_plot.hpp"

namespace gabarit::bench {
namespace {

using Clock = std::chrono::steady_clock;

struct StudyShape {
  Shape shape;
  bool held_out = false;
  std::uint32_t sequence_frames = 500;
};

struct NamedPolicy {
  std::string name;
  host::DecimationPolicy policy;
};

std::vector<NamedPolicy> study_policies() {
  std::vector<NamedPolicy> out;
  const auto add = [&](const std::string& name, auto&& edit) {
    host::DecimationPolicy p;
    p.spread = false;  // each name says what it adds
    edit(p);
    out.push_back({name, p});
  };
  add("global", [](auto& p) { p.method = host::Decimation::kGlobal; });
  add("uniform", [](auto& p) { p.method = host::Decimation::kUniform; });
  add("stencil", [](auto&) {});
  add("stencil power:2", [](auto& p) { p.weight = host::RemovalWeight::kPower; });
  add("stencil power:3", [](auto& p) { p.weight = host::RemovalWeight::kPower, p.power = 3; });
  add("stencil greedy", [](auto& p) { p.weight = host::RemovalWeight::kGreedy; });
  add("stencil rival", [](auto& p) { p.weight = host::RemovalWeight::kRival; });
  add("stencil most-overlapping", [](auto& p) { p.most_overlapping = true; });
  add("stencil spread", [](auto& p) { p.spread = true; });
  add("stencil rival spread", [](auto& p) { p.weight = host::RemovalWeight::kRival, p.spread = true; });
  return out;
}

std::vector<StudyShape> study_shapes(bool quick) {
  std::vector<StudyShape> out;
  out.push_back({make_shape("curve", host::thesis_curve()), false, 500});
  out.push_back({make_shape("watch", host::watch_shape()), false, 800});
  out.push_back({make_shape("curve-b", host::random_closed_curve(191, 31)), true, 500});
  if (!quick) {
    out.push_back({make_shape("curve-c", host::random_closed_curve(600, 32)), true, 500});
    const app::GrayImage camera = app::read_pgm(host::debian_photo_pgm("camera"));
    out.push_back({make_shape("camera", host::photo_edge_points(camera, 1500, 2)), true, 800});
  }
  if (quick)
    for (auto& s : out) s.sequence_frames = 120;
  return out;
}

struct SequenceRow {
  std::string shape, policy;
  double noise = 0, keep = 1;
  std::size_t frames = 0, exact = 0;
  double mean_us = 0;
  std::size_t table_bytes = 0;
};

// Continuous sequences: every variant (policy x keep) tracks the same frames
// in lockstep, each from its own previous estimate.
std::vector<SequenceRow> run_sequences(const std::vector<StudyShape>& shapes, const std::vector<NamedPolicy>& policies,
                                       const std::vector<double>& noises, const std::vector<double>& keeps, unsigned threads) {
  const std::size_t variants = policies.size() * keeps.size();
  std::vector<std::vector<std::vector<std::byte>>> tables(shapes.size());
  for (std::size_t s = 0; s < shapes.size(); ++s)
    for (const NamedPolicy& p : policies)
      for (double keep : keeps) tables[s].push_back(shape_table(shapes[s].shape, keep, 1, p.policy));
  const std::size_t jobs = shapes.size() * noises.size();
  std::vector<SequenceRow> rows(jobs * variants);
  std::atomic<std::size_t> next{0}, done{0};
  std::mutex progress;
  const auto worker = [&] {
    for (std::size_t job; (job = next++) < jobs;) {
      const std::size_t s = job / noises.size(), n = job % noises.size();
      host::SynthOptions o;
      o.shape = shapes[s].shape.points;
      o.frames = shapes[s].sequence_frames;
      o.max_step = kMaxStep;
      o.velocity_walk = true;
      o.noise = noises[n];
      o.seed = 7001 + job;
      host::fit_image_to_shape(o);
      const std::vector<host::TruthRow> truth = host::synthetic_trajectory(o);
      std::vector<std::unique_ptr<Estimator>> trackers;
      std::vector<Point> at(variants, Point{truth[0].x, truth[0].y});
      std::vector<std::size_t> exact(variants, 0);
      std::vector<double> micros(variants, 0);
      for (std::size_t v = 0; v < variants; ++v) trackers.push_back(hough(tables[s][v], "hough"));
      for (const host::TruthRow& t : truth) {
        Trial trial;
        trial.frame = host::render_frame(o, t.x, t.y, host::synthetic_frame_seed(o, t.frame));
        trial.truth = {t.x, t.y};
        for (std::size_t k = 0; k < variants; ++k) {
          const std::size_t v = (k + t.frame) % variants;  // rotate who meets the cold frame
          trial.previous = at[v];
          const auto t0 = Clock::now();
          at[v] = trackers[v]->estimate(trial);
          micros[v] += std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
          exact[v] += at[v].x == t.x && at[v].y == t.y;
        }
      }
      for (std::size_t v = 0; v < variants; ++v) {
        rows[job * variants + v] = {shapes[s].shape.name, policies[v / keeps.size()].name, noises[n], keeps[v % keeps.size()],
                                    truth.size(), exact[v], micros[v] / static_cast<double>(truth.size()), tables[s][v].size()};
      }
      const std::size_t d = ++done;
      std::lock_guard<std::mutex> lock(progress);
      std::fprintf(stderr, "\rdecimation: sequences %zu/%zu", d, jobs);
      if (d == jobs) std::fputc('\n', stderr);
    }
  };
  std::vector<std::thread> pool;
  for (unsigned i = 1; i < std::max(1u, threads); ++i) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  return rows;
}

std::string percent(double v) {
  std::ostringstream s;
  s << static_cast<int>(v * 100 + 0.5) << "%";
  return s.str();
}
std::string keep_label(double k) {
  std::ostringstream s;
  s << k * 100 << "%";
  return s.str();
}

// The highest noise level up to which every level passes (no wrong frame):
// -1 when even the lowest fails.
template <class Row, class Pass>
double noise_reached(const std::vector<Row>& rows, const std::vector<double>& noises, Pass&& pass) {
  double reached = -1;
  for (double n : noises) {
    const auto it = std::find_if(rows.begin(), rows.end(), [&](const Row& r) { return r.noise == n; });
    if (it == rows.end() || !pass(*it)) break;
    reached = n;
  }
  return reached;
}

std::string reached_text(double r) { return r < 0 ? "none" : percent(r); }

// Voting time alone (features extracted beforehand), per frame, for the CSR
// voter, the dense voter and the cost model's choice, interleaved frame by
// frame, best of three passes.
struct VoteTiming {
  double keep = 1;
  std::size_t bytes = 0;
  double refs_per_feature = 0;
  double csr_us = 0, dense_us = 0, auto_us = 0;
  bool auto_dense = false;
};
std::vector<std::byte> rotation_table(const Shape& shape, double keep, const std::string& theta) {
  host::ModelStack model;
  model.depths.push_back(shape.points);
  model.detector.kind = table_format::DetectorKind::kBinary;
  host::BuildOptions b;
  b.space.x = host::parse_axis(kCellAxis, "x");
  b.space.y = host::parse_axis(kCellAxis, "y");
  b.space.theta = host::parse_axis(theta, "theta");
  b.keep = keep;
  return host::build_table(model, b);
}

std::vector<VoteTiming> time_voting(const Shape& shape, const std::vector<double>& keeps, std::size_t frames,
                                    const std::string& theta = "0:0:1") {
  const std::vector<Trial> trials = make_trials(shape, 0.2, frames, 99);
  std::vector<VoteTiming> out;
  for (double keep : keeps) {
    const std::vector<std::byte> bytes = rotation_table(shape, keep, theta);
    TableView table;
    if (TableView::open(bytes, table) != Status::kOk) throw app::Error("bench: invalid table");
    app::TrackerBuffers csr(table, app::VoterChoice::kCsr), dense(table, app::VoterChoice::kDense), chosen(table, app::VoterChoice::kAuto);
    // Features of every trial, once.
    std::vector<std::vector<RoiPoint>> features;
    for (const Trial& t : trials) {
      TrackerScratch sc = csr.scratch();
      PreparedFrame f;
      const Pose previous{static_cast<float>(t.previous.x), static_cast<float>(t.previous.y), 0, 0};
      if (prepare_frame(table, {table_format::DetectorKind::kBinary, 0}, t.frame.view(), previous, sc, f) != Status::kOk)
        throw app::Error("bench: prepare_frame failed");
      features.emplace_back(sc.features.begin(), sc.features.begin() + f.features);
    }
    VoteTiming row{keep, bytes.size(), 0, 1e300, 1e300, 1e300, !chosen.scratch().dense_masks.empty()};
    std::uint64_t votes = 0, feature_count = 0;
    for (int pass = 0; pass < 3; ++pass) {
      double sum[3] = {0, 0, 0};
      for (std::size_t i = 0; i < features.size(); ++i) {
        for (int k = 0; k < 3; ++k) {
          const int which = (k + static_cast<int>(i)) % 3;
          app::TrackerBuffers& b = which == 0 ? csr : which == 1 ? dense : chosen;
          TrackerScratch sc = b.scratch();
          VoteTally tally;
          const auto t0 = Clock::now();
          Status st = clear_counters(table, sc.counters);
          if (st == Status::kOk) {
            // As track_step votes: dense masks, else the expanded offsets of a compact table, else its own.
            st = !sc.dense_masks.empty()
                     ? accumulate_votes_dense(table, sc.dense_masks, features[i], sc.counters, sc.dense_scratch, tally)
                 : !sc.expanded_offsets.empty() ? accumulate_votes_expanded(table, sc.expanded_offsets, features[i], sc.counters, tally)
                                                : accumulate_votes(table, features[i], sc.counters, tally);
          }
          sum[which] += std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
          if (st != Status::kOk) throw app::Error("bench: voting failed");
          if (pass == 0 && which == 0) votes += tally.votes, feature_count += tally.features;
        }
      }
      row.csr_us = std::min(row.csr_us, sum[0] / features.size());
      row.dense_us = std::min(row.dense_us, sum[1] / features.size());
      row.auto_us = std::min(row.auto_us, sum[2] / features.size());
    }
    row.refs_per_feature = static_cast<double>(votes) / static_cast<double>(std::max<std::uint64_t>(1, feature_count));
    out.push_back(row);
  }
  return out;
}

// Reduced template, decimated stencils and both, at equal table bytes:
// wrong one-step frames per noise level.
struct ReductionRow {
  std::string shape;
  std::uint32_t k = 0;
  std::size_t points = 0;
  std::size_t bytes[3] = {0, 0, 0};       // reduced, decimated, both
  double reached[3] = {-1, -1, -1};       // highest noise with no wrong frame
  std::size_t wrong[3] = {0, 0, 0};       // over the noise levels
};

std::vector<std::byte> point_table(const std::vector<Point>& points, double keep, const host::Budget* budget) {
  host::ModelStack model;
  model.depths.push_back(points);
  model.detector.kind = table_format::DetectorKind::kBinary;
  host::BuildOptions b;
  b.space.x = host::parse_axis(kCellAxis, "x");
  b.space.y = host::parse_axis(kCellAxis, "y");
  b.keep = keep;
  if (budget == nullptr) return host::build_table(model, b);
  host::BudgetReport report;
  return host::build_table_to_budget(model, b, *budget, report);
}

std::vector<ReductionRow> compare_reduction(const std::vector<StudyShape>& shapes, const std::vector<double>& noises, std::size_t frames) {
  std::vector<std::int32_t> centres;
  for (int i = -5; i <= 5; ++i) centres.push_back(i);
  const std::vector<Point> shifts = host::translation_differences(centres, centres);
  std::vector<ReductionRow> out;
  for (const StudyShape& s : shapes) {
    if (s.shape.name == "camera") continue;  // the large shapes' runs are long; watch stands for them
    for (std::uint32_t k : {5u, 10u, 20u, 40u}) {
      ReductionRow row;
      row.shape = s.shape.name;
      row.k = k;
      const host::ReductionResult r = host::reduce_template(s.shape.points, shifts, k, host::ReductionOrder::kGreedy, 1, 1);
      row.points = r.points.size();
      std::vector<std::vector<std::byte>> tables;
      tables.push_back(point_table(r.points, 1.0, nullptr));
      host::Budget budget;
      budget.max_bytes = tables[0].size();
      try {
        tables.push_back(point_table(s.shape.points, 1.0, &budget));
      } catch (const app::Error&) {
        tables.push_back(point_table(s.shape.points, 1e-6, nullptr));  // cannot get as small: the smallest (its bytes say so)
      }
      // Both: a template reduced half as far (2K), decimated to the same bytes.
      const host::ReductionResult r2 = host::reduce_template(s.shape.points, shifts, std::min(2 * k, r.full_value),
                                                             host::ReductionOrder::kGreedy, 1, 1);
      try {
        tables.push_back(point_table(r2.points, 1.0, &budget));
      } catch (const app::Error&) {
        tables.push_back(tables[0]);  // the 2K template's smallest table does not fit: same as the reduced one
      }
      for (int v = 0; v < 3; ++v) {
        row.bytes[v] = tables[static_cast<std::size_t>(v)].size();
        auto est = hough(tables[static_cast<std::size_t>(v)], "hough");
        bool still = true;
        for (std::size_t n = 0; n < noises.size(); ++n) {
          std::size_t wrong = 0;
          for (const Trial& t : make_trials(s.shape, noises[n], frames, 4242 + n)) {
            const Point e = est->estimate(t);
            wrong += e.x != t.truth.x || e.y != t.truth.y;
          }
          row.wrong[v] += wrong;
          if (still && wrong == 0) row.reached[v] = noises[n];
          else still = false;
        }
      }
      out.push_back(row);
    }
  }
  return out;
}

}  // namespace

namespace {

// Per policy and half: the sum of the one-step wrong frames over the grid
// (keep < 1), and the continuous sequences passed.
void report_policy_summary(const std::vector<StudyShape>& shapes, const std::vector<NamedPolicy>& policies,
                           const std::vector<GridRow>& grid, const std::vector<SequenceRow>& seq, std::ostringstream& md) {
  md << "## Summary per policy (keep < 100%)\n\n"
     << "| policy | one-step wrong, tuning | one-step wrong, held out | sequences all exact, tuning | sequences all exact, held out |\n"
     << "|---|---:|---:|---:|---:|\n";
  for (const auto& p : policies) {
    const std::string name = host::describe(p.policy);
    std::size_t wrong[2] = {0, 0}, passed[2] = {0, 0}, total[2] = {0, 0};
    for (const GridRow& r : grid) {
      if (r.policy != name || r.keep == 1.0) continue;
      const bool held = std::find_if(shapes.begin(), shapes.end(), [&](const StudyShape& s) { return s.shape.name == r.shape; })->held_out;
      wrong[held] += r.wrong;
    }
    for (const SequenceRow& r : seq) {
      if (r.policy != p.name || r.keep == 1.0) continue;
      const bool held = std::find_if(shapes.begin(), shapes.end(), [&](const StudyShape& s) { return s.shape.name == r.shape; })->held_out;
      passed[held] += r.exact == r.frames;
      ++total[held];
    }
    md << "| " << p.name << " | " << wrong[0] << " | " << wrong[1] << " | " << passed[0] << "/" << total[0] << " | " << passed[1] << "/"
       << total[1] << " |\n";
  }

}

// The rest of a table's header after "| policy |": one column per keep.
void keep_columns(const std::vector<double>& keeps, std::ostringstream& md) {
  for (double k : keeps) md << ' ' << keep_label(k) << " |";
  md << "\n|---|";
  for (std::size_t i = 0; i < keeps.size(); ++i) md << "---:|";
  md << '\n';
}

// One shape: the highest noise every sequence frame is exact up to, and the
// one-step trials', per policy and keep; the default policy's bytes and
// time per keep; its heat maps.
void report_shape(const DecimationStudyOptions& o, const StudyShape& s, const std::vector<NamedPolicy>& policies,
                  const std::vector<double>& noises, const std::vector<double>& keeps, const std::vector<GridRow>& grid,
                  const std::vector<SequenceRow>& seq, const GridSpec& spec, std::ostringstream& md) {
  md << "\n## `" << s.shape.name << "`: continuous sequences (" << s.sequence_frames
     << " frames), highest noise with every frame exact\n\n| policy |";
  keep_columns(keeps, md);
  for (const auto& p : policies) {
    md << "| " << p.name << " |";
    for (double k : keeps) {
      std::vector<SequenceRow> rows;
      for (const auto& r : seq)
        if (r.shape == s.shape.name && r.policy == p.name && r.keep == k) rows.push_back(r);
      md << ' ' << reached_text(noise_reached(rows, noises, [](const SequenceRow& r) { return r.exact == r.frames; })) << " |";
    }
    md << '\n';
  }
  md << "\nOne-step trials (" << spec.frames << " per point), highest noise with no wrong frame:\n\n| policy |";
  keep_columns(keeps, md);
  for (const auto& p : policies) {
    md << "| " << p.name << " |";
    const std::string name = host::describe(p.policy);
    for (double k : keeps) {
      std::vector<GridRow> rows;
      for (const auto& r : grid)
        if (r.shape == s.shape.name && r.policy == name && r.keep == k) rows.push_back(r);
      md << ' ' << reached_text(noise_reached(rows, noises, [](const GridRow& r) { return r.wrong == 0; })) << " |";
    }
    md << '\n';
  }
  // Bytes and time per keep for the default policy (the sequences' mean µs per frame, all noise levels).
  md << "\nThe default policy (`" << host::describe(host::DecimationPolicy{}) << "`): table bytes and mean µs per frame over the sequences\n\n"
     << "| keep | table bytes | of full | µs/frame | speed-up |\n|---:|---:|---:|---:|---:|\n";
  double full_us = 0;
  std::size_t full_bytes = 0;
  for (double k : keeps) {
    double us = 0;
    std::size_t bytes = 0, count = 0;
    for (const auto& r : seq)
      if (r.shape == s.shape.name && r.policy == "stencil" && r.keep == k) us += r.mean_us, bytes = r.table_bytes, ++count;
    us /= std::max<std::size_t>(1, count);
    if (k == 1.0) full_us = us, full_bytes = bytes;
    char line[160];
    std::snprintf(line, sizeof line, "| %s | %zu | %.1f%% | %.1f | %.2fx |\n", keep_label(k).c_str(), bytes,
                  100.0 * static_cast<double>(bytes) / static_cast<double>(std::max<std::size_t>(1, full_bytes)), us, full_us / us);
    md << line;
  }

  // Heat maps: wrong frames of the default policy's sequences, and time.
  std::vector<std::string> xl, yl;
  for (double k : keeps) xl.push_back(keep_label(k));
  for (double n : noises) yl.push_back(percent(n));
  std::vector<std::vector<double>> wrong(noises.size(), std::vector<double>(keeps.size(), 0)), time = wrong;
  for (const auto& r : seq) {
    if (r.shape != s.shape.name || r.policy != "stencil") continue;
    const auto ni = static_cast<std::size_t>(std::find(noises.begin(), noises.end(), r.noise) - noises.begin());
    const auto ki = static_cast<std::size_t>(std::find(keeps.begin(), keeps.end(), r.keep) - keeps.begin());
    wrong[ni][ki] = static_cast<double>(r.frames - r.exact);
    time[ni][ki] = r.mean_us;
  }
  double max_time = 0;
  for (const auto& row : time) max_time = std::max(max_time, *std::max_element(row.begin(), row.end()));
  app::svg::write(o.out + "/decimation_wrong_" + s.shape.name + ".svg",
             app::svg::heatmap(s.shape.name + ": wrong frames of " + std::to_string(s.sequence_frames) + " (default policy)", "references kept",
                          xl, "noise", yl, wrong, static_cast<double>(s.sequence_frames)));
  app::svg::write(o.out + "/decimation_time_" + s.shape.name + ".svg",
             app::svg::heatmap(s.shape.name + ": us per frame (default policy)", "references kept", xl, "noise", yl, time, max_time));
  md << "\n![wrong frames](decimation_wrong_" << s.shape.name << ".svg) ![time](decimation_time_" << s.shape.name << ".svg)\n";
}

// Voting time per keep ratio, one run, single thread (the thesis's decimation gain).
void report_voting_time(const DecimationStudyOptions& o, const std::vector<StudyShape>& shapes, const std::vector<double>& keeps,
                        std::ostringstream& md) {
  md << "\n## Voting time per frame (features extracted beforehand; 20% noise, one-step trials, best of 3)\n\n"
     << "The voter the cost model picks (`auto`, dense_voter.hpp's dense_voter_pays_off) is marked.\n\n"
     << "| shape, cells | keep | table bytes | refs per feature | CSR µs | dense µs | auto µs (choice) | auto vs full |\n"
     << "|---|---:|---:|---:|---:|---:|---:|---:|\n";
  struct Space {
    std::size_t shape;
    std::string theta, label;
  };
  const std::vector<Space> spaces = {{0, "0:0:1", "curve, 121"}, {1, "0:0:1", "watch, 121"}, {0, "-1:1:3", "curve, 363"},
                                     {0, "-2:2:5", "curve, 605"}, {0, "-3:3:7", "curve, 847"}};
  for (const Space& sp : spaces) {
    const std::vector<VoteTiming> vt = time_voting(shapes[sp.shape].shape, keeps, o.quick ? 30 : 200, sp.theta);
    for (const VoteTiming& v : vt) {
      char line[256];
      std::snprintf(line, sizeof line, "| %s | %s | %zu | %.2f | %.2f | %.2f | %.2f (%s) | %.2fx |\n", sp.label.c_str(),
                    keep_label(v.keep).c_str(), v.bytes, v.refs_per_feature, v.csr_us, v.dense_us, v.auto_us,
                    v.auto_dense ? "dense" : "CSR", vt.front().auto_us / v.auto_us);
      md << line;
    }
  }
}

}  // namespace

int run_decimation_study(const DecimationStudyOptions& o) {
  std::filesystem::create_directories(o.out);
  const std::vector<StudyShape> shapes = study_shapes(o.quick);
  const std::vector<NamedPolicy> policies = study_policies();
  std::vector<double> noises, keeps;
  if (o.quick) {
    noises = {0.0, 0.1, 0.2, 0.3, 0.4, 0.5};
    keeps = {1.0, 0.3, 0.1, 0.03};
  } else {
    for (int i = 0; i <= 25; ++i) noises.push_back(i * 0.02);
    keeps = {1.0, 0.7, 0.5, 0.3, 0.2, 0.1, 0.07, 0.05, 0.03, 0.02, 0.01};
  }

  // One-step trials.
  std::vector<Shape> grid_shapes;
  for (const auto& s : shapes) grid_shapes.push_back(s.shape);
  GridSpec spec;
  spec.noises = noises;
  spec.keeps = keeps;
  spec.frames = o.quick ? 20 : 100;
  spec.threads = o.threads;
  spec.policies.clear();
  for (const auto& p : policies) spec.policies.push_back(p.policy);
  spec.progress = [](std::size_t d, std::size_t total) {
    std::fprintf(stderr, "\rdecimation: one-step grid %zu/%zu", d, total);
    if (d == total) std::fputc('\n', stderr);
  };
  const std::vector<GridRow> grid = run_grid(grid_shapes, spec);
  // Continuous sequences.
  const std::vector<SequenceRow> seq = run_sequences(shapes, policies, noises, keeps, o.threads);

  {
    std::ofstream g(o.out + "/decimation_grid.csv");
    g << "shape,policy,noise,keep,frames,wrong\n";
    for (const GridRow& r : grid) g << r.shape << ",\"" << r.policy << "\"," << r.noise << ',' << r.keep << ',' << r.frames << ',' << r.wrong << '\n';
    std::ofstream s(o.out + "/decimation_sequences.csv");
    s << "shape,policy,noise,keep,frames,exact,mean_us,table_bytes\n";
    for (const SequenceRow& r : seq)
      s << r.shape << ',' << r.policy << ',' << r.noise << ',' << r.keep << ',' << r.frames << ',' << r.exact << ',' << r.mean_us << ','
        << r.table_bytes << '\n';
  }

  std::ostringstream md;
  md << "# Decimation policies: the thesis's section 6.2 protocol\n\n"
     << "Written by `gabarit bench --decimation" << (o.quick ? " --quick" : "") << "`. Shapes: ";
  for (const auto& s : shapes) md << '`' << s.shape.name << "` (" << s.shape.points.size() << " points, " << (s.held_out ? "held out" : "tuning") << ") ";
  md << "\n\nNoise levels: " << noises.size() << " from 0 to " << percent(noises.back()) << "; keep ratios: ";
  for (double k : keeps) md << keep_label(k) << ' ';
  md << "\n\n";

  report_policy_summary(shapes, policies, grid, seq, md);
  // Per shape: the highest noise every sequence frame is exact up to, per policy and keep.
  for (const auto& s : shapes) report_shape(o, s, policies, noises, keeps, grid, seq, spec, md);
  report_voting_time(o, shapes, keeps, md);
  // Template reduction against decimation at equal bytes.
  md << "\n## Reduced template, decimated stencils, both: at equal table bytes (one-step trials)\n\n"
     << "For K: the template reduced (greedy) to characterising value K; the full model's stencils decimated\n"
     << "(`--max-bytes`, the default policy) to the same bytes; and a template reduced to 2K, decimated to the\n"
     << "same bytes. Highest noise with no wrong frame, and wrong frames summed over the noise levels.\n\n"
     << "| shape | K | points | bytes (reduced / decimated / both) | noise reached (reduced / decimated / both) | wrong (reduced / decimated / both) |\n"
     << "|---|---:|---:|---|---|---|\n";
  for (const ReductionRow& r : compare_reduction(shapes, noises, o.quick ? 20 : 100)) {
    md << "| " << r.shape << " | " << r.k << " | " << r.points << " | " << r.bytes[0] << " / " << r.bytes[1] << " / " << r.bytes[2] << " | "
       << reached_text(r.reached[0]) << " / " << reached_text(r.reached[1]) << " / " << reached_text(r.reached[2]) << " | " << r.wrong[0]
       << " / " << r.wrong[1] << " / " << r.wrong[2] << " |\n";
  }
  const std::string path = o.out + "/decimation.md";
  std::ofstream(path) << md.str();
  std::printf("%s", md.str().c_str());
  std::fprintf(stderr, "wrote %s\n", path.c_str());
  return 0;
}

}  // namespace gabarit::bench
