// Drives a Verilated gbt_voter (any lane count and capacities) and compares
// it with the C++ kernel (the golden model): every counter, best cell,
// runner-up, vote and feature counts, bit for bit. Shared by the
// co-simulation tests (tests/hdl) and the HIL harness's Verilator DUT
// (hil/duts/verilator_dut.cpp).
#pragma once

#include <verilated.h>
#if VM_TRACE
#include <verilated_fst_c.h>
#endif
#if VM_COVERAGE
#include <verilated_cov.h>
#endif

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "gabarit/features.hpp"
#include "gabarit/app/hdl_export.hpp"
#include "gabarit/app/image_io.hpp"
#include "gabarit/app/rng.hpp"
#include "gabarit/voter.hpp"

namespace gabarit::hdl {

// Capacities the co-simulation models are verilated with (tests/hdl/CMakeLists.txt).
inline constexpr std::uint32_t kCellCapacity = 512;
inline constexpr std::uint32_t kPixelCapacity = 4096;
inline constexpr std::uint32_t kRefsPerLane = 65536;

inline void set_wide(std::uint32_t& port, const std::vector<std::uint32_t>& v) { port = v.empty() ? 0 : v[0]; }
inline void set_wide(std::uint64_t& port, const std::vector<std::uint32_t>& v) {
  port = (v.size() > 0 ? v[0] : 0) | (std::uint64_t{v.size() > 1 ? v[1] : 0u} << 32);
}
template <std::size_t N>
void set_wide(VlWide<N>& port, const std::vector<std::uint32_t>& v) {
  for (std::size_t i = 0; i < N; ++i) port[i] = i < v.size() ? v[i] : 0;
}

struct Outcome {
  std::vector<VoteCounter> counters;
  std::uint32_t best_cell = 0, best_votes = 0, runner_cell = kNoCell, runner_votes = 0;
  std::uint64_t votes = 0;
  std::uint32_t features = 0;
  // Hardware only.
  std::uint64_t cycles = 0, first_vote_cycle = 0, last_vote_cycle = 0;
  bool roi_error = false, overflow = false;
};

// The kernel's answer for one frame.
inline Outcome kernel_outcome(const TableView& t, const std::vector<RoiPoint>& features) {
  Outcome o;
  o.counters.assign(t.cell_count(), 0);
  VoteTally tally;
  if (accumulate_votes(t, features, o.counters, tally) != Status::kOk) std::abort();
  CellScore top[2];
  const std::size_t k = t.cell_count() >= 2 ? 2 : 1;
  if (select_top_cells(t, o.counters, std::span<CellScore>(top, k)) != Status::kOk) std::abort();
  o.best_cell = top[0].cell;
  o.best_votes = top[0].votes;
  if (k == 2) o.runner_cell = top[1].cell, o.runner_votes = top[1].votes;
  o.votes = tally.votes;
  o.features = tally.features;
  return o;
}

// The binary features of a synthetic trial frame, with the table's ROI
// centred on the trial's previous position (what the tracker would vote with).
inline std::vector<RoiPoint> trial_features(const TableView& t, const app::GrayImage& frame, std::int32_t x, std::int32_t y) {
  const ImageWindow w{x + t.roi_origin_x(), y + t.roi_origin_y(), t.roi_width(), t.roi_height()};
  std::vector<RoiPoint> f(t.roi_pixels());
  FeatureCount fc;
  if (extract_binary(frame.view(), w, f, fc) != Status::kOk) std::abort();
  f.resize(fc.written);
  return f;
}

// First difference between hardware and kernel, or empty.
// Every difference between the hardware's outcome and the kernel's, "" when
// they agree: how many counters differ (and the first), then the best cell,
// the runner-up and the counts, each that differs.
inline std::string compare(const Outcome& hw, const Outcome& sw) {
  std::ostringstream o;
  const auto next = [&] { return o.tellp() > 0 ? "; " : ""; };
  std::size_t differing = 0, first = 0;
  for (std::size_t c = 0; c < sw.counters.size(); ++c) {
    if (hw.counters[c] != sw.counters[c] && differing++ == 0) first = c;
  }
  if (differing > 0) {
    o << differing << " counter(s) differ, first cell " << first << ": hardware " << hw.counters[first] << ", kernel "
      << sw.counters[first];
  }
  if (hw.best_cell != sw.best_cell || hw.best_votes != sw.best_votes) {
    o << next() << "best: hardware cell " << hw.best_cell << " (" << hw.best_votes << "), kernel " << sw.best_cell << " ("
      << sw.best_votes << ")";
  }
  if (hw.runner_cell != sw.runner_cell || hw.runner_votes != sw.runner_votes) {
    o << next() << "runner-up: hardware cell " << hw.runner_cell << " (" << hw.runner_votes << "), kernel " << sw.runner_cell
      << " (" << sw.runner_votes << ")";
  }
  if (hw.votes != sw.votes || hw.features != sw.features) {
    o << next() << "counts: hardware " << hw.votes << " votes / " << hw.features << " features, kernel " << sw.votes << " / "
      << sw.features;
  }
  return o.str();
}

template <class Model>
class Harness {
 public:
  explicit Harness(const std::string& trace_path = {}, std::uint32_t cell_capacity = kCellCapacity,
                   std::uint32_t refs_per_lane = kRefsPerLane)
      : context_(std::make_unique<VerilatedContext>()), cell_capacity_(cell_capacity), refs_per_lane_(refs_per_lane) {
    context_->traceEverOn(!trace_path.empty());
    model_ = std::make_unique<Model>(context_.get());
#if VM_TRACE
    if (!trace_path.empty()) {
      trace_ = std::make_unique<VerilatedFstC>();
      model_->trace(trace_.get(), 99);
      trace_->open(trace_path.c_str());
    }
#else
    if (!trace_path.empty()) throw std::runtime_error("this model was verilated without tracing");
#endif
    model_->rst_ni = 0;
    model_->clk_i = 0;
    model_->eval();
    tick();
    model_->rst_ni = 1;
    tick();
  }
  ~Harness() {
#if VM_TRACE
    if (trace_) trace_->close();
#endif
    model_->final();
#if VM_COVERAGE
    // Line/toggle coverage (models are verilated with COVERAGE): one file per
    // harness in $VERILATOR_COVERAGE_DIR, merged by the hdl-coverage target.
    if (const char* dir = std::getenv("VERILATOR_COVERAGE_DIR"); dir && *dir) {
      static int serial = 0;
      const std::string path = std::string(dir) + "/coverage_" + model_->modelName() + "_" + std::to_string(::getpid()) + "_" +
                               std::to_string(serial++) + ".dat";
      context_->coveragep()->write(path.c_str());
    }
#endif
  }
  Model& model() { return *model_; }
  std::uint64_t cycle() const { return cycle_; }

