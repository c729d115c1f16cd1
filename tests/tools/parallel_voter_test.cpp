// Multi-threaded voting: bit-identical to the reference voter for any number
// of threads, on awkward table sizes, including saturating counters.
#include "gabarit/host/runs/parallel_voter.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "test_tables.hpp"

namespace gabarit {
namespace {

TEST(ParallelVoter, CountersAreBitIdenticalToTheReferenceVoter) {
  app::Rng rng(17);
  for (const char* axis : {"0:0:1", "-1:1:3", "-3:3:7", "-6:6:13"}) {
    const auto bytes = testing::build(testing::point_model(testing::random_points(rng, 45, 10)), axis, "-2:2:5");
    const TableView t = testing::open_table(bytes);
    std::vector<RoiPoint> features;
    for (int i = 0; i < 700; ++i)
      features.push_back({static_cast<std::uint16_t>(rng.uniform_int(0, t.roi_width() - 1)),
                          static_cast<std::uint16_t>(rng.uniform_int(0, t.roi_height() - 1))});
    std::vector<VoteCounter> reference(t.cell_count(), 0);
    VoteTally want;
    ASSERT_EQ(accumulate_votes(t, features, reference, want), Status::kOk);
    for (unsigned threads : {1u, 2u, 3u, 4u, 7u}) {
     for (const auto split : {host::ParallelVoter::Split::kCells, host::ParallelVoter::Split::kFeatures}) {
      host::ParallelVoter voter(threads, split);
      std::vector<VoteCounter> counters(t.cell_count(), 0);
      VoteTally got;
      ASSERT_EQ(voter.accumulate(t, features, counters, got), Status::kOk);
      EXPECT_EQ(counters, reference) << axis << ", " << threads << " threads";
      EXPECT_EQ(got.votes, want.votes);
      EXPECT_EQ(got.features, want.features);
      // Again, from counters near saturation: the same saturated values.
      std::vector<VoteCounter> high(t.cell_count(), 65530), high_ref(t.cell_count(), 65530);
      VoteTally a, b;
      ASSERT_EQ(accumulate_votes(t, features, high_ref, a), Status::kOk);
      ASSERT_EQ(voter.accumulate(t, features, high, b), Status::kOk);
      EXPECT_EQ(high, high_ref);
     }
    }
  }
}

TEST(ParallelVoter, AFeatureOutsideTheRoiIsRefused) {
  app::Rng rng(2);
  const auto bytes = testing::build(testing::point_model(testing::random_points(rng, 20, 6)), "-2:2:5", "-2:2:5");
  const TableView t = testing::open_table(bytes);
  for (const auto split : {host::ParallelVoter::Split::kCells, host::ParallelVoter::Split::kFeatures}) {
    host::ParallelVoter voter(3, split);
    std::vector<VoteCounter> counters(t.cell_count(), 0);
    const std::vector<RoiPoint> features{{0, 0}, {1, 1}, {t.roi_width(), 0}};
    VoteTally tally;
    EXPECT_EQ(voter.accumulate(t, features, counters, tally), Status::kFeatureOutOfRoi);
  }
}

}  // namespace
}  // namespace gabarit
