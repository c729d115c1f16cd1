// The cross-target test vectors: reproducible, replayed exactly on the host,
// and a replay that differs in any field is reported with its frame and field.
#include "gabarit/app/test_vectors.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

#include "gabarit/byte_order.hpp"
#include "gabarit/crc32.hpp"
#include "gabarit/host/scenes/test_vector_scene.hpp"
#include "gabarit/host/runs/tracking_run.hpp"
#include "gabarit/particle_measures.hpp"

namespace gabarit {
namespace {

std::vector<std::byte> read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<char> chars((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::byte> out(chars.size());
  std::memcpy(out.data(), chars.data(), chars.size());
  return out;
}

void reseal(std::vector<std::byte>& file) {
  const std::size_t body = file.size() - vectors::kTrailerBytes;
  store_le<std::uint32_t>(file.data() + body, crc32(std::span<const std::byte>(file.data(), body)));
}

class TestVectors : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = std::filesystem::temp_directory_path() / ("gabarit-vectors-test-" + std::to_string(::getpid()));
    host::VectorSceneOptions o;
    o.model_points = 300;
    o.depths = 2;
    o.frames = 4;
    o.keep = 0.5;
    o.session_frames = 14;
    o.hidden_from = 3;
    o.hidden_frames = 8;
    o.particles = 300;
    summary_ = host::write_test_vectors(o, (dir_ / "a").string());
    host::write_test_vectors(o, (dir_ / "b").string());
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }

  // Table a/table.gbt, copied to 8-byte-aligned storage (the sections are aligned).
  struct AlignedTable {
    explicit AlignedTable(const char* name = "table.gbt") {
      const std::vector<std::byte> bytes = read_bytes(dir_ / "a" / name);
      words.resize((bytes.size() + 7) / 8);
      std::memcpy(words.data(), bytes.data(), bytes.size());
      EXPECT_EQ(TableView::open({reinterpret_cast<const std::byte*>(words.data()), bytes.size()}, view), Status::kOk);
    }
    std::vector<std::uint64_t> words;
    TableView view;
  };

  // Replays `file` on the host against table a/table.gbt.
  static Status replay(const std::vector<std::byte>& file, vectors::Report& report) {
    AlignedTable aligned;
    const TableView& table = aligned.view;
    vectors::VectorSet set;
    GABARIT_TRY(vectors::open_vectors(file, set));
    app::TrackerBuffers buffers(table, app::VoterChoice::kCsr);
    return vectors::check_vectors(table, set, buffers.scratch(), report);
  }

  // Replays session `file` on the host against table a/table.gbt.
  static Status replay_session(const std::vector<std::byte>& file, vectors::Report& report) {
    AlignedTable aligned;
    const TableView& table = aligned.view;
    vectors::SessionVectorSet set;
    GABARIT_TRY(vectors::open_session_vectors(file, set));
    app::SessionBuffers buffers(table, nullptr, app::VoterChoice::kCsr, true);
    std::vector<ImageView> stack(set.stack_depths);
    return vectors::check_session_vectors(table, set, buffers.scratch(), stack, report);
  }

  // Replays particle `file` on the host against table a/table.gbt, with
  // scratch for `particles` particles.
  static Status replay_particles(const std::vector<std::byte>& file, vectors::Report& report, std::uint32_t particles = 300,
                                 const char* table_name = "table.gbt") {
    AlignedTable aligned(table_name);
    const TableView& table = aligned.view;
    vectors::ParticleVectorSet set;
    GABARIT_TRY(vectors::open_particle_vectors(file, set));
    std::vector<Particle> cloud(particle_scratch_particles(particles)), next(particle_scratch_particles(particles));
    std::vector<std::uint32_t> order(particle_scratch_order(particles));
    std::vector<std::uint64_t> bits(edge_map_words(set.width, set.height));
    std::vector<RoiPoint> features(edge_map_features(set.width));
    app::TrackerBuffers buffers(table, app::VoterChoice::kCsr);
    std::vector<ImageView> stack_views(table.depth_count());
    std::vector<IntensityCorrelationMeasure> measures(2);
    return vectors::check_particle_vectors(table, set, {{cloud, next, order}, bits, features, buffers.scratch(), stack_views, measures},
                                           report);
  }

