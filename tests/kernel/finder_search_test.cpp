// A detection spread over frames (finder_search.hpp): on one frame, any
// budget gives ModelFinder::find's detections bit for bit; each call spends
// about its budget; a survey for look-alikes spread over calls sees what one
// call sees; errors for a search not begun or a frame of another size.
#include "gabarit/finder_search.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "gabarit/detection_recovery.hpp"
#include "finder_rig.hpp"

namespace gabarit {
namespace {

constexpr std::uint32_t kSide = testing::kFinderSide;
using testing::Finding;
using testing::twins;

TEST(FinderSearch, SpreadOverCallsOnOneFrameIsFindBitForBit) {
  Finding t;
  auto& [rig, finder, options, buffers, fine] = t;
  const app::GrayImage frame = twins(rig, 100, 90, 35, 230, 210, -120);
  std::vector<Detection> whole(options.max_count);
  std::uint32_t whole_count = 0;
  ASSERT_EQ(finder.find(frame.view(), options, buffers.scratch(fine.view()), whole, whole_count), Status::kOk);
  ASSERT_EQ(whole_count, 2u);
  std::uint64_t total = 0;
  for (const std::uint64_t budget : {std::uint64_t{1}, std::uint64_t{997}, std::uint64_t{20000}, std::uint64_t{200000}, kUnlimitedWork}) {
    FinderSearch search(finder);
    ASSERT_EQ(search.begin(kSide, kSide, options, buffers.scratch(fine.view())), Status::kOk);
    std::uint64_t most = 0;
    while (search.active()) {
      ASSERT_EQ(search.advance(frame.view(), buffers.scratch(fine.view()), budget), Status::kOk);
      most = std::max(most, search.last_work());
    }
    ASSERT_TRUE(search.done());
    std::vector<Detection> spread(options.max_count);
    std::uint32_t count = 0;
    ASSERT_EQ(search.results(buffers.scratch(fine.view()), spread, count), Status::kOk);
    ASSERT_EQ(count, whole_count) << budget;
    EXPECT_EQ(std::memcmp(spread.data(), whole.data(), count * sizeof(Detection)), 0) << budget;
    // The same work however it is cut (in one call the frame is not held:
    // less by the copy); each call about its budget (the largest piece, a
    // fine vote and its verification, is about 130000 here).
    if (total == 0) {
      total = search.total_work();
    }
    if (budget == kUnlimitedWork) {
      EXPECT_EQ(search.total_work(), total - kSide * kSide / 4);
    } else {
      EXPECT_EQ(search.total_work(), total) << budget;
    }
    if (budget == 200000) {
      EXPECT_LE(most, 2 * budget);
      EXPECT_GE(search.frames(), total / (2 * budget));
    }
    if (budget == kUnlimitedWork) {
      EXPECT_EQ(search.frames(), 1u);
    }
  }
  EXPECT_GT(total, 2000000u);  // a search worth spreading: ten frames at 200000
}

TEST(FinderSearch, RefusesASearchNotBegunAndAFrameOfAnotherSize) {
  Finding t;
  auto& [rig, finder, options, buffers, fine] = t;
  const app::GrayImage frame = twins(rig, 100, 90, 35, 230, 210, -120);
  FinderSearch search(finder);
  EXPECT_EQ(search.advance(frame.view(), buffers.scratch(fine.view()), 1000), Status::kInvalidArgument);
  std::vector<Detection> out(options.max_count);
  std::uint32_t count = 7;
  EXPECT_EQ(search.results(buffers.scratch(fine.view()), out, count), Status::kInvalidArgument);
  EXPECT_EQ(count, 0u);
  ASSERT_EQ(search.begin(kSide, kSide, options, buffers.scratch(fine.view())), Status::kOk);
  const app::GrayImage other(kSide - 8, kSide);
  EXPECT_EQ(search.advance(other.view(), buffers.scratch(fine.view()), 1000), Status::kInvalidArgument);
  EXPECT_FALSE(search.active());
  FinderOptions bad = options;
  bad.candidates = 0;
  EXPECT_EQ(search.begin(kSide, kSide, bad, buffers.scratch(fine.view())), Status::kInvalidArgument);
  EXPECT_EQ(search.begin(0, kSide, options, buffers.scratch(fine.view())), Status::kInvalidArgument);
  EXPECT_EQ(search.begin(kSide + 64, kSide, options, buffers.scratch(fine.view())), Status::kBufferTooSmall);
}

// The survey spread over calls (the session's default after tracked frames)
// sees the copy that one call sees.
TEST(FinderSearch, ASurveySpreadOverFramesSeesTheLookalike) {
  Finding t;
  auto& [rig, finder, options, buffers, fine] = t;
  const app::GrayImage frame = twins(rig, 80, 80, 0, 220, 200, 30);
  const Pose target{80, 80, 0, 0};
  DetectionRecovery at_once(finder, options, buffers.scratch(fine.view()));
  ASSERT_EQ(at_once.survey(frame.view(), target, fine.view(), kUnlimitedWork), Status::kOk);
  ASSERT_TRUE(at_once.surveyed());
  DetectionRecovery spread(finder, options, buffers.scratch(fine.view()));
  int calls = 0;
  while (!spread.surveyed() && calls < 1000) {
    ASSERT_EQ(spread.survey(frame.view(), target, fine.view(), 5000), Status::kOk);
    ++calls;
  }
  EXPECT_GT(calls, 10);
  EXPECT_LT(calls, 1000);
  EXPECT_GT(at_once.lookalike_distance_squared(), 0.0f);
  EXPECT_EQ(spread.lookalike_distance_squared(), at_once.lookalike_distance_squared());
  // A new session forgets it and surveys again.
  spread.restart_survey();
  EXPECT_FALSE(spread.surveyed());
  EXPECT_EQ(spread.lookalike_distance_squared(), 0.0f);
}

// A candidate whose first vote verifies far below min_score is not voted
// again: converging raises a score by little (finder_search.cpp,
// kConvergeFloor), and during an occlusion every candidate is clutter.
// Without the floor, which candidates converge does not depend on
// min_score, and the two searches below cost the same.
TEST(FinderSearch, CandidatesHopelesslyBelowTheMinimumScoreAreNotConverged) {
  Finding t;  // no structured bindings: the lambda below captures (clang 14 refuses bindings there)
  app::GrayImage clutter(kSide, kSide);
  std::uint32_t state = 12345;
  for (std::uint8_t& p : clutter.pixels) {
    state = state * 1664525u + 1013904223u;
    p = (state >> 24) < 3 ? 255 : 0;  // 1.2% of the pixels lit: no model anywhere
  }
  const auto search_work = [&](float min_score, std::uint32_t& found) {
    FinderOptions o = t.options;
    o.min_score = min_score;
    FinderSearch search(t.finder);
    EXPECT_EQ(search.begin(kSide, kSide, o, t.buffers.scratch(t.fine.view())), Status::kOk);
    EXPECT_EQ(search.advance(clutter.view(), t.buffers.scratch(t.fine.view()), kUnlimitedWork), Status::kOk);
    EXPECT_TRUE(search.done());
    std::vector<Detection> out(o.max_count);
    found = 99;
    EXPECT_EQ(search.results(t.buffers.scratch(t.fine.view()), out, found), Status::kOk);
    return search.total_work();
  };
  std::uint32_t found_strict = 0, found_lax = 0;
  const std::uint64_t strict = search_work(t.options.min_score, found_strict);
  const std::uint64_t lax = search_work(0.01f, found_lax);
  EXPECT_EQ(found_strict, 0u);
  EXPECT_GT(found_lax, 0u);  // clutter scores above 0.01: candidates were there to converge
  // At least one fine vote fewer (a vote's extraction alone is over 10000 units here).
  EXPECT_LT(strict + 10000, lax);
}

}  // namespace
}  // namespace gabarit
