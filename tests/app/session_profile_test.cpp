// The session profile: its text file, its mode bits, its validation, and the
// firmware's static twin (platform/cortex-m/firmware_session.hpp) against the
// hosted session that gabarit track, the board and the harness run.
#include "gabarit/app/session_profile.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "firmware_particle_session.hpp"
#include "firmware_session.hpp"
#include "gabarit/app/error.hpp"
#include "gabarit/app/hosted_session.hpp"
#include "gabarit/app/particle_run.hpp"
#include "gabarit/app/image_io.hpp"
#include "gabarit/app/session_profile_io.hpp"
#include "gabarit/host/tables/model.hpp"
#include "gabarit/host/scenes/scene_synth.hpp"
#include "gabarit/app/evaluation.hpp"
#include "gabarit/link/protocol.hpp"
#include "test_tables.hpp"

namespace gabarit::app {
namespace {

SessionProfile tuned() {
  SessionProfile p;
  p.recovery = RecoveryKind::kDetection;
  p.subcell = SubCellKind::kAlignment;
  p.focus_stack = false;
  p.search_budget = 40;
  p.search_interval = 3;
  p.screen_stride = 5;
  p.detect_after = 5;
  p.recovery_frames = 6;
  p.survey_frames = 0;
  p.particles = 77;
  p.seed = 1234567890123ull;
  p.edge_stride = 9;
  p.edge_tolerance = 3;
  p.particle_improvements_off = kImproveModes | kImproveReinit | kImproveProposals | kImproveDetection;
  p.verify_refine = RefineBy::kQuadraticDesign;
  p.particle_clustering = ModeClustering::kRunningMean;
  return p;
}

TEST(SessionProfile, TextRoundTripsEveryKeyAndIsStable) {
  for (const SessionProfile& p : {SessionProfile{}, plain_profile(), tuned()}) {
    const std::string text = format_profile(p);
    EXPECT_EQ(text.rfind(std::string(kProfileMagic) + "\n", 0), 0u);
    const SessionProfile back = parse_profile(text, "t");
    EXPECT_TRUE(back == p) << text;
    EXPECT_EQ(format_profile(back), text);
  }
}

TEST(SessionProfile, ShortFilesKeepTheDefaultsAndCommentsAreSkipped) {
  const SessionProfile p = parse_profile("gabarit-session-profile 1\r\n# mine\n\nplain = true\n  recover=true  \n", "t");
  SessionProfile want = plain_profile();
  want.recover = true;
  EXPECT_TRUE(p == want);
}

TEST(SessionProfile, RefusalsNameTheFileAndLine) {
  const auto refused = [](const std::string& text, const std::string& words) {
    try {
      (void)parse_profile(text, "p.profile");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  refused("", "p.profile: empty");
  refused("plain = true\n", "p.profile:1: not a session profile");
  refused("gabarit-session-profile 1\nplain = yes\n", "p.profile:2: plain 'yes'");
  refused("gabarit-session-profile 1\nverify-refine = newton\n", "p.profile:2: verify-refine 'newton': want gauss-newton or quadratic");
  refused("gabarit-session-profile 1\nspeed = 3\n", "p.profile:2: unknown key 'speed'");
  refused("gabarit-session-profile 1\nseed = 1\nseed = 2\n", "p.profile:3: 'seed' given twice");
  refused("gabarit-session-profile 1\nsearch-interval = 0\n", "p.profile:2: search-interval '0'");
  refused("gabarit-session-profile 1\nsearch-budget = 559\n", "search-budget '559'");
  refused("gabarit-session-profile 1\nwithout = modes,speed\n", "'speed' is none of");
  refused("gabarit-session-profile 1\nplain\n", "p.profile:2: want 'key = value'");
  refused("gabarit-session-profile 1\nplain = true\nrecovery = detect\n", "needs recovery");
  refused("gabarit-session-profile 1\nplain = true\nsubcell = alignment\n", "needs refinement");
}

TEST(SessionProfile, ValidateRefusesWhatNoSessionRuns) {
  EXPECT_EQ(validate(SessionProfile{}), Status::kOk);
  EXPECT_EQ(validate(plain_profile()), Status::kOk);
  EXPECT_EQ(validate(tuned()), Status::kOk);
  const auto bad = [](auto change) {
    SessionProfile p;
    change(p);
    return validate(p) == Status::kInvalidArgument;
  };
  EXPECT_TRUE(bad([](SessionProfile& p) { p.search_interval = 0; }));
  EXPECT_TRUE(bad([](SessionProfile& p) { p.screen_stride = 17; }));
  EXPECT_TRUE(bad([](SessionProfile& p) { p.search_budget = kSearchPlacementCount; }));
  EXPECT_TRUE(bad([](SessionProfile& p) { p.particles = 0; }));
  EXPECT_TRUE(bad([](SessionProfile& p) { p.edge_tolerance = 4; }));
  EXPECT_TRUE(bad([](SessionProfile& p) { p.particle_improvements_off = 1u << 10; }));
  EXPECT_TRUE(bad([](SessionProfile& p) { p.refine = true; }));  // a part added to the full session
  EXPECT_TRUE(bad([](SessionProfile& p) { p.plain = true, p.recovery = RecoveryKind::kParticles; }));
  EXPECT_TRUE(bad([](SessionProfile& p) { p.recovery = static_cast<RecoveryKind>(4); }));
  EXPECT_TRUE(bad([](SessionProfile& p) { p.particle_clustering = static_cast<ModeClustering>(2); }));
}

TEST(SessionProfile, OptionsAreTheKernelsDefaultsAndThePlainLoop) {
  const SessionOptions d = session_options(SessionProfile{});
  const SessionOptions want{};
  EXPECT_EQ(std::memcmp(&d.recovery, &want.recovery, sizeof want.recovery), 0);
  EXPECT_EQ(d.motion_filter, want.motion_filter);
  EXPECT_EQ(d.depth_votes_decisive, want.depth_votes_decisive);
  EXPECT_EQ(d.recovery_frames, want.recovery_frames);
  EXPECT_EQ(d.survey_frames, want.survey_frames);
  const SessionOptions plain = session_options(plain_profile());
  EXPECT_FALSE(plain.motion_filter || plain.refine || plain.recover || plain.vote_at_last_pose || plain.follow_when_unsure);
  SessionProfile parts = plain_profile();
  parts.motion_filter = true;
  const SessionOptions with_filter = session_options(parts);
  EXPECT_TRUE(with_filter.motion_filter && with_filter.vote_at_last_pose && with_filter.follow_when_unsure);
  EXPECT_FALSE(with_filter.refine || with_filter.recover);
  EXPECT_EQ(session_options(tuned()).recovery.budget, 40u);
  EXPECT_TRUE(session_options(tuned()).align_features);
  EXPECT_EQ(session_options(tuned()).recovery_frames, 6.0f);
  EXPECT_EQ(session_options(tuned()).survey_frames, 0.0f);
}

// What a device reports is what the harness's reference runs: the bits of the
// profile read back from them are the same bits, and the same kernel options.
TEST(SessionProfile, ModeBitsCarryTheChoicesAndFlagTunedNumbers) {
  std::vector<SessionProfile> profiles = {SessionProfile{}, plain_profile()};
  for (int parts = 0; parts < 8; ++parts) {
    SessionProfile p = plain_profile();
    p.motion_filter = (parts & 1) != 0, p.refine = (parts & 2) != 0, p.recover = (parts & 4) != 0;
    profiles.push_back(p);
  }
  SessionProfile d;
  d.recovery = RecoveryKind::kDetection;
  profiles.push_back(d);
  d.recovery = RecoveryKind::kParticles, d.subcell = SubCellKind::kAlignment, d.focus_stack = false;
  profiles.push_back(d);
  for (const SessionProfile& p : profiles) {
    for (int effect = 0; effect < 4; ++effect) {
      const std::uint32_t bits = mode_bits(p, (effect & 1) != 0, (effect & 2) != 0);
      EXPECT_EQ(bits & link::kModeTuned, 0u);
      const SessionProfile back = profile_from_mode_bits(bits);
      EXPECT_EQ(mode_bits(back, (effect & 1) != 0, (effect & 2) != 0), bits) << format_profile(p);
      const SessionOptions a = session_options(p), b = session_options(back);
      EXPECT_EQ(std::memcmp(&a.recovery, &b.recovery, sizeof a.recovery), 0);
      EXPECT_EQ(a.motion_filter, b.motion_filter);
      EXPECT_EQ(a.refine, b.refine);
      EXPECT_EQ(a.recover, b.recover);
      EXPECT_EQ(a.align_features, b.align_features);
      EXPECT_EQ(a.vote_at_last_pose, b.vote_at_last_pose);
    }
  }
  EXPECT_NE(mode_bits(tuned(), true, true) & link::kModeTuned, 0u);
}

TEST(SessionProfile, CommandLineGroupReadsIntoTheProfileOnce) {
  Args args("t", "", "", session_option_group());
  ASSERT_TRUE(args.parse({"--recovery", "detect", "--detect-after", "4", "--search-budget", "40", "--no-focus-stack",
                          "--recovery-frames", "6", "--survey-frames", "0"}));
  const SessionProfile p = read_session_profile(args);
  EXPECT_EQ(p.recovery, RecoveryKind::kDetection);
  EXPECT_EQ(p.detect_after, 4u);
  EXPECT_EQ(p.recovery_frames, 6u);
  EXPECT_EQ(p.survey_frames, 0u);
  EXPECT_EQ(p.search_budget, 40u);
  EXPECT_FALSE(p.focus_stack);
  Args refused("t", "", "", session_option_group());
  ASSERT_TRUE(refused.parse({"--plain", "--recovery", "particle"}));
  EXPECT_THROW((void)read_session_profile(refused), UsageError);
  Args stray("t", "", "", session_option_group());
  ASSERT_TRUE(stray.parse({"--recovery", "grid", "--detect-after", "3"}));
  EXPECT_THROW((void)read_session_profile(stray), UsageError);
  Args stray_budget("t", "", "", session_option_group());
  ASSERT_TRUE(stray_budget.parse({"--recovery", "grid", "--recovery-frames", "3"}));
  EXPECT_THROW((void)read_session_profile(stray_budget), UsageError);
  Args too_much("t", "", "", session_option_group());
  ASSERT_TRUE(too_much.parse({"--survey-frames", "1001"}));
  EXPECT_THROW((void)read_session_profile(too_much), UsageError);
  // The default (auto) may detect: --detect-after applies to it.
  Args by_default("t", "", "", session_option_group());
  ASSERT_TRUE(by_default.parse({"--detect-after", "3"}));
  EXPECT_EQ(read_session_profile(by_default).recovery, RecoveryKind::kAuto);
}

// Auto recovery is detection where the session verifies, the grid elsewhere
// (a binary table, the plain loop, verification off).
TEST(SessionProfile, AutoRecoveryIsDetectionWhereTheSessionVerifies) {
  const SessionProfile d;
  EXPECT_EQ(d.recovery, RecoveryKind::kAuto);
  EXPECT_EQ(resolve_recovery(d, true).recovery, RecoveryKind::kDetection);
  EXPECT_EQ(resolve_recovery(d, false).recovery, RecoveryKind::kGrid);
  SessionProfile plain = d;
  plain.plain = true;
  EXPECT_EQ(validate(plain), Status::kOk);
  EXPECT_EQ(resolve_recovery(plain, true).recovery, RecoveryKind::kGrid);
  SessionProfile unverified = d;
  unverified.verify = false;
  EXPECT_EQ(resolve_recovery(unverified, true).recovery, RecoveryKind::kGrid);
  SessionProfile particles = d;
  particles.recovery = RecoveryKind::kParticles;
  EXPECT_EQ(resolve_recovery(particles, true).recovery, RecoveryKind::kParticles);
  // CAPS carries the resolved kind: read back, the grid stays the grid.
  EXPECT_EQ(profile_from_mode_bits(mode_bits(resolve_recovery(d, false), true, true)).recovery, RecoveryKind::kGrid);
  EXPECT_EQ(profile_from_mode_bits(mode_bits(resolve_recovery(d, true), true, true)).recovery, RecoveryKind::kDetection);
}

// A two-depth grayscale scene of the object's own size, the object hidden
// for a while, in a temporary folder: its frames, its model (from its two
// images, Canny) and its first true pose.
struct OccludedScene {
  OccludedScene(const char* name, std::uint32_t frames, std::uint32_t occlusion_start, std::uint32_t occlusion_frames)
      : dir(std::filesystem::temp_directory_path() / (std::string(name) + "-" + std::to_string(::getpid()))) {
    host::SceneOptions so;
    so.frames = frames;
    so.width = 0, so.height = 0;  // the object's own size
    so.depths = 2;
    so.occlusion_start = occlusion_start;
    so.occlusion_frames = occlusion_frames;
    so.blur_every = 0;
    host::write_scene_sequence(so, dir.string());
    host::ImageModelOptions mo;
    mo.canny = true;
    model = host::model_from_images({(dir / "model_00.pgm").string(), (dir / "model_01.pgm").string()}, mo);
    truth = app::read_pose_csv((dir / "gt.csv").string());
    start = {static_cast<float>(truth[0].x), static_cast<float>(truth[0].y), static_cast<float>(truth[0].theta_deg), 0};
  }
  ~OccludedScene() { std::filesystem::remove_all(dir); }
  std::string frames() const { return (dir / "frames.y4m").string(); }
  std::vector<std::byte> table() const { return testing::build(model, "-3:3:7", "-3:3:7", "-1:1:3"); }
  std::filesystem::path dir;
  host::ModelStack model;
  std::vector<PoseSample> truth;
  Pose start;
};

// The firmware's static twin and the hosted session, on the same grayscale
// scene (two depths, an occlusion that loses and re-acquires the target):
// every frame's result bit for bit, from the bits the twin reports in CAPS,
// as the harness builds its reference.
TEST(SessionProfile, FirmwareTwinMatchesTheHostedSessionBitForBit) {
  const OccludedScene scene("gabarit-profile-test", 50, 12, 16);
  const std::vector<std::byte> bytes = scene.table();
  const TableView table = testing::open_table(bytes);
  ASSERT_TRUE(table.has_model_images());

  std::vector<ImageView> views(16);
  mcu::FirmwareSession twin(table, views);
  HostedSession hosted(table, profile_from_mode_bits(twin.mode()));
  EXPECT_EQ(hosted.mode(), twin.mode());
  EXPECT_NE(twin.mode() & link::kModeFocusStack, 0u);
  std::vector<RoiPoint> features(tracker_feature_capacity(table));
  std::vector<VoteCounter> counters(voter_counter_count(table.cell_count()));
  std::vector<std::uint8_t> mask(tracker_mask_bytes(table));
  const TrackerScratch fine{features, counters, mask};

  ASSERT_TRUE(twin.start(scene.start));
  ASSERT_TRUE(hosted.start(scene.start));
  auto frames = open_frames(scene.frames());
  GrayImage frame;
  int lost = 0, n = 0;
  for (; frames->next(frame); ++n) {
    SessionResult a, b;
    ASSERT_EQ(twin.step(frame.view(), fine, a), Status::kOk);
    ASSERT_EQ(hosted.step(frame.view(), b), Status::kOk);
    const auto same = [](float x, float y) { return std::memcmp(&x, &y, sizeof x) == 0; };
    EXPECT_TRUE(same(a.pose.x, b.pose.x) && same(a.pose.y, b.pose.y) && same(a.pose.theta_deg, b.pose.theta_deg)) << "frame " << n;
    EXPECT_EQ(a.pose.depth, b.pose.depth) << n;
    EXPECT_EQ(a.state, b.state) << n;
    EXPECT_EQ(a.confidence, b.confidence) << n;
    EXPECT_TRUE(same(a.score, b.score)) << n;
    EXPECT_EQ(a.step.votes, b.step.votes) << n;
    lost += a.state == TrackState::kLost;
  }
  EXPECT_EQ(n, 50);
  EXPECT_GT(lost, 0) << "the occlusion should have lost the target (the recovery path is compared too)";
}


// The particle tracker is a choice of the profile: its text, the command
// line's group, and CAPS (its measure resolved) carry it.
TEST(SessionProfile, TheParticleTrackerTravelsInTheTextTheOptionsAndCaps) {
  SessionProfile p;
  p.tracker = TrackerKind::kParticle;
  p.particle_measure = ParticleMeasureKind::kEdges;
  EXPECT_EQ(validate(p), Status::kOk);
  const std::string text = format_profile(p);
  EXPECT_NE(text.find("tracker = particle\n"), std::string::npos) << text;
  EXPECT_NE(text.find("measure = edges\n"), std::string::npos) << text;
  EXPECT_TRUE(parse_profile(text, "t") == p);
  EXPECT_EQ(format_profile(SessionProfile{}).find("tracker = stencil\nmeasure = auto\n"), std::string(kProfileMagic).size() + 1);
  for (ParticleMeasureKind m : {ParticleMeasureKind::kEdges, ParticleMeasureKind::kStencil, ParticleMeasureKind::kIntensity}) {
    p.particle_measure = m;
    for (int effect = 0; effect < 4; ++effect) {  // the stencil session's effects do not apply
      const std::uint32_t bits = mode_bits(p, (effect & 1) != 0, (effect & 2) != 0);
      EXPECT_EQ(bits & ~(link::kModeParticleTracker | link::kModeParticleMeasureMask | link::kModeRecoveryDetection), 0u) << bits;
      EXPECT_NE(bits & link::kModeRecoveryDetection, 0u) << bits;  // detection by default
      EXPECT_TRUE(profile_from_mode_bits(bits) == p) << bits;
    }
  }
  // Without detection (a device that cannot run it): CAPS says so, and the
  // profile is not tuned for it.
  SessionProfile undetecting = p;
  undetecting.particle_improvements_off = kImproveDetection;
  EXPECT_FALSE(particle_detection(undetecting));
  const std::uint32_t undetecting_bits = mode_bits(undetecting, false, false);
  EXPECT_EQ(undetecting_bits & (link::kModeRecoveryDetection | link::kModeTuned), 0u) << undetecting_bits;
  EXPECT_TRUE(profile_from_mode_bits(undetecting_bits) == undetecting);
  EXPECT_FALSE(particle_run_options(undetecting).detection);
  EXPECT_TRUE(particle_run_options(p).detection);
  undetecting.particle_improvements_off = kAllImprovements;  // plain CONDENSATION: none
  EXPECT_FALSE(particle_detection(undetecting));
  p.seed = 2;  // numbers do not travel: the harness refuses a tuned device
  EXPECT_NE(mode_bits(p, false, false) & link::kModeTuned, 0u);
  EXPECT_EQ(profile_from_mode_bits(mode_bits(SessionProfile{}, true, true)).tracker, TrackerKind::kStencil);

  SessionProfile bad = p;
  bad.plain = true;  // the particle tracker is not the thesis's loop
  EXPECT_EQ(validate(bad), Status::kInvalidArgument);
  SessionProfile measured;  // a measure names the particle tracker's
  measured.particle_measure = ParticleMeasureKind::kEdges;
  EXPECT_EQ(validate(measured), Status::kInvalidArgument);
  EXPECT_THROW((void)parse_profile("gabarit-session-profile 1\nmeasure = edges\n", "t"), Error);
  EXPECT_THROW((void)parse_profile("gabarit-session-profile 1\ntracker = particle\nplain = true\n", "t"), Error);
  EXPECT_THROW((void)parse_profile("gabarit-session-profile 1\ntracker = kalman\n", "t"), Error);

  Args args("t", "", "", session_option_group());
  ASSERT_TRUE(args.parse({"--tracker", "particle", "--measure", "stencil", "--particles", "300"}));
  const SessionProfile read = read_session_profile(args);
  EXPECT_EQ(read.tracker, TrackerKind::kParticle);
  EXPECT_EQ(read.particle_measure, ParticleMeasureKind::kStencil);
  EXPECT_EQ(read.particles, 300u);
  const ParticleRunOptions run = particle_run_options(read);
  EXPECT_EQ(run.measure, ParticleMeasureKind::kStencil);
  EXPECT_FALSE(run.finer);  // the stencil measure alone reads no edge map
  for (const std::vector<std::string>& refused : std::vector<std::vector<std::string>>{
           {"--measure", "edges"}, {"--tracker", "particle", "--no-verify"}, {"--tracker", "particle", "--plain"},
           {"--tracker", "particle", "--recovery", "grid"}, {"--tracker", "hough"}, {"--tracker", "particle", "--measure", "ncc"}}) {
    Args a("t", "", "", session_option_group());
    ASSERT_TRUE(a.parse(refused));
    EXPECT_THROW((void)read_session_profile(a), UsageError) << refused[1];
  }
}

// The hosted session with the profile's particle tracker runs what gabarit
// track --tracker particle runs (run_particle_tracking), bit for bit, on a
// scene with an occlusion; CAPS reports the measure the table resolves.
TEST(HostedSession, RunsTheProfilesParticleTrackerAsGabaritTrackDoes) {
  const OccludedScene scene("gabarit-particle-session", 24, 8, 6);
  const std::vector<std::byte> bytes = scene.table();
  const TableView table = testing::open_table(bytes);
  const Pose& start = scene.start;
  const auto& truth = scene.truth;

  for (ParticleMeasureKind measure : {ParticleMeasureKind::kAuto, ParticleMeasureKind::kEdges}) {
    SessionProfile p;
    p.tracker = TrackerKind::kParticle;
    p.particle_measure = measure;
    p.particles = 300;
    std::vector<TrackRow> want;
    auto frames = open_frames(scene.frames());
    run_particle_tracking(table, *frames, start, particle_run_options(p), [&](const TrackRow& row) { want.push_back(row); });
    ASSERT_EQ(want.size(), 24u);

    HostedSession hosted(table, p);
    const std::uint32_t resolved = measure == ParticleMeasureKind::kAuto ? 3u : 1u;  // intensity with images, as asked
    // The table verifies (model images, Canny): re-acquisition by detection.
    EXPECT_EQ(hosted.mode(), link::kModeParticleTracker | (resolved << link::kModeParticleMeasureShift) |
                                 link::kModeRecoveryDetection | link::kModeTuned);
    EXPECT_FALSE(hosted.started());
    EXPECT_FALSE(hosted.start(Pose{start.x, start.y, start.theta_deg, 2}));  // a depth the table does not have
    ASSERT_TRUE(hosted.start(start));
    frames = open_frames(scene.frames());
    GrayImage frame;
    const auto same = [](float x, float y) { return std::memcmp(&x, &y, sizeof x) == 0; };
    std::size_t near = 0;
    for (std::size_t n = 0; frames->next(frame); ++n) {
      SessionResult r;
      ASSERT_EQ(hosted.step(frame.view(), r), Status::kOk);
      near += std::hypot(r.pose.x - truth[n].x, r.pose.y - truth[n].y) < 3.0;
      EXPECT_TRUE(same(r.pose.x, want[n].step.pose.x) && same(r.pose.y, want[n].step.pose.y) &&
                  same(r.pose.theta_deg, want[n].step.pose.theta_deg) && r.pose.depth == want[n].step.pose.depth)
          << "frame " << n;
      EXPECT_EQ(r.state, want[n].step.state) << n;
      EXPECT_TRUE(same(r.score, want[n].step.score)) << n;
      EXPECT_EQ(r.confidence, want[n].confidence) << n;
    }
    EXPECT_GE(near, 8u) << "the runs compared should track the object (up to the occlusion at least)";
    // The filter is built for the first frame's size.
    const GrayImage other(frame.width + 1, frame.height);
    SessionResult r;
    EXPECT_EQ(hosted.step(other.view(), r), Status::kInvalidArgument);
  }
  SessionProfile p;
  p.tracker = TrackerKind::kParticle;
  p.particle_measure = ParticleMeasureKind::kIntensity;
  app::Rng rng(3);
  const std::vector<std::byte> edges_only = testing::build(testing::point_model(testing::random_points(rng, 40, 20, 2)), "-2:2:5", "-2:2:5");
  EXPECT_THROW(HostedSession(testing::open_table(edges_only), p), Error);  // no model images
}

// The particle HIL firmware's static twin and the hosted session with the
// profile's particle tracker, from the bits the twin reports in CAPS as the
// harness builds its reference: every frame's result bit for bit, with the
// intensity measure (a table with model images) and the edge measure (the
// same model without them), through an occlusion and a restart.
TEST(SessionProfile, FirmwareParticleTwinMatchesTheHostedSessionBitForBit) {
  const OccludedScene scene("gabarit-particle-twin", 16, 6, 4);
  const std::vector<std::byte> with_images = scene.table();
  host::ModelStack model = scene.model;
  model.images.clear(), model.image_width = model.image_height = 0;
  const std::vector<std::byte> without_images = testing::build(model, "-3:3:7", "-3:3:7", "-1:1:3");
  const Pose& start = scene.start;

  const std::uint32_t n = mcu::kFirmwareParticleProfile.particles;
  std::vector<Particle> cloud(particle_scratch_particles(n)), next(particle_scratch_particles(n));
  std::vector<std::uint32_t> order(particle_scratch_order(n));
  std::vector<std::uint64_t> bits(edge_map_words(512, 512));
  std::vector<RoiPoint> edge_features(edge_map_features(512));
  std::vector<ImageView> views(16);
  std::vector<IntensityCorrelationMeasure> measures(2);
  for (const std::vector<std::byte>* bytes : {&with_images, &without_images}) {
    const TableView table = testing::open_table(*bytes);
    testing::TrackerTestScratch proposer(table);
    mcu::FirmwareParticleSession twin(table, {{cloud, next, order}, bits, edge_features, proposer.view(), views, measures});
    HostedSession hosted(table, profile_from_mode_bits(twin.mode()));
    EXPECT_EQ(hosted.mode(), twin.mode());
    const std::uint32_t measure = (twin.mode() & link::kModeParticleMeasureMask) >> link::kModeParticleMeasureShift;
    EXPECT_EQ(measure, table.has_model_images() ? 3u : 1u);
    SessionResult r;
    GrayImage frame;
    EXPECT_EQ(twin.step(GrayImage(8, 8).view(), r), Status::kInvalidArgument);  // not started
    for (int run = 0; run < 2; ++run) {  // the second run: a restart, the filter built afresh
      ASSERT_TRUE(twin.start(start));
      ASSERT_TRUE(hosted.start(start));
      auto frames = open_frames(scene.frames());
      int k = 0;
      for (; frames->next(frame); ++k) {
        SessionResult a, b;
        ASSERT_EQ(twin.step(frame.view(), a), Status::kOk) << k;
        ASSERT_EQ(hosted.step(frame.view(), b), Status::kOk) << k;
        const auto same = [](float x, float y) { return std::memcmp(&x, &y, sizeof x) == 0; };
        EXPECT_TRUE(same(a.pose.x, b.pose.x) && same(a.pose.y, b.pose.y) && same(a.pose.theta_deg, b.pose.theta_deg) &&
                    a.pose.depth == b.pose.depth)
            << "measure " << measure << ", frame " << k;
        EXPECT_EQ(a.state, b.state) << k;
        EXPECT_EQ(a.confidence, b.confidence) << k;
        EXPECT_TRUE(same(a.score, b.score)) << k;
        EXPECT_EQ(a.step.features, b.step.features) << k;
        EXPECT_EQ(a.step.votes, b.step.votes) << k;
        EXPECT_EQ(a.work, b.work) << k;
      }
      EXPECT_EQ(k, 16);
    }
    EXPECT_EQ(twin.step(GrayImage(frame.width, frame.height + 1).view(), r), Status::kInvalidArgument);  // another size
    EXPECT_FALSE(twin.start(Pose{start.x, start.y, start.theta_deg, 2}));  // a depth the table does not have
  }
  // A cloud or a frame larger than the scratch holds.
  const TableView table = testing::open_table(without_images);
  testing::TrackerTestScratch proposer(table);
  mcu::FirmwareParticleSession short_cloud(table, {{std::span(cloud).first(10), next, order}, bits, edge_features, proposer.view(), views, measures});
  ASSERT_TRUE(short_cloud.start(start));
  SessionResult r;
  EXPECT_EQ(short_cloud.step(GrayImage(64, 64).view(), r), Status::kBufferTooSmall);
  mcu::FirmwareParticleSession small_map(table, {{cloud, next, order}, std::span(bits).first(8), edge_features, proposer.view(), views, measures});
  ASSERT_TRUE(small_map.start(start));
  EXPECT_EQ(small_map.step(GrayImage(64, 64).view(), r), Status::kBufferTooSmall);
}

}  // namespace
}  // namespace gabarit::app
