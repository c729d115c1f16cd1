#include "experiments.hpp"

#include "gabarit/host/tables/table_analysis.hpp"

#include <algorithm>
#include <atomic>
#include <limits>
#include <mutex>
#include <thread>

#include "gabarit/deterministic_math.hpp"
#include "gabarit/app/error.hpp"
#include "gabarit/app/rng.hpp"
#include "gabarit/host/tables/state_space.hpp"
#include "gabarit/host/tables/table_builder.hpp"
#include "gabarit/host/runs/tracking_run.hpp"
#include "gabarit/voter.hpp"

namespace gabarit::bench {
namespace {

struct Box {
  std::int32_t min_x, min_y, max_x, max_y;
  std::int32_t width() const { return max_x - min_x + 1; }
  std::int32_t height() const { return max_y - min_y + 1; }
};

Box bounds(const std::vector<Point>& pts) {
  Box b{INT32_MAX, INT32_MAX, INT32_MIN, INT32_MIN};
  for (const Point& p : pts) {
    b.min_x = std::min(b.min_x, p.x);
    b.min_y = std::min(b.min_y, p.y);
    b.max_x = std::max(b.max_x, p.x);
    b.max_y = std::max(b.max_y, p.y);
  }
  return b;
}

constexpr std::int32_t kRange = 5;  // translations -5..5, as kCellAxis

class RectXcorr final : public Estimator {
 public:
  explicit RectXcorr(const Shape& s) : box_(bounds(s.points)), templ_(static_cast<std::size_t>(box_.width() * box_.height()), 0) {
    for (const Point& p : s.points) templ_[static_cast<std::size_t>((p.y - box_.min_y) * box_.width() + (p.x - box_.min_x))] = 1;
  }
  std::string name() const override { return "(a) cross-correlation, rectangular template"; }
  Point estimate(const Trial& t) override {
    std::uint64_t best = 0;
    Point arg = t.previous;
    const std::size_t stride = t.frame.width;
    for (std::int32_t ty = -kRange; ty <= kRange; ++ty)
      for (std::int32_t tx = -kRange; tx <= kRange; ++tx) {
        const std::uint8_t* origin = t.frame.pixels.data() + static_cast<std::ptrdiff_t>(t.previous.y + ty + box_.min_y) * static_cast<std::ptrdiff_t>(stride) +
                                     (t.previous.x + tx + box_.min_x);
        std::uint32_t sum = 0;
        for (std::int32_t v = 0; v < box_.height(); ++v) {
          const std::uint8_t* f = origin + static_cast<std::ptrdiff_t>(v) * static_cast<std::ptrdiff_t>(stride);
          const std::uint8_t* m = templ_.data() + static_cast<std::size_t>(v * box_.width());
          for (std::int32_t u = 0; u < box_.width(); ++u) sum += static_cast<std::uint32_t>(f[u] * m[u]);
        }
        if (sum > best) best = sum, arg = {t.previous.x + tx, t.previous.y + ty};
      }
    return arg;
  }

 private:
  Box box_;
  std::vector<std::uint8_t> templ_;
};

class ShapeXcorr final : public Estimator {
 public:
  explicit ShapeXcorr(const Shape& s) : points_(s.points) {}
  std::string name() const override { return "(b) cross-correlation, shape template"; }
  Point estimate(const Trial& t) override {
    std::int64_t best = -1;
    Point arg = t.previous;
    const std::ptrdiff_t stride = t.frame.width;
    if (offsets_stride_ != stride) {
      offsets_.clear();
      for (const Point& p : points_) offsets_.push_back(p.y * stride + p.x);
      offsets_stride_ = stride;
    }
    for (std::int32_t ty = -kRange; ty <= kRange; ++ty)
      for (std::int32_t tx = -kRange; tx <= kRange; ++tx) {
        const std::uint8_t* c = t.frame.pixels.data() + (t.previous.y + ty) * stride + t.previous.x + tx;
        std::int64_t sum = 0;
        for (std::ptrdiff_t o : offsets_) sum += c[o] != 0;
        if (sum > best) best = sum, arg = {t.previous.x + tx, t.previous.y + ty};
      }
    return arg;
  }

 private:
  std::vector<Point> points_;
  std::vector<std::ptrdiff_t> offsets_;
  std::ptrdiff_t offsets_stride_ = -1;
};

class ExhaustiveStencil final : public Estimator {
 public:
  ExhaustiveStencil(const std::vector<std::byte>& bytes, std::size_t stride) : bytes_(bytes) {
    if (TableView::open(bytes_, table_) != Status::kOk) throw app::Error("bench: invalid table");
    // Transpose the table: cell -> image offsets of its stencil pixels.
    begin_.assign(table_.cell_count() + 1, 0);
    for (std::uint32_t i = 0; i < table_.reference_count(); ++i) ++begin_[table_.reference(i) + 1];
    for (std::uint32_t c = 0; c < table_.cell_count(); ++c) begin_[c + 1] += begin_[c];
    offsets_.resize(table_.reference_count());
    std::vector<std::uint32_t> fill(begin_.begin(), begin_.end() - 1);
    for (std::uint32_t p = 0; p < table_.roi_slots(); ++p) {
      const std::ptrdiff_t dx = table_.roi_origin_x() + static_cast<std::int32_t>(p % table_.roi_width());
      const std::ptrdiff_t dy = table_.roi_origin_y() + static_cast<std::int32_t>(p / table_.roi_width());
      for (std::uint32_t i = table_.references_begin(p); i < table_.references_begin(p + 1); ++i) {
        offsets_[fill[table_.reference(i)]++] = dy * static_cast<std::ptrdiff_t>(stride) + dx;
      }
    }
  }
  std::string name() const override { return "(c) exhaustive stencil estimator (Algorithm 3)"; }
  Point estimate(const Trial& t) override {
    const std::uint8_t* c = t.frame.pixels.data() + static_cast<std::ptrdiff_t>(t.previous.y) * t.frame.width + t.previous.x;
    CellScore best{0, 0, 0};
    for (std::uint32_t cell = 0; cell < table_.cell_count(); ++cell) {
      std::uint32_t votes = 0;
      for (std::uint32_t i = begin_[cell]; i < begin_[cell + 1]; ++i) votes += c[offsets_[i]] != 0;
      const CellScore s{cell, static_cast<VoteCounter>(std::min<std::uint32_t>(votes, kVoteCounterMax)), table_.stencil_size(cell)};
      if (cell == 0 || ranks_before(s, best)) best = s;
    }
    const CellBounds b = table_.cell(best.cell);
    return {t.previous.x + static_cast<std::int32_t>(b.x_centre()), t.previous.y + static_cast<std::int32_t>(b.y_centre())};
  }

