// The word-parallel voter against the CSR reference, bit for bit, on awkward
// shapes: cell counts on both sides of 64-bit word boundaries, feature counts
// that are not multiples of the 8-mask step, blocks past 65535 features
// (saturation), and whole tracking steps with both detectors and rotation.
#include "gabarit/dense_voter.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "../../kernel/src/dense_lanes.hpp"
#include "gabarit/app/image_io.hpp"
#include "gabarit/features.hpp"
#include "gabarit/tracker.hpp"
#include "test_tables.hpp"

namespace gabarit {
namespace {

struct Dense {
  explicit Dense(const TableView& t)
      : masks(dense_mask_words(t.roi_slots(), t.cell_count())), scratch(dense_scratch_words(t.cell_count())) {
    EXPECT_EQ(build_dense_masks(t, masks), Status::kOk);
  }
  std::vector<std::uint64_t> masks, scratch;
};

// x cells, y cells -> cell counts 1, 63, 64, 65, 121, 128, 129, 1024, and
// 289, 441 and 841 (5, 7 and 14 words: a vector body's tails).
const std::pair<const char*, const char*> kSpaces[] = {
    {"0:0:1", "0:0:1"},     {"-31:31:63", "0:0:1"}, {"-31.5:31.5:64", "0:0:1"}, {"-32:32:65", "0:0:1"},
    {"-5:5:11", "-5:5:11"}, {"-8:7:16", "-4:3:8"},  {"-64:64:129", "0:0:1"},    {"-16:15:32", "-16:15:32"},
    {"-8:8:17", "-8:8:17"}, {"-10:10:21", "-10:10:21"}, {"-14:14:29", "-14:14:29"},
};

TEST(DenseVoter, MatchesTheCsrVoterBitForBit) {
  app::Rng rng(31);
  for (const auto& [x, y] : kSpaces) {
    const auto bytes = testing::build(testing::point_model(testing::random_points(rng, 6, 6)), x, y);
    const TableView t = testing::open_table(bytes);
    Dense d(t);
    std::vector<RoiPoint> all;
    for (std::uint16_t r = 0; r < t.roi_height(); ++r)
      for (std::uint16_t c = 0; c < t.roi_width(); ++c) all.push_back({c, r});
    for (std::size_t n : {0u, 1u, 7u, 8u, 9u, 15u, 17u, 100u, 1001u}) {
      std::vector<RoiPoint> f;
      for (std::size_t i = 0; i < n; ++i) f.push_back(all[rng.next_u32() % all.size()]);  // duplicates allowed
      std::vector<VoteCounter> a(t.cell_count(), 3), b(t.cell_count(), 3);
      VoteTally ta, tb;
      ASSERT_EQ(accumulate_votes(t, f, a, ta), Status::kOk);
      ASSERT_EQ(accumulate_votes_dense(t, d.masks, f, b, d.scratch, tb), Status::kOk);
      ASSERT_EQ(a, b) << t.cell_count() << " cells, " << n << " features";
      EXPECT_EQ(ta.votes, tb.votes);
      EXPECT_EQ(ta.features, tb.features);
    }
  }
}

// Each vector body this build has and this CPU runs (kernel/src/
// vector_body.hpp), against the scalar body, on every width from 1 to 17
// words: whole vectors, AVX2's half vector and a scalar tail. The counters
// start random, so that carries ripple through every plane and past the
// last, and some masks are all ones.
TEST(DenseVoter, EveryBodyAddsMasksLikeTheScalarBody) {
  app::Rng rng(77);
  const auto word = [&rng] { return std::uint64_t{rng.next_u32()} << 32 | rng.next_u32(); };
  std::uint32_t bodies_compared = 0;
  for (const VectorBody body : {VectorBody::kSse4, VectorBody::kAvx2, VectorBody::kNeon}) {
    if (!vector_body_runs(body)) continue;
    ++bodies_compared;
    for (std::size_t words = 1; words <= 17; ++words) {
      std::vector<std::uint64_t> state((dense_lanes::kPlanes + 3) * words);
      for (auto& w : state) w = word();
      std::vector<std::uint64_t> vector_state = state;
      const auto view = [words](std::vector<std::uint64_t>& s) {
        std::uint64_t* planes = s.data();
        std::uint64_t* ones = planes + dense_lanes::kPlanes * words;
        return dense_lanes::SlicedWords{planes, ones, ones + words, ones + 2 * words, words};
      };
      for (int round = 0; round < 40; ++round) {
        std::vector<std::uint64_t> masks(8 * words);
        for (auto& m : masks) m = round % 5 == 0 ? ~std::uint64_t{0} : word();
        const std::uint64_t* m[8];
        for (std::size_t k = 0; k < 8; ++k) m[k] = masks.data() + k * words;
        dense_lanes::add8(view(state), m, VectorBody::kScalar);
        dense_lanes::add8(view(vector_state), m, body);
        ASSERT_EQ(state, vector_state) << vector_body_name(body) << ", " << words << " words, round " << round;
      }
    }
  }
  // Where the build made vector bodies, the CPUs CI runs on have one.
#if defined(GABARIT_EXPECT_CANNY_VECTOR_BODY)
  EXPECT_GT(bodies_compared, 0u);
#endif
  EXPECT_STREQ(vector_body_name(vector_body()), canny_vector_body()) << "the Canny rows and the voter run one body";
}

TEST(DenseVoter, SaturatesLikeTheCsrVoterAcrossBlocks) {
  const auto bytes = testing::build(testing::point_model({{0, 0}, {1, 0}, {3, 2}}), "-1:1:3", "0:0:1");
  const TableView t = testing::open_table(bytes);
  Dense d(t);
  for (std::size_t n : {65534u, 65535u, 65536u, 70001u, 140000u}) {
    std::vector<RoiPoint> f(n, RoiPoint{1, 0});
    f[n / 2] = {0, 0};
    std::vector<VoteCounter> a(t.cell_count(), 0), b(t.cell_count(), 0);
    VoteTally ta, tb;
    ASSERT_EQ(accumulate_votes(t, f, a, ta), Status::kOk);
    ASSERT_EQ(accumulate_votes_dense(t, d.masks, f, b, d.scratch, tb), Status::kOk);
    EXPECT_EQ(a, b) << n;
    EXPECT_EQ(ta.votes, tb.votes) << n;
  }
}

TEST(DenseVoter, TrackingStepsAreIdenticalWithEitherVoter) {
  app::Rng rng(12);
  const auto pts = testing::random_points(rng, 70, 15);
  const auto bytes = testing::build(testing::point_model(pts), "-4:4:9", "-4:4:9", "-6:6:3");
  const TableView t = testing::open_table(bytes);
  Dense d(t);
  std::vector<RoiPoint> features(tracker_feature_capacity(t));
  std::vector<VoteCounter> counters(t.cell_count());
  std::vector<std::uint8_t> mask(tracker_mask_bytes(t));
  for (int frame = 0; frame < 30; ++frame) {
    app::GrayImage img(90, 80);
    for (auto& p : img.pixels) p = rng.bernoulli(0.25) ? 255 : 0;
    const Pose pose{45.0f + static_cast<float>(rng.uniform_int(-3, 3)), 40, frame % 3 == 0 ? 0.0f : 4.5f, 0};
    for (auto kind : {table_format::DetectorKind::kBinary, table_format::DetectorKind::kGradientRows}) {
      const Detector det{kind, 200};
      StepResult a, b;
      ASSERT_EQ(track_step(t, det, img.view(), pose, {features, counters, mask}, a), Status::kOk);
      const std::vector<VoteCounter> csr_counters = counters;
      ASSERT_EQ(track_step(t, det, img.view(), pose, {features, counters, mask, d.masks, d.scratch}, b), Status::kOk);
      EXPECT_EQ(csr_counters, counters) << "frame " << frame;
      EXPECT_EQ(a.best.cell, b.best.cell);
      EXPECT_EQ(a.best.votes, b.best.votes);
      EXPECT_EQ(a.runner_up.cell, b.runner_up.cell);
      EXPECT_EQ(a.pose.x, b.pose.x);
      EXPECT_EQ(a.pose.theta_deg, b.pose.theta_deg);
      EXPECT_EQ(a.votes, b.votes);
      EXPECT_EQ(a.features, b.features);
    }
  }
}

TEST(DenseVoter, RejectsTablesAndBuffersItCannotServe) {
  const auto bytes = testing::build(testing::point_model({{0, 0}}), "-512:512:1025", "0:0:1");  // 1025 cells
  const TableView big = testing::open_table(bytes);
  std::vector<std::uint64_t> masks(dense_mask_words(big.roi_pixels(), big.cell_count()));
  EXPECT_EQ(build_dense_masks(big, masks), Status::kInvalidArgument);
  const auto small_bytes = testing::build(testing::point_model({{0, 0}}), "-1:1:3", "0:0:1");
  const TableView t = testing::open_table(small_bytes);
  std::vector<std::uint64_t> short_masks(1), scratch(dense_scratch_words(3)), ok_masks(dense_mask_words(t.roi_pixels(), 3));
  std::vector<VoteCounter> counters(3);
  VoteTally tally;
  EXPECT_EQ(build_dense_masks(t, short_masks), Status::kBufferTooSmall);
  ASSERT_EQ(build_dense_masks(t, ok_masks), Status::kOk);
  EXPECT_EQ(accumulate_votes_dense(t, ok_masks, {}, counters, std::span(scratch).first(2), tally), Status::kBufferTooSmall);
  const std::vector<RoiPoint> outside = {{t.roi_width(), 0}};
  EXPECT_EQ(accumulate_votes_dense(t, ok_masks, outside, counters, scratch, tally), Status::kFeatureOutOfRoi);
}

}  // namespace
}  // namespace gabarit
