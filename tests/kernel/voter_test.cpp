#include "gabarit/voter.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>
#include <vector>

#include "gabarit/host/tables/state_space.hpp"
#include "gabarit/host/tables/table_builder.hpp"
#include "test_tables.hpp"

namespace gabarit {
namespace {

using testing::build;
using testing::point_model;

std::vector<RoiPoint> random_features(app::Rng& rng, const TableView& t, double density) {
  std::vector<RoiPoint> f;
  for (std::uint16_t r = 0; r < t.roi_height(); ++r)
    for (std::uint16_t c = 0; c < t.roi_width(); ++c)
      if (rng.bernoulli(density)) f.push_back({c, r});
  return f;
}

TEST(Voter, CountsEachFeatureOncePerCellItsPixelLists) {
  app::Rng rng(5);
  const auto bytes = build(point_model(testing::random_points(rng, 30, 12)), "-3:3:7", "-3:3:7");
  const TableView t = testing::open_table(bytes);
  const auto features = random_features(rng, t, 0.2);
  std::vector<VoteCounter> counters(t.cell_count(), 0);
  VoteTally tally;
  ASSERT_EQ(accumulate_votes(t, features, counters, tally), Status::kOk);
  std::vector<VoteCounter> expected(t.cell_count(), 0);
  std::uint64_t refs = 0;
  for (const RoiPoint& f : features) {
    const std::uint32_t p = std::uint32_t{f.row} * t.roi_width() + f.col;
    for (std::uint32_t i = t.references_begin(p); i < t.references_begin(p + 1); ++i) ++expected[t.reference(i)], ++refs;
  }
  EXPECT_EQ(counters, expected);
  EXPECT_EQ(tally.votes, refs);
}

// Every offset encoding (u32 per pixel, compact u8 or u16 deltas) and list
// length (the voter takes the first two references of a list without a
// branch) votes exactly what the lists say, on awkward sizes.
TEST(Voter, EveryOffsetEncodingVotesWhatItsListsSay) {
  app::Rng rng(17);
  std::set<int> encodings;
  for (int round = 0; round < 12; ++round) {
    host::BuildOptions o;
    const int half = 1 + round % 6;
    const std::string axis = std::to_string(-half) + ":" + std::to_string(half) + ":" + std::to_string(2 * half + 1);
    o.space.x = host::parse_axis(axis, "x");
    o.space.y = host::parse_axis(round % 2 ? "0:0:1" : axis, "y");
    o.keep = round % 3 == 0 ? 1.0 : round % 3 == 1 ? 0.3 : 0.04;
    o.compact_offsets = round % 4 != 3;
    const auto bytes = host::build_table(point_model(testing::random_points(rng, 8 + 9 * round, 4 + round)), o);
    const TableView t = testing::open_table(bytes);
    encodings.insert(t.offset_delta_bytes());
    const auto features = random_features(rng, t, 0.35);
    std::vector<VoteCounter> counters(t.cell_count(), 0);
    VoteTally tally;
    ASSERT_EQ(accumulate_votes(t, features, counters, tally), Status::kOk);
    std::vector<VoteCounter> expected(t.cell_count(), 0);
    for (const RoiPoint& f : features) {
      const std::uint32_t p = std::uint32_t{f.row} * t.roi_width() + f.col;
      for (std::uint32_t i = t.references_begin(p); i < t.references_begin(p + 1); ++i) ++expected[t.reference(i)];
    }
    EXPECT_EQ(counters, expected) << "round " << round;
    // And through the offsets expanded once (what hosted programs do for a compact table).
    std::vector<std::uint32_t> expanded(expanded_offsets_count(t));
    ASSERT_EQ(expand_offsets(t, expanded), Status::kOk);
    std::vector<VoteCounter> again(t.cell_count(), 0);
    VoteTally tally_again;
    ASSERT_EQ(accumulate_votes_expanded(t, expanded, features, again, tally_again), Status::kOk);
    EXPECT_EQ(again, expected) << "round " << round;
    EXPECT_EQ(tally_again.votes, tally.votes);
    expanded.pop_back();
    EXPECT_EQ(accumulate_votes_expanded(t, expanded, features, again, tally_again), Status::kBufferTooSmall);
  }
  EXPECT_TRUE(encodings.count(0) && (encodings.count(1) || encodings.count(2)));
}

TEST(Voter, TiesResolveToTheLowestCellIndex) {
  // One model point and 1-pixel cells: every stencil is one pixel, so voting
  // for every pixel gives every cell exactly one vote.
  const auto bytes = build(point_model({{0, 0}}), "-2:2:5", "-2:2:5");
  const TableView t = testing::open_table(bytes);
  std::vector<VoteCounter> counters(t.cell_count(), 1);
  CellScore top[3];
  ASSERT_EQ(select_top_cells(t, counters, top), Status::kOk);
  EXPECT_EQ(top[0].cell, 0u);
  EXPECT_EQ(top[1].cell, 1u);
  EXPECT_EQ(top[2].cell, 2u);
  counters[17] = 2;
  counters[9] = 2;
  ASSERT_EQ(select_top_cells(t, counters, top), Status::kOk);
  EXPECT_EQ(top[0].cell, 9u);
  EXPECT_EQ(top[1].cell, 17u);
  EXPECT_EQ(top[2].cell, 0u);
}

TEST(Voter, RanksByVotesRelativeToStencilSize) {
  const CellScore small{5, 9, 10};   // 0.9
  const CellScore big{2, 80, 100};   // 0.8
  EXPECT_TRUE(ranks_before(small, big));
  EXPECT_FALSE(ranks_before(big, small));
  const CellScore same_ratio_lower_index{1, 45, 50};  // 0.9, lower index
  EXPECT_TRUE(ranks_before(same_ratio_lower_index, small));
  EXPECT_TRUE(scores_equal(same_ratio_lower_index, small));
  const CellScore empty_stencil{0, 0, 0};
  EXPECT_TRUE(ranks_before(big, empty_stencil));  // 0/0 reads as 0, not a tie
  EXPECT_FLOAT_EQ(normalised_score(small), 0.9f);
}

TEST(Voter, TopKIsTheSortedOrderOfAllCells) {
  app::Rng rng(9);
  const auto bytes = build(point_model(testing::random_points(rng, 40, 12)), "-5:5:11", "-5:5:11", "0:0:1", 0.3, 4);
  const TableView t = testing::open_table(bytes);
  for (int round = 0; round < 20; ++round) {
    std::vector<VoteCounter> counters(t.cell_count());
    for (auto& c : counters) c = static_cast<VoteCounter>(rng.next_u32() % 12);  // many ties
    std::vector<CellScore> all;
    for (std::uint32_t c = 0; c < t.cell_count(); ++c) all.push_back({c, counters[c], t.stencil_size(c)});
    std::sort(all.begin(), all.end(), ranks_before);
    std::vector<CellScore> top(7);
    ASSERT_EQ(select_top_cells(t, counters, top), Status::kOk);
    for (std::size_t i = 0; i < top.size(); ++i) EXPECT_EQ(top[i].cell, all[i].cell) << "rank " << i;
  }
}

// best_cell_in is the first of its range in ranks_before's order, ties
// to the lowest index, and kNoCell for an empty range.
TEST(Voter, BestCellInARangeIsTheFirstOfItsSortedOrder) {
  app::Rng rng(13);
  const auto bytes = build(point_model(testing::random_points(rng, 40, 12)), "-5:5:11", "-5:5:11", "0:0:1", 0.3, 4);
  const TableView t = testing::open_table(bytes);
  EXPECT_EQ(best_cell_in(t, std::vector<VoteCounter>(t.cell_count()), CellRange{3, 3}).cell, kNoCell);
  for (int round = 0; round < 40; ++round) {
    std::vector<VoteCounter> counters(t.cell_count());
    for (auto& c : counters) c = static_cast<VoteCounter>(rng.next_u32() % 6);  // many ties
    const std::uint32_t begin = rng.next_u32() % t.cell_count();
    const std::uint32_t end = begin + 1 + rng.next_u32() % (t.cell_count() - begin);
    std::vector<CellScore> range;
    for (std::uint32_t c = begin; c < end; ++c) range.push_back({c, counters[c], t.stencil_size(c)});
    std::sort(range.begin(), range.end(), ranks_before);
    const CellScore best = best_cell_in(t, counters, CellRange{begin, end});
    EXPECT_EQ(best.cell, range.front().cell) << begin << ".." << end;
    EXPECT_EQ(best.votes, range.front().votes);
  }
}

TEST(Voter, CountersSaturateInsteadOfWrapping) {
  const auto bytes = build(point_model({{0, 0}, {1, 0}}), "0:1:2", "0:0:1");
  const TableView t = testing::open_table(bytes);
  const std::vector<RoiPoint> same(70000, RoiPoint{1, 0});  // one pixel listed many times
  std::vector<VoteCounter> counters(t.cell_count(), 0);
  VoteTally tally;
  ASSERT_EQ(accumulate_votes(t, same, counters, tally), Status::kOk);
  for (VoteCounter c : counters) EXPECT_TRUE(c == 0 || c == kVoteCounterMax);
  EXPECT_EQ(*std::max_element(counters.begin(), counters.end()), kVoteCounterMax);
}

// A call whose votes cannot reach the maximum counts with plain increments,
// one that could saturates: on either side of the boundary the counts are
// what saturating each vote gives (the same pixel voted 100 times, counters
// starting 100 and 99 below the maximum).
TEST(Voter, CountsTheSameEitherSideOfWhereACounterCouldSaturate) {
  const auto bytes = build(point_model({{0, 0}, {1, 0}}), "0:1:2", "0:0:1");
  const TableView t = testing::open_table(bytes);
  const std::vector<RoiPoint> same(100, RoiPoint{1, 0});
  for (const int below : {100, 99}) {
    std::vector<VoteCounter> counters(t.cell_count(), static_cast<VoteCounter>(kVoteCounterMax - below));
    std::vector<VoteCounter> expected = counters;
    VoteTally tally;
    ASSERT_EQ(accumulate_votes(t, same, counters, tally), Status::kOk);
    for (std::uint32_t i = t.references_begin(1); i < t.references_begin(2); ++i) {
      const std::uint32_t c = t.reference(i);
      expected[c] = static_cast<VoteCounter>(std::min<std::uint32_t>(expected[c] + 100u, kVoteCounterMax));
    }
    EXPECT_EQ(counters, expected) << below;
    EXPECT_GT(tally.votes, 0u);
  }
}

TEST(Voter, RejectsFeaturesOutsideTheRoiWithoutTouchingCounters) {
  const auto bytes = build(point_model({{0, 0}, {2, 1}}), "-1:1:3", "-1:1:3");
  const TableView t = testing::open_table(bytes);
  std::vector<VoteCounter> counters(t.cell_count(), 3);
  VoteTally tally;
  const std::vector<RoiPoint> f = {{0, 0}, {t.roi_width(), 0}};
  EXPECT_EQ(accumulate_votes(t, f, counters, tally), Status::kFeatureOutOfRoi);
  EXPECT_EQ(std::count(counters.begin(), counters.end(), 3), static_cast<long>(t.cell_count()));
  EXPECT_EQ(tally.votes, 0u);
}

TEST(Voter, RejectsWrongBufferSizes) {
  const auto bytes = build(point_model({{0, 0}}), "-1:1:3", "0:0:1");
  const TableView t = testing::open_table(bytes);
  std::vector<VoteCounter> short_counters(t.cell_count() - 1);
  VoteTally tally;
  EXPECT_EQ(accumulate_votes(t, {}, short_counters, tally), Status::kBufferTooSmall);
  EXPECT_EQ(clear_counters(t, short_counters), Status::kBufferTooSmall);
  std::vector<VoteCounter> counters(t.cell_count());
  std::vector<CellScore> too_many(t.cell_count() + 1);
  EXPECT_EQ(select_top_cells(t, counters, too_many), Status::kInvalidArgument);
  EXPECT_EQ(select_top_cells(t, counters, {}), Status::kInvalidArgument);
  EXPECT_EQ(accumulate_votes(TableView{}, {}, counters, tally), Status::kInvalidArgument);
}

}  // namespace
}  // namespace gabarit