  void tick() {
    model_->clk_i = 0;
    model_->eval();
    dump();
    context_->timeInc(1);
    model_->clk_i = 1;
    model_->eval();
    dump();
    context_->timeInc(1);
    ++cycle_;
  }

  void load(const app::HdlLayout& l, std::uint32_t lanes) {
    const app::HdlWidths w = app::hdl_widths(lanes, cell_capacity_, refs_per_lane_);
    Model& m = *model_;
    m.cell_count_i = l.cell_count;
    m.roi_width_i = l.roi_width;
    m.roi_height_i = l.roi_height;
    m.tbl_we_i = 1;
    for (std::uint32_t p = 0; p < l.ranges.size(); ++p) {
      m.tbl_sel_i = 0;
      m.tbl_lane_i = 0;
      m.tbl_addr_i = p;
      set_wide(m.tbl_data_i, app::hdl_offsets_word(l, p, w));
      tick();
    }
    for (std::uint32_t k = 0; k < lanes; ++k) {
      for (std::uint32_t i = 0; i < l.refs[k].size(); ++i) write(1, k, i, l.refs[k][i]);
      for (std::uint32_t i = 0; i < l.sizes[k].size(); ++i) write(2, k, i, l.sizes[k][i]);
    }
    m.tbl_we_i = 0;
    tick();
  }

  // One frame: start, stream `features` (col,row pairs; with probability
  // `gap` a clock passes with valid low), end, wait for the result, read back
  // `cells` counters.
  Outcome frame(const std::vector<RoiPoint>& features, std::uint32_t cells, double gap, app::Rng& rng) {
    Model& m = *model_;
    Outcome o;
    const std::uint64_t start = cycle_;
    m.frame_start_i = 1;
    tick();
    m.frame_start_i = 0;
    std::uint32_t previous_votes = 0;
    const auto watch_votes = [&] {
      if (m.votes_o != previous_votes) {
        if (previous_votes == 0) o.first_vote_cycle = cycle_;
        o.last_vote_cycle = cycle_;
        previous_votes = m.votes_o;
      }
    };
    std::size_t next = 0;
    for (std::uint64_t guard = 0; next < features.size(); ++guard) {
      if (guard > 100 * (features.size() + 1000) + 10 * cells) throw std::runtime_error("feature stream stalled");
      const bool offer = gap == 0 || !rng.bernoulli(gap);
      m.feat_valid_i = offer;
      m.feat_col_i = features[next].col;
      m.feat_row_i = features[next].row;
      m.eval();
      const bool taken = offer && m.feat_ready_o;
      tick();
      watch_votes();
      if (taken) ++next;
    }
    m.feat_valid_i = 0;
    m.frame_end_i = 1;
    tick();
    m.frame_end_i = 0;
    for (std::uint64_t guard = 0; !m.result_valid_o; ++guard) {
      if (guard > 1000000) throw std::runtime_error("no result after frame end");
      tick();
      watch_votes();
    }
    o.cycles = cycle_ - start;
    o.best_cell = m.best_cell_o;
    o.best_votes = m.best_votes_o;
    o.runner_cell = m.runner_valid_o ? m.runner_cell_o : kNoCell;
    o.runner_votes = m.runner_valid_o ? m.runner_votes_o : 0;
    o.votes = m.votes_o;
    o.features = m.features_o;
    o.roi_error = m.roi_error_o;
    o.overflow = m.overflow_o;
    o.counters.resize(cells);
    for (std::uint32_t c = 0; c < cells; ++c) {
      m.cnt_cell_i = c;
      tick();
      m.eval();
      o.counters[c] = static_cast<VoteCounter>(m.cnt_data_o);
    }
    return o;
  }

 private:
  void write(std::uint32_t sel, std::uint32_t lane, std::uint32_t addr, std::uint32_t data) {
    Model& m = *model_;
    m.tbl_sel_i = sel;
    m.tbl_lane_i = lane;
    m.tbl_addr_i = addr;
    set_wide(m.tbl_data_i, {data});
    tick();
  }

  std::unique_ptr<VerilatedContext> context_;
  std::uint32_t cell_capacity_, refs_per_lane_;
  std::unique_ptr<Model> model_;
#if VM_TRACE
  void dump() {
    if (trace_) trace_->dump(context_->time());
  }
  std::unique_ptr<VerilatedFstC> trace_;
#else
  void dump() {}
#endif
  std::uint64_t cycle_ = 0;
};

}  // namespace gabarit::hdl
