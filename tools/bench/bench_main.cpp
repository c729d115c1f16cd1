// gabarit-bench (run as `gabarit bench`): regenerates the evidence of the
// thesis's synthetic experiments in one run — Table 6.1 timings with OpenCV's
// matchTemplate as the peer, the wrong-frame grid of Figs. 6.16-6.19, the
// refs-per-pixel histograms of Fig. 6.20 and the robustness indicators of
// Figs. 6.26/6.27 — as CSV, SVG plots and a Markdown report.
//
// OpenCV is linked here and nowhere else.
#include <sys/utsname.h>
#include <unistd.h>

#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <thread>

#include "decimation_study.hpp"
#include "experiments.hpp"
#include "microscope.hpp"
#include "pipette.hpp"
#include "suite.hpp"
#include "gabarit/app/error.hpp"
#include "gabarit/host/scenes/thesis_shapes.hpp"
#include "gabarit/app/svg_plot.hpp"

#ifndef GABARIT_BUILD_TYPE
#define GABARIT_BUILD_TYPE "unknown"
#endif

namespace gabarit::bench {
namespace {

using Clock = std::chrono::steady_clock;
constexpr const char* kHoughFull = "(d) bounded Hough, full stencils (dense voter)";

// OpenCV's template matching over the same bounded window: the window holds
// the rectangular template at every translation of +-5 px.
class CvMatch final : public Estimator {
 public:
  CvMatch(const Shape& s, int method, std::string name) : method_(method), name_(std::move(name)) {
    min_x_ = min_y_ = INT32_MAX;
    std::int32_t max_x = INT32_MIN, max_y = INT32_MIN;
    for (const Point& p : s.points) {
      min_x_ = std::min(min_x_, p.x), min_y_ = std::min(min_y_, p.y);
      max_x = std::max(max_x, p.x), max_y = std::max(max_y, p.y);
    }
    templ_ = cv::Mat::zeros(max_y - min_y_ + 1, max_x - min_x_ + 1, CV_8U);
    for (const Point& p : s.points) templ_.at<std::uint8_t>(p.y - min_y_, p.x - min_x_) = 255;
  }
  std::string name() const override { return name_; }
  Point estimate(const Trial& t) override {
    const cv::Mat frame(static_cast<int>(t.frame.height), static_cast<int>(t.frame.width), CV_8U,
                        const_cast<std::uint8_t*>(t.frame.pixels.data()));
    const cv::Rect window(t.previous.x + min_x_ - 5, t.previous.y + min_y_ - 5, templ_.cols + 10, templ_.rows + 10);
    cv::matchTemplate(frame(window), templ_, result_, method_);
    cv::Point best;
    cv::minMaxLoc(result_, nullptr, nullptr, nullptr, &best);
    return {t.previous.x + best.x - 5, t.previous.y + best.y - 5};
  }