 private:
  std::vector<std::byte> bytes_;
  TableView table_;
  std::vector<std::uint32_t> begin_;
  std::vector<std::ptrdiff_t> offsets_;
};

class Hough final : public Estimator {
 public:
  Hough(std::vector<std::byte> bytes, std::string name, app::VoterChoice voter)
      : bytes_(std::move(bytes)), name_(std::move(name)), table_(open(bytes_)), buffers_(table_, voter) {}
  std::string name() const override { return name_; }
  Point estimate(const Trial& t) override {
    StepResult r;
    const Pose previous{static_cast<float>(t.previous.x), static_cast<float>(t.previous.y), 0, 0};
    if (track_step(table_, {table_format::DetectorKind::kBinary, 0}, t.frame.view(), previous, buffers_.scratch(), r) !=
        Status::kOk) {
      throw app::Error("bench: track_step failed");
    }
    return {round_to_int(r.pose.x), round_to_int(r.pose.y)};
  }

 private:
  static TableView open(const std::vector<std::byte>& bytes) {
    TableView t;
    if (TableView::open(bytes, t) != Status::kOk) throw app::Error("bench: invalid table");
    return t;
  }
  std::vector<std::byte> bytes_;
  std::string name_;
  TableView table_;
  app::TrackerBuffers buffers_;
};

}  // namespace

std::unique_ptr<Estimator> rect_xcorr(const Shape& shape) { return std::make_unique<RectXcorr>(shape); }
std::unique_ptr<Estimator> shape_xcorr(const Shape& shape) { return std::make_unique<ShapeXcorr>(shape); }
std::unique_ptr<Estimator> exhaustive_stencil(const std::vector<std::byte>& table, std::size_t stride) {
  return std::make_unique<ExhaustiveStencil>(table, stride);
}
std::unique_ptr<Estimator> hough(std::vector<std::byte> table, const std::string& name, app::VoterChoice voter) {
  return std::make_unique<Hough>(std::move(table), name, voter);
}

std::vector<GridRow> run_grid(const std::vector<Shape>& shapes, const GridSpec& spec) {
  // Tables first (one per shape and keep), then one job per shape and noise:
  // the job renders its trials once and runs every keep on them.
  // tables[shape][policy * keeps + keep]
  const std::size_t variants = spec.policies.size() * spec.keeps.size();
  std::vector<std::vector<std::vector<std::byte>>> tables(shapes.size());
  for (std::size_t s = 0; s < shapes.size(); ++s)
    for (const host::DecimationPolicy& policy : spec.policies)
      for (double keep : spec.keeps) tables[s].push_back(shape_table(shapes[s], keep, spec.seed, policy));

  const std::size_t jobs = shapes.size() * spec.noises.size();
  std::vector<GridRow> rows(jobs * variants);
  std::atomic<std::size_t> next{0}, done{0};
  std::mutex progress_mutex;
  const auto worker = [&] {
    for (std::size_t job; (job = next++) < jobs;) {
      const std::size_t s = job / spec.noises.size(), n = job % spec.noises.size();
      const auto trials = make_trials(shapes[s], spec.noises[n], spec.frames, spec.seed * 1000003 + job);
      for (std::size_t v = 0; v < variants; ++v) {
        auto estimator = hough(tables[s][v], "hough");
        std::size_t wrong = 0;
        for (const Trial& t : trials) {
          const Point e = estimator->estimate(t);
          wrong += e.x != t.truth.x || e.y != t.truth.y;
        }
        rows[job * variants + v] = {shapes[s].name, host::describe(spec.policies[v / spec.keeps.size()]), spec.noises[n],
                                    spec.keeps[v % spec.keeps.size()], trials.size(), wrong};
      }
      const std::size_t d = ++done;
      if (spec.progress) {
        std::lock_guard<std::mutex> lock(progress_mutex);
        spec.progress(d, jobs);
      }
    }
  };
  std::vector<std::thread> pool;
  for (unsigned i = 1; i < std::max(1u, spec.threads); ++i) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  return rows;
}

GridSpec regression_grid_spec() {
  GridSpec s;
  s.noises = {0.0, 0.2, 0.3, 0.4, 0.44, 0.48};
  s.keeps = {1.0, 0.5, 0.1, 0.02};
  s.frames = 25;
  s.seed = 2024;
  return s;
}

Robustness stencil_robustness(const TableView& t) {
  const host::TableAnalysis a = host::analyse_table(t);
  return {a.robustness_mean, a.robustness_min};
}

}  // namespace gabarit::bench
