// Co-simulation of the hardware voter (hdl/rtl/gbt_voter.sv, Verilated with 1
// and 4 lanes) against the C++ kernel, the golden model: random tables and
// feature streams with random valid gaps, frames of the tracker's synthetic
// sequences, saturation, and the ROI and capacity flags. Every counter, the
// best cell, the runner-up and the counts must match bit for bit. The random
// part runs to the end whatever it finds and reports every mismatching frame
// (table seed, frame, cycle, every differing field; the first ten in full)
// and their count, then re-runs the first with an FST waveform written next
// to the test binary.
//
// GABARIT_COSIM_TABLES / GABARIT_COSIM_FRAMES scale the random part (the
// nightly-style target `hdl-cosim-long` sets them high).
#include <unistd.h>

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <optional>

#include "Vvoter_l1.h"
#include "Vvoter_l4.h"
#include "gabarit/app/image_io.hpp"
#include "gabarit/host/tables/model.hpp"
#include "gabarit/host/tables/table_builder.hpp"
#include "gabarit/host/runs/voter_trials.hpp"
#include "gabarit/features.hpp"
#include "gabarit/host/scenes/thesis_shapes.hpp"
#include "test_tables.hpp"
#include "voter_harness.hpp"

namespace gabarit::hdl {
namespace {

std::size_t env_count(const char* name, std::size_t fallback) {
  const char* v = std::getenv(name);
  return v && *v ? std::strtoull(v, nullptr, 10) : fallback;
}

struct RandomTable {
  std::uint64_t seed;
  std::vector<std::byte> bytes;
  TableView view;
};

RandomTable random_table(std::uint64_t seed) {
  app::Rng rng(seed);
  for (;;) {
    const auto pts = testing::random_points(rng, 1 + rng.next_u32() % 30, 2 + static_cast<std::int32_t>(rng.next_u32() % 14));
    const std::uint32_t xc = 1 + rng.next_u32() % 16, yc = 1 + rng.next_u32() % 16, tc = 1 + rng.next_u32() % 2;
    if (xc * yc * tc > kCellCapacity) continue;
    const auto axis = [&](std::uint32_t cells) {
      return cells == 1 ? std::string("0:0:1") : "-" + std::to_string(cells / 2) + ":" + std::to_string(cells - 1 - cells / 2) + ":" + std::to_string(cells);
    };
    const double keep = rng.bernoulli(0.5) ? 1.0 : 0.2 + 0.8 * rng.next_unit();  // decimated: stencil sizes differ
    RandomTable t{seed, testing::build(testing::point_model(pts), axis(xc), axis(yc), tc == 1 ? "0:0:1" : "-5:5:2", keep, seed), {}};
    if (TableView::open(t.bytes, t.view) != Status::kOk) std::abort();
    if (t.view.roi_pixels() <= kPixelCapacity) return t;
  }
}

std::vector<RoiPoint> random_features(app::Rng& rng, const TableView& t, std::size_t n) {
  std::vector<RoiPoint> f(n);
  for (auto& p : f) p = {static_cast<std::uint16_t>(rng.next_u32() % t.roi_width()), static_cast<std::uint16_t>(rng.next_u32() % t.roi_height())};
  return f;
}

template <class Model>
void replay_with_trace(const char* model, const RandomTable& t, std::uint32_t lanes, const std::vector<RoiPoint>& f, double gap,
                       std::uint64_t frame_seed) {
  const std::string path = std::string("hdl_mismatch_") + model + "_table" + std::to_string(t.seed) + ".fst";
  Harness<Model> h(path);
  h.load(app::hdl_layout(t.view, lanes), lanes);
  app::Rng rng(frame_seed);
  (void)h.frame(f, t.view.cell_count(), gap, rng);
  std::printf("waveform of the failing frame: %s\n", std::filesystem::absolute(path).c_str());
}

struct Failure {
  RandomTable table;
  std::vector<RoiPoint> features;
  double gap = 0;
  std::uint64_t frame_seed = 0;
};

template <class Model>
void random_cosim(const char* model, std::uint32_t lanes) {
  const std::size_t tables = env_count("GABARIT_COSIM_TABLES", 110);
  const std::size_t frames = env_count("GABARIT_COSIM_FRAMES", 3);
  std::uint64_t features = 0, votes = 0, frames_run = 0, mismatches = 0;
  std::optional<Failure> failure;  // the first mismatch
  {
    Harness<Model> h;
    for (std::size_t i = 0; i < tables; ++i) {
      RandomTable t = random_table(1000 + i);
      h.load(app::hdl_layout(t.view, lanes), lanes);
      app::Rng rng(t.seed * 7 + lanes);
      for (std::size_t fr = 0; fr < frames; ++fr) {
        const std::uint64_t frame_seed = rng.next_u64();
        app::Rng frame_rng(frame_seed);
        const auto f = random_features(frame_rng, t.view, frame_rng.next_u32() % 6000);
        const double gap = fr == 0 ? 0.0 : 0.3;
        app::Rng valid_rng(frame_seed);
        const Outcome hw = h.frame(f, t.view.cell_count(), gap, valid_rng);
        const Outcome sw = kernel_outcome(t.view, f);
        const std::string diff = compare(hw, sw);
        ++frames_run;
        if (!diff.empty()) {
          if (++mismatches <= 10) {
            ADD_FAILURE() << model << ": table seed " << t.seed << " (" << t.view.cell_count() << " cells), frame " << fr << " of "
                          << f.size() << " features, ending at cycle " << h.cycle() << ": " << diff;
          }
          if (!failure) failure = Failure{t, f, gap, frame_seed};
        }
        features += f.size();
        votes += sw.votes;
      }
    }
  }
  // One live model at a time: Verilator 5.006 can deadlock destroying a
  // second model while another exists, so the traced replay comes after.
  if (failure) {
    ADD_FAILURE() << model << ": " << mismatches << " of " << frames_run << " frames mismatched; the first is table seed "
                  << failure->table.seed;
    if (TableView::open(failure->table.bytes, failure->table.view) != Status::kOk) std::abort();  // bytes copied
    replay_with_trace<Model>(model, failure->table, lanes, failure->features, failure->gap, failure->frame_seed);
    return;
  }
  std::printf("%s: %zu random tables, %llu features, %llu votes: 0 mismatches\n", model, tables,
              static_cast<unsigned long long>(features), static_cast<unsigned long long>(votes));
  if (tables >= 100 && frames >= 3) EXPECT_GE(features, 1000000u);
}

TEST(VoterCosim, OneLaneMatchesTheKernelOnRandomTables) { random_cosim<Vvoter_l1>("1-lane", 1); }
TEST(VoterCosim, FourLanesMatchTheKernelOnRandomTables) { random_cosim<Vvoter_l4>("4-lane", 4); }

// Frames of the synthetic sequences the tracker is tested on: the thesis
// curve, 1-pixel cells over +-5 px, 20% and 40% noise, features from the
// kernel's detector at the true previous position. Also the throughput
// targets, from exact cycle counts (deterministic, not wall-clock).
template <class Model>
void sequence_cosim(const char* model, std::uint32_t lanes, double min_votes_per_clock) {
  const host::Shape shape = host::make_shape("curve", host::thesis_curve());
  const auto bytes = host::shape_table(shape, 1.0, 1);
  TableView t;
  ASSERT_EQ(TableView::open(bytes, t), Status::kOk);
  Harness<Model> h;
  h.load(app::hdl_layout(t, lanes), lanes);
  std::uint64_t votes = 0, vote_cycles = 0;
  for (double noise : {0.2, 0.4}) {
    const auto trials = host::make_trials(shape, noise, 25, 99);
    for (std::size_t i = 0; i < trials.size(); ++i) {
      const auto f = trial_features(t, trials[i].frame, trials[i].previous.x, trials[i].previous.y);
      app::Rng rng(i);
      const Outcome hw = h.frame(f, t.cell_count(), 0.0, rng);
      const Outcome sw = kernel_outcome(t, f);
      ASSERT_EQ(compare(hw, sw), "") << model << ", noise " << noise << ", frame " << i;
      votes += hw.votes;
      vote_cycles += hw.last_vote_cycle - hw.first_vote_cycle + 1;
    }
  }
  const double per_clock = static_cast<double>(votes) / static_cast<double>(vote_cycles);
  std::printf("%s on the curve sequences: %llu votes in %llu voting cycles = %.3f votes/clock (%.3f cycles/vote)\n", model,
              static_cast<unsigned long long>(votes), static_cast<unsigned long long>(vote_cycles), per_clock, 1.0 / per_clock);
  EXPECT_GE(per_clock, min_votes_per_clock);
}

TEST(VoterCosim, OneLaneMatchesTheKernelOnTrackerSequencesAtOneVotePerClock) {
  sequence_cosim<Vvoter_l1>("1-lane", 1, 1.0 / 1.05);
}
TEST(VoterCosim, FourLanesMatchTheKernelOnTrackerSequencesAtNinetyPercentOfFourVotesPerClock) {
  sequence_cosim<Vvoter_l4>("4-lane", 4, 0.9 * 4);
}

TEST(VoterCosim, CountersSaturateAndExtraFeaturesRaiseOverflow) {
  const auto bytes = testing::build(testing::point_model({{0, 0}, {1, 0}, {4, 2}}), "-1:1:3", "0:0:1");
  const TableView t = testing::open_table(bytes);
  Harness<Vvoter_l1> h;
  h.load(app::hdl_layout(t, 1), 1);
  app::Rng rng(1);
  std::vector<RoiPoint> f(70000, RoiPoint{2, 0});
  const Outcome hw = h.frame(f, t.cell_count(), 0.0, rng);
  const Outcome sw = kernel_outcome(t, f);
  // The kernel saturates at 65535; the voter takes 65535 features (its
  // capacity) and flags the rest — the counters agree either way.
  EXPECT_EQ(hw.counters, sw.counters);
  EXPECT_EQ(hw.features, 65535u);
  EXPECT_TRUE(hw.overflow);
  EXPECT_EQ(hw.best_cell, sw.best_cell);
}

TEST(VoterCosim, FeaturesOutsideTheRoiAreDroppedAndFlagged) {
  const auto bytes = testing::build(testing::point_model({{0, 0}, {3, 1}}), "-2:2:5", "-1:1:3");
  const TableView t = testing::open_table(bytes);
  Harness<Vvoter_l4> h;
  h.load(app::hdl_layout(t, 4), 4);
  app::Rng rng(2);
  std::vector<RoiPoint> inside = random_features(rng, t, 200);
  std::vector<RoiPoint> mixed = inside;
  mixed.insert(mixed.begin() + 50, RoiPoint{t.roi_width(), 0});
  mixed.insert(mixed.begin() + 120, RoiPoint{0, static_cast<std::uint16_t>(t.roi_height() + 3)});
  const Outcome hw = h.frame(mixed, t.cell_count(), 0.0, rng);
  EXPECT_TRUE(hw.roi_error);
  EXPECT_FALSE(hw.overflow);
  EXPECT_EQ(compare(hw, kernel_outcome(t, inside)), "");
  // The flag clears at the next frame.
  const Outcome clean = h.frame(inside, t.cell_count(), 0.0, rng);
  EXPECT_FALSE(clean.roi_error);
  EXPECT_EQ(compare(clean, kernel_outcome(t, inside)), "");
}

TEST(VoterCosim, TablesWithFewerCellsThanLanes) {
  for (const char* x : {"0:0:1", "0:1:2", "-1:1:3"}) {
    const auto bytes = testing::build(testing::point_model({{0, 0}, {2, 1}}), x, "0:0:1");
    const TableView t = testing::open_table(bytes);
    Harness<Vvoter_l4> h;
    h.load(app::hdl_layout(t, 4), 4);
    app::Rng rng(3);
    for (int frame = 0; frame < 4; ++frame) {
      const auto f = random_features(rng, t, frame * 3);
      EXPECT_EQ(compare(h.frame(f, t.cell_count(), 0.0, rng), kernel_outcome(t, f)), "") << x << " frame " << frame;
    }
  }
}

// Orientation channels (format 1.3): the voter addresses slots (hdl_layout's
// roi_width is the slots per row) and takes each feature as its two slots
// (hdl_features); the counters match the kernel's bit for bit. The hardware
// counts slots as features: twice the kernel's.
TEST(VoterCosim, OrientationChannelTables) {
  const auto dir = std::filesystem::temp_directory_path() / ("gabarit_cosim_channels_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  app::GrayImage image(25, 25, 60);
  for (std::uint32_t y = 9; y < 16; ++y)
    for (std::uint32_t x = 8; x < 17; ++x)
      if (!(x > 13 && y > 12)) image.at(x, y) = 220;  // a notched block: edges of four orientations
  app::write_pgm((dir / "m.pgm").string(), image);
  host::ImageModelOptions mo;
  mo.canny = true;
  const host::ModelStack model = host::model_from_images({(dir / "m.pgm").string()}, mo);
  std::filesystem::remove_all(dir);
  for (const std::uint32_t channels : {4u, 16u}) {
    host::BuildOptions bo;
    bo.space.x = host::parse_axis("-1:1:3", "x");
    bo.space.y = host::parse_axis("-1:1:3", "y");
    bo.space.theta = host::parse_axis("-4:4:3", "theta");
    bo.orientation_channels = channels;
    const auto bytes = host::build_table(model, bo);
    const TableView t = testing::open_table(bytes);
    ASSERT_LE(t.roi_slots(), kPixelCapacity);
    Harness<Vvoter_l4> h;
    h.load(app::hdl_layout(t, 4), 4);
    app::Rng rng(channels);
    for (int frame = 0; frame < 6; ++frame) {
      std::vector<RoiPoint> f(static_cast<std::size_t>(5 + frame * 7));
      for (auto& p : f) {  // kernel encoding: column, channel, upper half
        const std::uint32_t col = rng.next_u32() % t.roi_width(), c = rng.next_u32() % channels, upper = rng.next_u32() & 1u;
        p = {static_cast<std::uint16_t>((col << t.channel_bits()) | (c << 1) | upper),
             static_cast<std::uint16_t>(rng.next_u32() % t.roi_height())};
      }
      Outcome sw = kernel_outcome(t, f);
      sw.features *= 2;
      EXPECT_EQ(compare(h.frame(app::hdl_features(t, f), t.cell_count(), 0.0, rng), sw), "") << channels << " channels, frame " << frame;
    }
  }
}

}  // namespace
}  // namespace gabarit::hdl