 private:
  int method_;
  std::string name_;
  std::int32_t min_x_, min_y_;
  cv::Mat templ_, result_;
};

struct Options {
  bool quick = false;
  std::string out = "bench-out";
  std::size_t grid_frames = 0, timing_frames = 0;
  unsigned threads = std::max(1u, std::thread::hardware_concurrency());
  std::string regression_csv;
  bool microscope = false;
  bool suite = false;
  bool pipette = false;
  bool no_particles = false;
  bool no_detection = false;
  std::uint32_t orientation_channels = 0;
  std::uint32_t detect_after = gabarit::RecoveryOptions{}.detect_after;
  std::uint32_t particles = 1000;
  std::uint32_t particle_seeds = 1;
  bool decimation = false;
  std::uint32_t scenes = 0;
  std::uint32_t first = 0;
  bool no_peer = false;
};

struct TimingRow {
  std::string shape, method;
  double micros = 0;
  std::size_t wrong = 0, frames = 0;
};

std::string cpu_model() {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown";
}

std::string fmt(double v, int digits = 1) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", digits, v);
  return b;
}

std::string pct(double v) {
  const double p = std::round(v * 1000) / 10;  // one decimal, float noise removed
  return fmt(p, p == std::floor(p) ? 0 : 1) + "%";
}

std::vector<TimingRow> time_methods(const Shape& shape, std::size_t frames, int reps, std::vector<TimingRow>& all) {
  const auto trials = make_trials(shape, 0.20, frames, 77);
  const auto full = shape_table(shape, 1.0, 1);
  std::vector<std::unique_ptr<Estimator>> methods;
  methods.push_back(rect_xcorr(shape));
  methods.push_back(shape_xcorr(shape));
  methods.push_back(exhaustive_stencil(full, shape.width));
  methods.push_back(hough(full, kHoughFull));
  for (double keep : {0.5, 0.1, 0.01}) {
    methods.push_back(hough(shape_table(shape, keep, 1), "(e) bounded Hough, " + pct(keep) + " of references"));
  }
  methods.push_back(hough(full, "(d') bounded Hough, full stencils, CSR voter", app::VoterChoice::kCsr));
  methods.push_back(std::make_unique<CvMatch>(shape, cv::TM_CCORR, "OpenCV matchTemplate TM_CCORR"));
  methods.push_back(std::make_unique<CvMatch>(shape, cv::TM_CCOEFF_NORMED, "OpenCV matchTemplate TM_CCOEFF_NORMED"));
  std::vector<double> best(methods.size(), 1e300);
  std::vector<std::size_t> wrong(methods.size(), 0);
  for (int rep = 0; rep < reps; ++rep) {
    std::vector<double> total(methods.size(), 0);
    // Side by side: every method on a frame before the next frame. The first
    // method to touch a frame pays its cache misses (frames arrive cold from
    // a camera), so the order rotates from frame to frame: each method goes
    // first equally often.
    for (std::size_t f = 0; f < trials.size(); ++f) {
      const Trial& t = trials[f];
      for (std::size_t k = 0; k < methods.size(); ++k) {
        const std::size_t m = (f + k) % methods.size();
        const auto a = Clock::now();
        const Point e = methods[m]->estimate(t);
        total[m] += std::chrono::duration<double, std::micro>(Clock::now() - a).count();
        if (rep == 0) wrong[m] += e.x != t.truth.x || e.y != t.truth.y;
      }
    }
    for (std::size_t m = 0; m < methods.size(); ++m) best[m] = std::min(best[m], total[m] / static_cast<double>(trials.size()));
  }
  std::vector<TimingRow> rows;
  for (std::size_t m = 0; m < methods.size(); ++m) rows.push_back({shape.name, methods[m]->name(), best[m], wrong[m], trials.size()});
  all.insert(all.end(), rows.begin(), rows.end());
  return rows;
}

// OpenCV's TM_CCOEFF_NORMED with its default thread pool, for the record:
// the best of `reps` per shape, microseconds per frame.
std::map<std::string, double> opencv_threaded(const std::vector<Shape>& shapes, std::size_t timing_frames, int reps) {
  cv::setNumThreads(-1);
  std::map<std::string, double> cv_threaded;
  for (const Shape& s : shapes) {
    const auto trials = make_trials(s, 0.20, timing_frames, 77);
    CvMatch m(s, cv::TM_CCOEFF_NORMED, "");
    double best = 1e300;
    for (int rep = 0; rep < reps; ++rep) {
      const auto a = Clock::now();
      for (const Trial& t : trials) (void)m.estimate(t);
      best = std::min(best, std::chrono::duration<double, std::micro>(Clock::now() - a).count() / static_cast<double>(trials.size()));
    }
    cv_threaded[s.name] = best;
  }
  cv::setNumThreads(1);

  return cv_threaded;
}

// Figs. 6.20, 6.26/6.27: each shape's table at each keep ratio, its
// references per ROI pixel and its stencils' robustness.
struct StencilStatistics {
  std::ostringstream hist_csv, robust_csv;
  std::map<std::string, std::vector<app::svg::Series>> hist_series, robust_series;
  std::map<std::string, std::vector<std::string>> robust_rows;
};
void stencil_statistics(const std::vector<Shape>& shapes, const std::vector<double>& keeps, StencilStatistics& st) {
  std::ostringstream& hist_csv = st.hist_csv;
  std::ostringstream& robust_csv = st.robust_csv;
  auto& hist_series = st.hist_series;
  auto& robust_series = st.robust_series;
  auto& robust_rows = st.robust_rows;
  hist_csv << "shape,keep,refs_per_pixel,pixels\n";
  robust_csv << "shape,keep,references,mean_margin,min_margin\n";
  for (const Shape& s : shapes) {
    app::svg::Series mean{"mean", {}, {}}, min{"minimum", {}, {}};
    for (double keep : keeps) {
      const auto bytes = shape_table(s, keep, 1);
      TableView t;
      if (TableView::open(bytes, t) != Status::kOk) throw app::Error("bench: invalid table");
      const Robustness r = stencil_robustness(t);
      robust_csv << s.name << ',' << keep << ',' << t.reference_count() << ',' << r.mean << ',' << r.min << '\n';
      robust_rows[s.name].push_back("| " + pct(keep) + " | " + std::to_string(t.reference_count()) + " | " + std::to_string(t.size_bytes()) +
                                    " | " + fmt(r.mean) + " | " + std::to_string(r.min) + " |");
      mean.x.push_back(keep), mean.y.push_back(r.mean);
      min.x.push_back(keep), min.y.push_back(static_cast<double>(r.min));
      if (keep == 1 || keep == 0.5 || keep == 0.1 || keep == 0.01) {
        const auto h = refs_per_pixel(t);
        app::svg::Series series{"keep " + pct(keep), {}, {}};
        for (std::size_t k = 0; k < h.size(); ++k) {
          hist_csv << s.name << ',' << keep << ',' << k << ',' << h[k] << '\n';
          series.x.push_back(static_cast<double>(k)), series.y.push_back(static_cast<double>(h[k]));
        }
        hist_series[s.name].push_back(series);
      }
    }
    robust_series[s.name] = {mean, min};
  }

}

// timing.csv, grid.csv, refs_per_pixel.csv, robustness.csv.
void write_bench_csvs(const Options& o, const std::vector<TimingRow>& timing, const std::vector<GridRow>& grid,
                      const StencilStatistics& st) {
  const std::string hist_csv = st.hist_csv.str(), robust_csv = st.robust_csv.str();
    std::ofstream f(o.out + "/timing.csv");
    f << "shape,method,per_frame_us,speedup_vs_a,wrong_frames,frames\n";
    for (const TimingRow& r : timing) {
      const double a = std::find_if(timing.begin(), timing.end(), [&](const TimingRow& x) { return x.shape == r.shape; })->micros;
      f << r.shape << ",\"" << r.method << "\"," << r.micros << ',' << a / r.micros << ',' << r.wrong << ',' << r.frames << '\n';
    }
    std::ofstream g(o.out + "/grid.csv");
    g << "shape,noise,keep,frames,wrong\n";
    for (const GridRow& r : grid) g << r.shape << ',' << r.noise << ',' << r.keep << ',' << r.frames << ',' << r.wrong << '\n';
    std::ofstream(o.out + "/refs_per_pixel.csv") << hist_csv;
    std::ofstream(o.out + "/robustness.csv") << robust_csv;
}

// The report's opening: when, where, how, the protocol.
void report_header(const Options& o, const std::vector<Shape>& shapes, std::ostringstream& md) {
  struct utsname un {};
  uname(&un);
  const std::time_t now = std::time(nullptr);
  char date[64];
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  md << "# gabarit bench: the thesis's synthetic experiments re-measured\n\n";
  md << "| | |\n|---|---|\n| date | " << date << " |\n| machine | " << cpu_model() << ", " << std::thread::hardware_concurrency()
     << " hardware threads, " << un.sysname << " " << un.release << " " << un.machine << " |\n| compiler | " << __VERSION__
     << " |\n| build type | " << GABARIT_BUILD_TYPE << " |\n| OpenCV | " << CV_VERSION << " |\n| threads | timing: 1 (OpenCV too, "
     << "`cv::setNumThreads(1)`); grid: " << o.threads << " |\n| mode | " << (o.quick ? "quick" : "full") << " |\n\n";
  md << "Protocol: each frame is an independent trial (one-step): the shape at a known previous position moves by a random "
        "step within ±4 px per axis; salt-and-pepper noise flips each pixel with probability p; every estimator searches "
        "the same ±5 px window (121 one-pixel cells). A frame is wrong unless the estimate is the true pixel. Shapes: "
        "`curve` ("
     << shapes[0].points.size() << " points, hand-drawn-like closed curve) and `watch` (" << shapes[1].points.size()
     << " edge points of python3-skimage's coffee.png, 2×2-averaged).\n\n";

}

// Table 6.1 re-measured, with a bar plot per shape.
void report_timing(const Options& o, const std::vector<Shape>& shapes, const std::vector<TimingRow>& timing,
                   std::map<std::string, double>& cv_threaded, std::ostringstream& md) {
  md << "## Table 6.1 re-measured: time per frame at 20% noise\n\n";
  for (const Shape& s : shapes) {
    md << "### " << s.name << " (" << s.points.size() << " points)\n\n| method | µs/frame | speed-up vs (a) | wrong frames |\n|---|---:|---:|---:|\n";
    double a = 0, hough_full = 0, cv_ccoeff = 0;
    std::vector<std::string> labels;
    std::vector<double> values;
    for (const TimingRow& r : timing) {
      if (r.shape != s.name) continue;
      if (a == 0) a = r.micros;
      if (r.method == kHoughFull) hough_full = r.micros;
      if (r.method.find("CCOEFF") != std::string::npos) cv_ccoeff = r.micros;
      md << "| " << r.method << " | " << fmt(r.micros) << " | " << fmt(a / r.micros, 2) << "× | " << r.wrong << "/" << r.frames << " |\n";
      labels.push_back(r.method), values.push_back(r.micros);
    }
    md << "\nOpenCV TM_CCOEFF_NORMED with its default thread pool: " << fmt(cv_threaded[s.name]) << " µs/frame.\n\n";
    md << "Bounded Hough speed-up over OpenCV matchTemplate (TM_CCOEFF_NORMED, 1 thread): full stencils **"
       << fmt(cv_ccoeff / hough_full, 1) << "×**";
    for (const TimingRow& r : timing)
      if (r.shape == s.name && r.method.rfind("(e)", 0) == 0) {
        md << ", " << r.method.substr(r.method.find(", ") + 2) << ": " << fmt(cv_ccoeff / r.micros, 1) << "×";
      }
    md << ".\n\n![timing " << s.name << "](timing_" << s.name << ".svg)\n\n";
    app::svg::write(o.out + "/timing_" + s.name + ".svg", app::svg::bars("Time per frame, " + s.name + " (" + std::to_string(s.points.size()) + " points), 20% noise",
                                                             "microseconds per frame", labels, values));
  }

}

// Figs. 6.16-6.19 re-measured: the wrong-frame grid, with a heat map per shape.
void report_grid(const Options& o, const std::vector<Shape>& shapes, const std::vector<double>& noises, const std::vector<double>& keeps,
                 const std::vector<GridRow>& grid, std::size_t grid_frames, std::ostringstream& md) {
  md << "## Figs. 6.16–6.19 re-measured: wrong frames (out of " << grid_frames << ") over noise × references kept\n\n";
  for (const Shape& s : shapes) {
    std::vector<std::string> xl, yl;
    for (double k : keeps) xl.push_back(pct(k));
    std::vector<std::vector<double>> values;
    md << "### " << s.name << "\n\n| noise |";
    for (double k : keeps) md << " keep " << pct(k) << " |";
    md << "\n|---:|";
    for (std::size_t i = 0; i < keeps.size(); ++i) md << "---:|";
    md << "\n";
    for (double n : noises) {
      yl.push_back(pct(n));
      values.emplace_back();
      md << "| " << pct(n) << " |";
      for (double k : keeps) {
        const auto it = std::find_if(grid.begin(), grid.end(), [&](const GridRow& r) { return r.shape == s.name && r.noise == n && r.keep == k; });
        md << " " << it->wrong << " |";
        values.back().push_back(static_cast<double>(it->wrong));
      }
      md << "\n";
    }
    md << "\nHighest noise with 0 wrong frames at that level and every lower one:";
    for (double k : keeps) {
      double limit = -1;
      for (double n : noises) {
        const auto it = std::find_if(grid.begin(), grid.end(), [&](const GridRow& r) { return r.shape == s.name && r.noise == n && r.keep == k; });
        if (it->wrong != 0) break;
        limit = n;
      }
      md << " keep " << pct(k) << ": " << (limit < 0 ? "none" : pct(limit)) << ";";
    }
    md << "\n\n![grid " << s.name << "](grid_" << s.name << ".svg)\n\n";
    app::svg::write(o.out + "/grid_" + s.name + ".svg",
               app::svg::heatmap("Wrong frames out of " + std::to_string(grid_frames) + ", " + s.name, "fraction of references kept", xl,
                            "salt-and-pepper noise", yl, values, static_cast<double>(grid_frames)));
  }

}

// Figs. 6.20, 6.26/6.27: references per pixel and robustness, with their plots.
void report_stencils(const Options& o, const std::vector<Shape>& shapes, StencilStatistics& st, std::ostringstream& md) {
  auto& hist_series = st.hist_series;
  auto& robust_series = st.robust_series;
  auto& robust_rows = st.robust_rows;
  md << "## Fig. 6.20: references per ROI pixel\n\n";
  for (const Shape& s : shapes) {
    md << "![refs per pixel " << s.name << "](refs_per_pixel_" << s.name << ".svg)\n\n";
    app::svg::write(o.out + "/refs_per_pixel_" + s.name + ".svg",
               app::svg::lines("ROI pixels by number of cells they list, " + s.name, "references (cells) per pixel", "pixels", hist_series[s.name], false, true));
  }
  md << "Data: `refs_per_pixel.csv`.\n\n## Figs. 6.26/6.27: robustness indicators\n\n"
        "For each stencil, its size minus its overlap with its most overlapping stencil; mean and minimum over the 121 stencils.\n\n";
  for (const Shape& s : shapes) {
    md << "### " << s.name << "\n\n| keep | references | table bytes | mean margin | min margin |\n|---:|---:|---:|---:|---:|\n";
    for (const auto& row : robust_rows[s.name]) md << row << "\n";
    md << "\n![robustness " << s.name << "](robustness_" << s.name << ".svg)\n\n";
    app::svg::write(o.out + "/robustness_" + s.name + ".svg",
               app::svg::lines("Stencil robustness indicators, " + s.name, "fraction of references kept", "pixels", robust_series[s.name], true, false));
  }
}

int run(const Options& o) {
  const auto started = Clock::now();
  std::vector<Shape> shapes = {make_shape("curve", host::thesis_curve()), make_shape("watch", host::watch_shape())};

  if (!o.regression_csv.empty()) {
    auto spec = regression_grid_spec();
    spec.threads = o.threads;
    std::ofstream f(o.regression_csv);
    f << "shape,noise,keep,frames,wrong\n";
    for (const GridRow& r : run_grid(shapes, spec)) f << r.shape << ',' << r.noise << ',' << r.keep << ',' << r.frames << ',' << r.wrong << '\n';
    std::cerr << "wrote " << o.regression_csv << "\n";
    return 0;
  }

  std::filesystem::create_directories(o.out);
  const std::size_t timing_frames = o.timing_frames ? o.timing_frames : (o.quick ? 40 : 300);
  const int reps = o.quick ? 2 : 3;
  const std::size_t grid_frames = o.grid_frames ? o.grid_frames : (o.quick ? 25 : 300);
  std::vector<double> noises, keeps;
  if (o.quick) {
    noises = {0, 0.1, 0.2, 0.3, 0.4, 0.44, 0.46, 0.48, 0.5};
    keeps = {1, 0.5, 0.1, 0.01};
  } else {
    for (int n = 0; n <= 50; n += 2) noises.push_back(n / 100.0);
    keeps = {1, 0.5, 0.2, 0.1, 0.05, 0.02, 0.01};
  }

  // 1. Table 6.1, single-threaded (OpenCV too, so the ratio compares like with like).
  cv::setNumThreads(1);
  std::vector<TimingRow> timing;
  for (const Shape& s : shapes) {
    std::cerr << "timing " << s.name << " (" << s.points.size() << " points, " << timing_frames << " frames x " << reps << ")\n";
    time_methods(s, timing_frames, reps, timing);
  }
  std::map<std::string, double> cv_threaded = opencv_threaded(shapes, timing_frames, reps);  // back to 1 thread after

  // 2. The wrong-frame grid.
  GridSpec spec;
  spec.noises = noises;
  spec.keeps = keeps;
  spec.frames = grid_frames;
  spec.threads = o.threads;
  const bool tty = isatty(STDERR_FILENO);
  spec.progress = [&](std::size_t done, std::size_t total) {
    if (tty) std::fprintf(stderr, "\rgrid: %zu/%zu shape x noise jobs", done, total);
    else if (done == total || done % 10 == 0) std::fprintf(stderr, "grid: %zu/%zu shape x noise jobs\n", done, total);
    if (tty && done == total) std::fputc('\n', stderr);
  };
  const auto grid = run_grid(shapes, spec);

  // 3. Stencil statistics.
  StencilStatistics stats;
  stencil_statistics(shapes, keeps, stats);

  write_bench_csvs(o, timing, grid, stats);
  std::ostringstream md;
  report_header(o, shapes, md);
  report_timing(o, shapes, timing, cv_threaded, md);
  report_grid(o, shapes, noises, keeps, grid, grid_frames, md);
  report_stencils(o, shapes, stats, md);
  const double seconds = std::chrono::duration<double>(Clock::now() - started).count();
  md << "---\nWhole bench: " << fmt(seconds) << " s. Files: timing.csv, grid.csv, refs_per_pixel.csv, robustness.csv, *.svg.\n";
  std::ofstream(o.out + "/report.md") << md.str();
  std::cerr << "wrote " << o.out << "/report.md (" << fmt(seconds) << " s)\n";
  return 0;
}

constexpr const char* kHelp =
    "usage: gabarit bench [--quick] [--out DIR] [--threads N] [--frames N] [--timing-frames N]\n"
    "       gabarit bench --microscope [--quick] [--out DIR]\n"
    "       gabarit bench --suite [--quick] [--out DIR] [--first I] [--scenes N] [--frames N] [--no-peer] [--no-particles]\n"
    "                     [--no-detection] [--orientation-channels N] [--detect-after N] [--particle-seeds N]\n"
    "       gabarit bench --decimation [--quick] [--out DIR] [--threads N]\n"
    "       gabarit bench --pipette [--quick] [--out DIR] [--frames N] [--particles N]\n"
    "       gabarit bench --regression-csv FILE\n\n"
    "Re-measures the thesis's synthetic experiments (section 6.2) in one run: Table 6.1 timings against\n"
    "OpenCV's matchTemplate, the wrong-frame grid over noise x references kept (Figs. 6.16-6.19), the\n"
    "refs-per-pixel histograms (Fig. 6.20) and the robustness indicators (Figs. 6.26/6.27). Writes\n"
    "DIR/report.md, CSVs and SVG plots (default DIR: bench-out).\n\n"
    "options:\n"
    "  --quick               fewer frames, noise levels and keep ratios (under a minute)\n"
    "  --out DIR             output directory\n"
    "  --threads N           grid threads (default: all cores; timings are always single-threaded)\n"
    "  --frames N            frames per grid point (default 300, quick 25)\n"
    "  --timing-frames N     frames per timed method (default 300, quick 40)\n"
    "  --microscope          the 4-DOF microscope experiment instead (section 6.1): grayscale scene, motion\n"
    "                        filter, refinement, recovery, OpenCV NCC bank, 2-thread voting, 4-DOF build time\n"
    "  --suite               the scene suite instead (docs/scene-suite.md): the default session, the plain\n"
    "                        loop and the OpenCV NCC bank per scene, median and worst scene per half\n"
    "                        (tuning / held out), mean and p99 us/frame; --first I starts at scene I (32: the\n"
    "                        families), --scenes N runs N of them (default: to the last, 42 in all; quick:\n"
    "                        every 5th, 9 scenes of both halves),\n"
    "                        --frames per scene (default 160, quick 60), --no-peer skips the NCC bank,\n"
    "                        --no-particles the particle filter, --no-detection the detection rows (gabarit\n"
    "                        detect and OpenCV's pyramid matchTemplate on every frame, re-acquisition by detection);\n"
    "                        --orientation-channels N builds the scenes' tables with N channels (format 1.3);\n"
    "                        --detect-after N: the re-acquisition-by-detection row searches its first N lost\n"
    "                        frames with the grid (default 0, the session's); --particle-seeds N runs the\n"
    "                        particle filter with seeds 1..N and counts issue 31's targets over scene-seeds too\n"
    "                        (its rows stay seed 1's; default 1)\n"
    "  --decimation          the decimation policies instead (docs/experiments.md, \"Decimation\"): every\n"
    "                        policy x 11 keep ratios x 26 noise levels, one-step trials and continuous\n"
    "                        sequences (500/800 frames), tuning and held-out shapes, bytes and us/frame;\n"
    "                        writes DIR/decimation.md (quick: 6 noise levels, 4 keeps, 120 frames)\n"
    "  --pipette             the thesis's section 6.4 re-run (docs/particle-filter.md): the stencil tracker\n"
    "                        (custom edges and Canny, without and with the motion model) against the\n"
    "                        particle filter on the glass-pipette scenes; Fig. 6.60's tip-error buckets and\n"
    "                        Fig. 6.61's timings per half; writes DIR/pipette.md (quick: 4 scenes of 80 frames)\n"
    "  --particles N         --pipette: particles (default 1000)\n"
    "  --regression-csv F    write the regression test's small grid to F and exit\n"
    "  --help                show this help\n";

}  // namespace
}  // namespace gabarit::bench