  static inline std::filesystem::path dir_;
  static inline host::VectorSceneSummary summary_;
};

TEST_F(TestVectors, SameOptionsWriteTheSameBytes) {
  EXPECT_EQ(read_bytes(dir_ / "a" / "table.gbt"), read_bytes(dir_ / "b" / "table.gbt"));
  EXPECT_EQ(read_bytes(dir_ / "a" / "vectors.gbv"), read_bytes(dir_ / "b" / "vectors.gbv"));
  EXPECT_EQ(read_bytes(dir_ / "a" / "session.gbs"), read_bytes(dir_ / "b" / "session.gbs"));
  EXPECT_EQ(read_bytes(dir_ / "a" / "session-screened.gbs"), read_bytes(dir_ / "b" / "session-screened.gbs"));
  EXPECT_EQ(read_bytes(dir_ / "a" / "particle.gbp"), read_bytes(dir_ / "b" / "particle.gbp"));
  EXPECT_EQ(read_bytes(dir_ / "a" / "particle-table.gbt"), read_bytes(dir_ / "b" / "particle-table.gbt"));
  EXPECT_EQ(read_bytes(dir_ / "a" / "particle-intensity.gbp"), read_bytes(dir_ / "b" / "particle-intensity.gbp"));
}

// The session's sequence exercises what the session adds: the target is
// hidden long enough to be lost, and found again.
TEST_F(TestVectors, TheSessionReplaysExactlyThroughALostPeriod) {
  EXPECT_GT(summary_.session_lost_frames, 0u);
  EXPECT_TRUE(summary_.session_reacquired);
  vectors::Report report;
  ASSERT_EQ(replay_session(read_bytes(dir_ / "a" / "session.gbs"), report), Status::kOk);
  EXPECT_TRUE(report.match) << "frame " << report.frame << " field " << report.field;
  EXPECT_EQ(report.frames_checked, 14u);
}

// The same sequence with the recovery screened from shared search features
// (the hosted default): replayed exactly, and refused without the scratch.
TEST_F(TestVectors, TheScreenedSessionReplaysExactlyAndNeedsItsScratch) {
  const auto file = read_bytes(dir_ / "a" / "session-screened.gbs");
  vectors::SessionVectorSet set;
  ASSERT_EQ(vectors::open_session_vectors(file, set), Status::kOk);
  EXPECT_TRUE(set.shared_search_features);
  vectors::Report report;
  ASSERT_EQ(replay_session(file, report), Status::kOk);
  EXPECT_TRUE(report.match) << "frame " << report.frame << " field " << report.field;
  EXPECT_EQ(report.frames_checked, 14u);
  AlignedTable aligned;
  app::TrackerBuffers tracker(aligned.view, app::VoterChoice::kCsr);
  std::vector<ImageView> stack(set.stack_depths);
  EXPECT_EQ(vectors::check_session_vectors(aligned.view, set, {tracker.scratch(), {}, {}}, stack, report), Status::kBufferTooSmall);
  // The two recordings differ: the screened search is a different computation.
  EXPECT_NE(file, read_bytes(dir_ / "a" / "session.gbs"));
}

TEST_F(TestVectors, ADifferentSessionResultIsReportedWithFrameAndField) {
  std::vector<std::byte> file = read_bytes(dir_ / "a" / "session.gbs");
  vectors::SessionVectorSet set;
  ASSERT_EQ(vectors::open_session_vectors(file, set), Status::kOk);
  // Frame 1's session pose x (after the vote's record), one ulp off.
  const std::size_t at = static_cast<std::size_t>(set.expected.data() - file.data()) + vectors::kSessionRecordBytes +
                         vectors::kRecordBytes;
  store_le<std::uint32_t>(file.data() + at, load_le<std::uint32_t>(file.data() + at) + 1);
  reseal(file);
  vectors::Report report;
  ASSERT_EQ(replay_session(file, report), Status::kOk);
  EXPECT_FALSE(report.match);
  EXPECT_EQ(report.frame, 1u);
  EXPECT_STREQ(report.field, "session_x");
  EXPECT_EQ(report.expected, report.actual + 1);
}

TEST_F(TestVectors, DamagedSessionFilesAreRefused) {
  const std::vector<std::byte> good = read_bytes(dir_ / "a" / "session.gbs");
  vectors::SessionVectorSet set;
  auto flipped = good;
  flipped[vectors::kSessionHeaderBytes + 10] ^= std::byte{0x01};  // a stack pixel
  EXPECT_EQ(vectors::open_session_vectors(flipped, set), Status::kBadChecksum);
  EXPECT_EQ(vectors::open_session_vectors(std::span(good).first(good.size() - 1), set), Status::kTruncated);
  auto flags = good;
  flags[21] = std::byte{0x10};  // an unknown option flag
  reseal(flags);
  EXPECT_EQ(vectors::open_session_vectors(flags, set), Status::kBadHeaderField);
  auto interval = good;
  store_le<std::uint32_t>(interval.data() + 68, 0);  // recovery interval 0
  reseal(interval);
  EXPECT_EQ(vectors::open_session_vectors(interval, set), Status::kBadHeaderField);
  EXPECT_EQ(vectors::open_session_vectors(read_bytes(dir_ / "a" / "vectors.gbv"), set), Status::kBadMagic);
}

TEST_F(TestVectors, TheHostReplaysItsOwnVectorsExactly) {
  vectors::Report report;
  ASSERT_EQ(replay(read_bytes(dir_ / "a" / "vectors.gbv"), report), Status::kOk);
  EXPECT_TRUE(report.match) << "frame " << report.frame << " field " << report.field;
  EXPECT_EQ(report.frames_checked, 4u);
}

TEST_F(TestVectors, ADifferentResultIsReportedWithFrameAndField) {
  std::vector<std::byte> file = read_bytes(dir_ / "a" / "vectors.gbv");
  vectors::VectorSet set;
  ASSERT_EQ(vectors::open_vectors(file, set), Status::kOk);
  // Frame 2's best-cell vote count (record offset 20), one more than the host saw.
  const std::size_t at = static_cast<std::size_t>(set.expected.data() - file.data()) + 2 * vectors::kRecordBytes + 20;
  store_le<std::uint16_t>(file.data() + at, static_cast<std::uint16_t>(load_le<std::uint16_t>(file.data() + at) + 1));
  reseal(file);
  vectors::Report report;
  ASSERT_EQ(replay(file, report), Status::kOk);
  EXPECT_FALSE(report.match);
  EXPECT_EQ(report.frame, 2u);
  EXPECT_STREQ(report.field, "best_votes");
  EXPECT_EQ(report.expected, report.actual + 1);
  EXPECT_EQ(report.frames_checked, 2u);
}

TEST_F(TestVectors, DamagedFilesAreRefused) {
  const std::vector<std::byte> good = read_bytes(dir_ / "a" / "vectors.gbv");
  vectors::VectorSet set;
  auto flipped = good;
  flipped[vectors::kHeaderBytes + 100] ^= std::byte{0x01};  // one frame pixel
  EXPECT_EQ(vectors::open_vectors(flipped, set), Status::kBadChecksum);
  EXPECT_EQ(vectors::open_vectors(std::span(good).first(good.size() - 1), set), Status::kTruncated);
  EXPECT_EQ(vectors::open_vectors(std::span(good).first(10), set), Status::kTruncated);
  auto longer = good;
  longer.push_back(std::byte{0});
  EXPECT_EQ(vectors::open_vectors(longer, set), Status::kSizeMismatch);
  auto magic = good;
  magic[0] = std::byte{'X'};
  EXPECT_EQ(vectors::open_vectors(magic, set), Status::kBadMagic);
  auto zero_frames = good;
  store_le<std::uint32_t>(zero_frames.data() + 8, 0);
  EXPECT_EQ(vectors::open_vectors(zero_frames, set), Status::kBadHeaderField);
}

// particle.gbp was recorded with app::ParticleTracker (what gabarit track
// --tracker particle runs); the replay composes the kernel's filter on the
// caller's memory, as the firmware does, and must give the same bits.
TEST_F(TestVectors, TheParticleTrackerReplaysExactlyThroughTheOcclusion) {
  EXPECT_GT(summary_.particle_frames_tracking, 0u);
  EXPECT_LT(summary_.particle_frames_tracking, 14u) << "the hidden frames are not tracking";
  const auto file = read_bytes(dir_ / "a" / "particle.gbp");
  vectors::ParticleVectorSet set;
  ASSERT_EQ(vectors::open_particle_vectors(file, set), Status::kOk);
  EXPECT_EQ(set.particles, 300u);
  EXPECT_EQ(set.proposals, 4u);
  EXPECT_TRUE(set.finer);
  vectors::Report report;
  ASSERT_EQ(replay_particles(file, report), Status::kOk);
  EXPECT_TRUE(report.match) << "frame " << report.frame << " field " << report.field;
  EXPECT_EQ(report.frames_checked, 14u);
  // Short of memory for the file's particles: refused, not overrun.
  EXPECT_EQ(replay_particles(file, report, 299), Status::kBufferTooSmall);
}

// The intensity measure, what gabarit track --tracker particle runs on a
// table with model images, on the same model's table with its images.
TEST_F(TestVectors, TheIntensityParticleTrackerReplaysExactlyOnItsTable) {
  EXPECT_GT(summary_.particle_intensity_frames_tracking, 0u);
  const auto file = read_bytes(dir_ / "a" / "particle-intensity.gbp");
  vectors::ParticleVectorSet set;
  ASSERT_EQ(vectors::open_particle_vectors(file, set), Status::kOk);
  EXPECT_TRUE(set.intensity);
  EXPECT_EQ(set.intensity_samples, kIntensityMeasureSamples);
  vectors::Report report;
  ASSERT_EQ(replay_particles(file, report, 300, "particle-table.gbt"), Status::kOk);
  EXPECT_TRUE(report.match) << "frame " << report.frame << " field " << report.field;
  EXPECT_EQ(report.frames_checked, 14u);
  // On a table without model images: refused, not scored against nothing.
  EXPECT_EQ(replay_particles(file, report, 300, "table.gbt"), Status::kInvalidArgument);
}

TEST_F(TestVectors, ADifferentParticleEstimateIsReportedWithFrameAndField) {
  std::vector<std::byte> file = read_bytes(dir_ / "a" / "particle.gbp");
  vectors::ParticleVectorSet set;
  ASSERT_EQ(vectors::open_particle_vectors(file, set), Status::kOk);
  // Frame 1's score (record offset 16), one ulp off.
  const std::size_t at = static_cast<std::size_t>(set.expected.data() - file.data()) + vectors::kParticleRecordBytes + 16;
  store_le<std::uint32_t>(file.data() + at, load_le<std::uint32_t>(file.data() + at) ^ 1u);
  reseal(file);
  vectors::Report report;
  ASSERT_EQ(replay_particles(file, report), Status::kOk);
  EXPECT_FALSE(report.match);
  EXPECT_EQ(report.frame, 1u);
  EXPECT_STREQ(report.field, "score");
  EXPECT_EQ(report.frames_checked, 1u);
}

TEST_F(TestVectors, DamagedParticleFilesAreRefused) {
  const std::vector<std::byte> good = read_bytes(dir_ / "a" / "particle.gbp");
  vectors::ParticleVectorSet set;
  auto flipped = good;
  flipped[vectors::kParticleHeaderBytes + 100] ^= std::byte{0x01};
  EXPECT_EQ(vectors::open_particle_vectors(flipped, set), Status::kBadChecksum);
  EXPECT_EQ(vectors::open_particle_vectors(std::span(good).first(good.size() - 1), set), Status::kTruncated);
  const auto header_field = [&](std::size_t offset, std::uint32_t value, std::size_t bytes) {
    auto bad = good;
    if (bytes == 1) bad[offset] = static_cast<std::byte>(value);
    if (bytes == 2) store_le<std::uint16_t>(bad.data() + offset, static_cast<std::uint16_t>(value));
    if (bytes == 4) store_le<std::uint32_t>(bad.data() + offset, value);
    reseal(bad);
    return vectors::open_particle_vectors(bad, set);
  };
  EXPECT_EQ(header_field(21, 2, 1), Status::kBadHeaderField) << "unknown flag";
  EXPECT_EQ(header_field(38, 9, 2), Status::kBadHeaderField) << "proposals over 8";
  EXPECT_EQ(header_field(40, 0, 4), Status::kBadHeaderField) << "no particles";
  EXPECT_EQ(header_field(40, vectors::kMaxVectorParticles + 1, 4), Status::kBadHeaderField) << "too many particles";
  EXPECT_EQ(header_field(44, 0, 4), Status::kBadHeaderField) << "stride 0";
  EXPECT_EQ(header_field(48, 4, 4), Status::kBadHeaderField) << "tolerance over 3";
  EXPECT_EQ(header_field(52, 256, 4), Status::kBadHeaderField) << "intensity samples without the intensity measure";
  EXPECT_EQ(header_field(21, 3, 1), Status::kBadHeaderField) << "the intensity measure without its samples";
  const auto intensity = read_bytes(dir_ / "a" / "particle-intensity.gbp");
  auto too_few = intensity;
  store_le<std::uint32_t>(too_few.data() + 52, 15);
  reseal(too_few);
  EXPECT_EQ(vectors::open_particle_vectors(too_few, set), Status::kBadHeaderField) << "fewer than 16 samples";
  EXPECT_EQ(header_field(40, 301, 4), Status::kOk) << "the header's own check passes; the replay then needs more scratch";
  EXPECT_EQ(vectors::open_particle_vectors(read_bytes(dir_ / "a" / "session.gbs"), set), Status::kBadMagic);
}

}  // namespace
}  // namespace gabarit