int main(int argc, char** argv) {
  using namespace gabarit::bench;
  Options o;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      const auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw gabarit::app::Error(a + " needs a value");
        return argv[++i];
      };
      const auto count = [&](std::size_t lo, std::size_t hi) {
        const std::string v = value();
        char* end = nullptr;
        const unsigned long long n = std::strtoull(v.c_str(), &end, 10);
        if (v.empty() || *end || n < lo || n > hi) throw gabarit::app::Error(a + " '" + v + "': want " + std::to_string(lo) + ".." + std::to_string(hi));
        return static_cast<std::size_t>(n);
      };
      if (a == "--help" || a == "-h") {
        std::fputs(kHelp, stdout);
        return 0;
      } else if (a == "--quick") {
        o.quick = true;
      } else if (a == "--out") {
        o.out = value();
      } else if (a == "--threads") {
        o.threads = static_cast<unsigned>(count(1, 256));
      } else if (a == "--frames") {
        o.grid_frames = count(1, 100000);
      } else if (a == "--timing-frames") {
        o.timing_frames = count(1, 100000);
      } else if (a == "--microscope") {
        o.microscope = true;
      } else if (a == "--suite") {
        o.suite = true;
      } else if (a == "--pipette") {
        o.pipette = true;
      } else if (a == "--particles") {
        o.particles = static_cast<std::uint32_t>(count(1, 1000000));
      } else if (a == "--decimation") {
        o.decimation = true;
      } else if (a == "--scenes") {
        o.scenes = static_cast<std::uint32_t>(count(1, 1000));
      } else if (a == "--first") {
        o.first = static_cast<std::uint32_t>(count(0, 999));
      } else if (a == "--no-peer") {
        o.no_peer = true;
      } else if (a == "--no-particles") {
        o.no_particles = true;
      } else if (a == "--particle-seeds") {
        o.particle_seeds = static_cast<std::uint32_t>(count(1, 64));
      } else if (a == "--no-detection") {
        o.no_detection = true;
      } else if (a == "--detect-after") {
        o.detect_after = static_cast<std::uint32_t>(count(0, 1000));
      } else if (a == "--orientation-channels") {
        o.orientation_channels = static_cast<std::uint32_t>(count(0, 16));
        if (o.orientation_channels != 0 && !gabarit::table_format::valid_orientation_channels(o.orientation_channels))
          throw gabarit::app::Error("--orientation-channels: want 0, 2, 4, 8 or 16");
      } else if (a == "--regression-csv") {
        o.regression_csv = value();
      } else {
        std::fprintf(stderr, "gabarit bench: unknown option %s\n(see gabarit bench --help)\n", a.c_str());
        return 2;
      }
    }
    if (o.microscope + o.suite + o.decimation + o.pipette > 1)
      throw gabarit::app::Error("give one of --microscope, --suite, --decimation and --pipette");
    if (o.pipette) return run_pipette({o.out, o.quick, static_cast<std::uint32_t>(o.grid_frames), o.particles});
    if (o.decimation) return run_decimation_study({o.out, o.quick, o.threads});
    if ((o.scenes || o.first || o.no_peer || o.no_particles || o.no_detection || o.particle_seeds > 1) && !o.suite)
      throw gabarit::app::Error("--first, --scenes, --no-peer, --no-particles, --no-detection and --particle-seeds apply to --suite");
    if (o.particle_seeds > 1 && o.no_particles) throw gabarit::app::Error("--particle-seeds needs the particle filter (not --no-particles)");
    if (o.microscope) return run_microscope(o.out, o.quick);
    if (o.suite) {
      SuiteOptions s;
      s.out = o.out;
      s.quick = o.quick;
      s.scenes = o.scenes;
      s.first = o.first;
      s.frames = static_cast<std::uint32_t>(o.grid_frames);
      s.peer = !o.no_peer;
      s.particles = !o.no_particles;
      s.particle_seeds = o.particle_seeds;
      s.detection = !o.no_detection;
      s.orientation_channels = o.orientation_channels;
      s.detect_after = o.detect_after;
      return run_suite(s);
    }
    return run(o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gabarit bench: error: %s\n", e.what());
    return 1;
  }
}
