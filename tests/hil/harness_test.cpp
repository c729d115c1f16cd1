// The HIL harness (hil/): fault plans, transports, and whole runs against the
// in-process DUT, with every fault kind, a DUT that hangs and one that never starts.
#include <gtest/gtest.h>

#include <sys/socket.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "gabarit/app/error.hpp"
#include "gabarit/app/files.hpp"
#include "gabarit/host/scenes/synth.hpp"
#include "gabarit/host/tables/table_builder.hpp"
#include "gabarit/hil/board_map.hpp"
#include "gabarit/hil/dut.hpp"
#include "gabarit/hil/faults.hpp"
#include "gabarit/hil/harness.hpp"
#include "gabarit/hil/report.hpp"
#include "gabarit/link/cobs.hpp"
#include "test_tables.hpp"

namespace gabarit::hil {
namespace {

namespace fs = std::filesystem;

std::string write_temp(const std::string& name, const std::string& text) {
  const fs::path p = fs::temp_directory_path() / ("gabarit_hil_test_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream(p) << text;
  return p.string();
}

TEST(FaultPlan, ReadsAFileAndRefusesWhatCannotBeInjected) {
  const FaultPlan plan = read_fault_file(write_temp("ok", "# a plan\n5 drop\n2 reorder   # swapped with 3\n9 restart\n"), 10);
  ASSERT_EQ(plan.faults.size(), 3u);
  EXPECT_EQ(plan.faults[0].frame, 2u);
  EXPECT_EQ(plan.faults[0].kind, FaultKind::kReorder);
  EXPECT_NE(plan.at(5), nullptr);
  EXPECT_EQ(plan.at(4), nullptr);
  EXPECT_EQ(read_fault_file(write_temp("rt", fault_file_text(plan)), 10).faults.size(), 3u);
  for (const char* bad : {"5 melt\n", "x drop\n", "-1 drop\n", "5\n", "5 drop extra\n", "12 drop\n", "3 drop\n3 corrupt\n",
                          "9 reorder\n", "3 reorder\n4 drop\n"}) {
    EXPECT_THROW(read_fault_file(write_temp("bad", bad), 10), app::Error) << bad;
  }
  EXPECT_THROW(read_fault_file("/nonexistent/plan", 10), app::Error);
}

TEST(FaultPlan, RandomPlansAreSeededAndRespectTheRules) {
  const FaultPlan a = random_fault_plan(0.2, 1000, 7), b = random_fault_plan(0.2, 1000, 7), c = random_fault_plan(0.2, 1000, 8);
  EXPECT_EQ(fault_file_text(a), fault_file_text(b));
  EXPECT_NE(fault_file_text(a), fault_file_text(c));
  EXPECT_GT(a.faults.size(), 150u);
  EXPECT_LT(a.faults.size(), 250u);
  std::array<int, 6> kinds{};
  for (const PlannedFault& f : a.faults) ++kinds[static_cast<std::size_t>(f.kind)];
  for (int k : kinds) EXPECT_GT(k, 10);
  EXPECT_TRUE(random_fault_plan(0.0, 100, 1).faults.empty());
  EXPECT_EQ(random_fault_plan(1.0, 100, 1).faults.size() + 0, random_fault_plan(1.0, 100, 1).faults.size());
  EXPECT_THROW(parse_fault_plan("random:1.5", 10, 1), app::Error);
  EXPECT_THROW(parse_fault_plan("random:", 10, 1), app::Error);
}

TEST(Transport, AStreamResynchronisesAfterGarbageAndItsTimeoutFires) {
  int sv[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_STREAM, 0, sv), 0);
  StreamTransport a(sv[0], sv[0], "a"), b(sv[1], sv[1], "b");
  const auto t0 = Clock::now();
  EXPECT_FALSE(b.receive(t0 + std::chrono::milliseconds(50)).has_value());
  const auto waited = Clock::now() - t0;
  EXPECT_GE(waited, std::chrono::milliseconds(45));
  EXPECT_LT(waited, std::chrono::seconds(2));
  const std::vector<std::byte> m1(300, std::byte{0}), m2 = {std::byte{1}, std::byte{2}, std::byte{0}, std::byte{3}};
  const std::byte junk[] = {std::byte{0x55}, std::byte{0x20}, std::byte{0}};  // a broken run, then a delimiter
  ASSERT_EQ(::write(sv[0], junk, sizeof junk), 3);
  a.send(m1, Clock::now() + std::chrono::seconds(1));
  a.flip_bits_on_next_send({5});  // this one arrives broken
  a.send(m2, Clock::now() + std::chrono::seconds(1));
  a.send(m2, Clock::now() + std::chrono::seconds(1));
  const auto r1 = b.receive(Clock::now() + std::chrono::seconds(1));
  ASSERT_TRUE(r1.has_value());
  EXPECT_EQ(*r1, m1);
  std::vector<std::vector<std::byte>> rest;
  while (auto r = b.receive(Clock::now() + std::chrono::milliseconds(100))) rest.push_back(*r);
  // The flipped copy breaks its run (discarded, counted); the next is whole.
  ASSERT_EQ(rest.size(), 1u);
  EXPECT_EQ(rest[0], m2);
  EXPECT_EQ(b.framing_errors(), 2u);
  EXPECT_GT(a.bytes_sent(), m1.size() + 2 * m2.size());
}

TEST(Transport, UdpCarriesOneMessagePerDatagramAndLoopbackCloseWakesTheReader) {
  UdpTransport a("127.0.0.1", 0), b("127.0.0.1", a.local_port());
  a.set_peer(b.local_port());
  const std::vector<std::byte> m(1000, std::byte{9});
  b.send(m, Clock::now() + std::chrono::seconds(1));
  const auto r = a.receive(Clock::now() + std::chrono::seconds(1));
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(*r, m);
  EXPECT_FALSE(a.receive(Clock::now() + std::chrono::milliseconds(20)).has_value());
  Loopback loop;
  auto host = loop.host_end();
  auto device = loop.device_end();
  host->send(m, Clock::now());
  EXPECT_EQ(*device->receive(Clock::now()), m);
  loop.close();
  EXPECT_THROW(device->receive(Clock::now() + std::chrono::seconds(5)), app::Error);
}

// A sequence and its table in a temporary folder, made once.
struct Sequence {
  Sequence() {
    dir = (fs::temp_directory_path() / ("gabarit_hil_seq_" + std::to_string(::getpid()))).string();
    fs::create_directories(dir);
    host::SynthOptions o;
    o.shape = host::random_closed_curve(80, 5);
    o.frames = 120;
    o.max_step = 3;
    o.noise = 0.02;
    o.width = o.height = 96;
    o.seed = 5;
    host::write_synthetic_sequence(o, dir);
    table = dir + "/table.gbt";
    const std::vector<std::byte> bytes = gabarit::testing::build(gabarit::testing::point_model(o.shape), "-4:4:9", "-4:4:9");
    app::write_file(table, bytes);
  }
  ~Sequence() { fs::remove_all(dir); }
  std::string dir, table;
};

const Sequence& sequence() {
  static const Sequence s;
  return s;
}

RunConfig config_for(const Sequence& s) {
  RunConfig c;
  c.sequence_dir = s.dir;
  c.table_path = s.table;
  c.max_frames = 120;
  return c;
}

const FrameRecord* first_with(const RunResult& r, Fate fate) {
  for (const FrameRecord& f : r.frames)
    if (f.fate == fate) return &f;
  return nullptr;
}

TEST(FaultPlan, CyclePlansTakeEachKindInTurnAndRigKindsHaveNames) {
  const FaultPlan p = parse_fault_plan("cycle:6:drop,board-kill,usb-unplug", 2000, 1);
  ASSERT_EQ(p.faults.size(), 333u);  // frames 6, 12, ..., 1998
  EXPECT_EQ(p.faults[0].frame, 6u);
  EXPECT_EQ(p.faults[1].kind, FaultKind::kBoardKill);
  EXPECT_EQ(p.faults[2].kind, FaultKind::kUsbUnplug);
  EXPECT_EQ(p.faults[3].kind, FaultKind::kDrop);
  EXPECT_EQ(parse_fault_plan("cycle:10", 100, 1).faults.size(), 9u);  // the harness's own kinds by default
  for (const FaultKind k : kRigFaultKinds) {
    EXPECT_TRUE(is_rig_fault(k));
    EXPECT_EQ(parse_fault_kind(fault_name(k), "test"), k);
  }
  EXPECT_FALSE(is_rig_fault(FaultKind::kRestart));
  EXPECT_EQ(rig_fault_number(FaultKind::kCameraError), 1u);
  EXPECT_EQ(rig_fault_number(FaultKind::kUsbCorrupt), 10u);
  EXPECT_STREQ(fault_name(FaultKind::kSequenceWrap), "sequence-wrap");
  for (const char* bad : {"cycle:1:drop", "cycle:x", "cycle:5:melt", "cycle:5:"}) EXPECT_THROW(parse_fault_plan(bad, 100, 1), app::Error) << bad;
  // A plan file takes the rig's kinds too.
  EXPECT_EQ(read_fault_file(write_temp("rig", "3 board-kill\n5 camera-error\n"), 10).faults[0].kind, FaultKind::kBoardKill);
}

TEST(BoardMap, ReadsTheProjectsBoardsAndRefusesMistakesByLine) {
  for (const char* name : {"raspberry-pi-4", "virtual-board-tcp"}) {
    const BoardMap m = load_board_map(name, GABARIT_BOARDS_DIR);
    EXPECT_EQ(m.name, name);
    EXPECT_FALSE(m.relay.empty());
    EXPECT_GE(m.lock_line, 0);
  }
  const BoardMap m = parse_board_map("name: b\nrelay: /dev/ttyUSB1   # the UART\nbaud: 921600\ngpio:\n  chip: gpiochip4\n  strobe: 5\n", "t");
  EXPECT_EQ(m.relay, "/dev/ttyUSB1");
  EXPECT_EQ(m.baud, 921600u);
  EXPECT_EQ(m.gpio_chip, "gpiochip4");
  EXPECT_EQ(m.strobe_line, 5);
  EXPECT_EQ(m.lock_line, -1);
  const char* bad[] = {"name: b\n",                               // no relay
                       "relay: x\n",                              // no name
                       "name: b\nrelay: x\nspeed: 3\n",          // unknown key
                       "name: b\nrelay: x\nbaud: fast\n",        // not a number
                       "name: b\nrelay: x\n  lock: 3\n",         // indented outside a section
                       "name: b\nrelay: x\ncamera\n",            // no colon
                       "name: b\nrelay: x\nframe_path: hdmi\n",  // not a frame path we have
                       "name: b\nrelay: x\nusb: 12345:1\n"};     // not VID:PID
  for (const char* text : bad) EXPECT_THROW(parse_board_map(text, "t"), app::Error) << text;
  try {
    parse_board_map("name: b\nrelay: x\nspeed: 3\n", "b.yaml");
    FAIL();
  } catch (const app::Error& e) {
    EXPECT_NE(std::string(e.what()).find("b.yaml:3"), std::string::npos) << e.what();
  }
  EXPECT_THROW(load_board_map("no-such-board", GABARIT_BOARDS_DIR), app::Error);
}

TEST(HilRun, ADutWithoutARigAnswersItsFaultsUnsupportedAndTheRunGoesOn) {
  InprocessOptions o;
  o.table_path = sequence().table;
  auto dut = make_inprocess_dut(o);
  RunConfig config = config_for(sequence());
  config.faults = parse_fault_plan("cycle:40:board-kill,camera-error", 120, 1);
  const RunResult r = run_hil(config, *dut);
  EXPECT_EQ(r.error, "");
  ASSERT_EQ(r.faults.size(), 2u);
  for (const InjectedFault& f : r.faults) {
    EXPECT_TRUE(f.answered);
    EXPECT_FALSE(f.detected);
    EXPECT_NE(f.evidence.find("unsupported"), std::string::npos) << f.evidence;
  }
  for (const FrameRecord& f : r.frames) ASSERT_EQ(f.reference, 1) << f.frame;
}

TEST(HilRun, TheInProcessDutMatchesTheReferenceOnEveryFrame) {
  for (bool udp : {false, true}) {
    InprocessOptions o;
    o.table_path = sequence().table;
    o.udp = udp;
    auto dut = make_inprocess_dut(o);
    const RunResult r = run_hil(config_for(sequence()), *dut);
    EXPECT_EQ(r.error, "");
    EXPECT_EQ(r.unaccounted, 0u);
    ASSERT_EQ(r.frames.size(), 120u);
    for (const FrameRecord& f : r.frames) {
      ASSERT_EQ(f.fate, Fate::kPose) << "frame " << f.frame << (udp ? " (udp)" : "");
      ASSERT_EQ(f.reference, 1) << "frame " << f.frame << ": " << f.mismatch;
      ASSERT_TRUE(f.frame_crc_ok);
      // The reference's work ledger, reported for the DUT: every frame votes.
      ASSERT_TRUE(f.reference_ledger.has_value());
      EXPECT_GT(f.reference_ledger->work[static_cast<int>(FramePhase::kVote)], 0u) << "frame " << f.frame;
      EXPECT_GT(f.reference_ledger->work[static_cast<int>(FramePhase::kFeatures)], 0u) << "frame " << f.frame;
    }
    EXPECT_STREQ(r.caps.kind, "inprocess");
    ASSERT_TRUE(r.dut_stats.has_value());
    EXPECT_EQ(r.dut_stats->frames_tracked, 120u);
    for (const Check& c : run_checks(r)) EXPECT_TRUE(c.passed) << c.name << ": " << c.message;
  }
}

// The profile's particle tracker on the device: CAPS says so (with the
// measure the table resolves), the reference runs it too, every frame is
// bit-identical, through a restart and a dropped frame.
TEST(HilRun, TheInProcessDutRunsTheProfilesParticleTracker) {
  InprocessOptions o;
  o.table_path = sequence().table;
  o.profile.tracker = app::TrackerKind::kParticle;
  auto dut = make_inprocess_dut(o);
  RunConfig c = config_for(sequence());
  c.max_frames = 40;
  c.faults = read_fault_file(write_temp("particle", "10 drop\n25 restart\n"), c.max_frames);
  const RunResult r = run_hil(c, *dut);
  EXPECT_EQ(r.error, "");
  EXPECT_NE(r.caps.mode & link::kModeParticleTracker, 0u);
  EXPECT_NE(r.caps.mode & link::kModeParticleMeasureMask, 0u);  // resolved: never auto
  EXPECT_EQ(r.unaccounted, 0u);
  std::size_t posed = 0;
  for (const FrameRecord& f : r.frames) {
    // Only the faults' frames go without a pose: the dropped one and those in flight at the restart.
    if (f.fate != Fate::kPose) {
      EXPECT_TRUE(f.fate == Fate::kDroppedByLink || f.fate == Fate::kLostInRestart) << f.frame << ": " << fate_name(f.fate);
      continue;
    }
    ++posed;
    ASSERT_EQ(f.reference, 1) << "frame " << f.frame << ": " << f.mismatch;
  }
  EXPECT_GE(posed, 40u - 1u - o.frame_slots);
  for (const Check& check : run_checks(r)) EXPECT_TRUE(check.passed) << check.name << ": " << check.message;
}

TEST(HilRun, EveryFaultKindIsDetectedAndRecoveredFrom) {
  const std::string plan = write_temp("every", "10 drop\n20 duplicate\n30 reorder\n40 corrupt\n50 bitflip\n60 restart\n70 drop\n71 corrupt\n");
  for (std::uint32_t slots : {1u, 4u}) {
    InprocessOptions o;
    o.table_path = sequence().table;
    o.frame_slots = slots;
    auto dut = make_inprocess_dut(o);
    RunConfig c = config_for(sequence());
    c.faults = read_fault_file(plan, c.max_frames);
    std::vector<std::uint32_t> streamed;
    c.on_resolved = [&](const FrameRecord& f) { streamed.push_back(f.frame); };
    const RunResult r = run_hil(c, *dut);
    EXPECT_EQ(r.error, "");
    EXPECT_EQ(r.unaccounted, 0u);
    EXPECT_EQ(r.out_of_order, 0u);
    EXPECT_EQ(r.double_answers, 0u);
    EXPECT_EQ(streamed.size(), 120u) << "every frame's fate is streamed once";
    ASSERT_EQ(r.faults.size(), 8u);
    for (const InjectedFault& f : r.faults)
      EXPECT_TRUE(f.detected && f.recovered) << fault_name(f.kind) << " at " << f.frame << ": " << f.evidence << " (" << slots << " slots)";
    EXPECT_EQ(r.frames[10].fate, Fate::kDroppedByLink);
    EXPECT_EQ(r.frames[30].fate, Fate::kSkippedByDut);
    EXPECT_EQ(r.frames[31].fate, Fate::kPose);
    EXPECT_EQ(r.frames[20].fate, Fate::kPose);
    EXPECT_GE(r.frames[20].repeats, 1u);
    EXPECT_EQ(r.restarts_planned, 1u);
    EXPECT_EQ(r.frames[60].run, 1u);
    for (const FrameRecord& f : r.frames) {
      if (f.pose) {
        EXPECT_EQ(f.reference, 1) << "frame " << f.frame << ": " << f.mismatch;
      }
    }
    ASSERT_TRUE(r.dut_stats.has_value());
    EXPECT_GE(r.dut_stats->bad_crc + r.dut_stats->bad_message + r.dut_stats->framing_errors, 1u);
  }
}

// A DUT that stops answering after `answers` messages until restarted.
class HangingDut final : public DutDriver {
 public:
  HangingDut(std::string table, std::uint32_t answers) : answers_(answers) {
    InprocessOptions o;
    o.table_path = std::move(table);
    inner_ = make_inprocess_dut(o);
  }
  std::string kind() const override { return "hanging"; }
  void start() override {
    inner_->start();
    ++starts;
    mute_ = std::make_unique<Mute>(inner_->transport(), starts == 1 ? answers_ : 1u << 30);
  }
  void stop() noexcept override {
    mute_.reset();
    inner_->stop();
  }
  Transport& transport() override { return *mute_; }
  std::chrono::milliseconds default_hang_timeout() const override { return std::chrono::milliseconds(300); }
  int starts = 0;

 private:
  struct Mute final : Transport {
    Mute(Transport& t, std::uint32_t n) : inner(t), left(n) {}
    void send(std::span<const std::byte> m, Clock::time_point d) override { inner.send(m, d); }
    std::optional<std::vector<std::byte>> receive(Clock::time_point d) override {
      auto m = inner.receive(d);
      if (m && left == 0) return std::nullopt;  // swallowed: the DUT looks hung
      if (m) --left;
      return m;
    }
    Transport& inner;
    std::uint32_t left;
  };
  std::uint32_t answers_;
  std::unique_ptr<DutDriver> inner_;
  std::unique_ptr<Mute> mute_;
};

TEST(HilRun, AHungDutIsRestartedAndTheRunCompletes) {
  HangingDut dut(sequence().table, 40);
  const auto t0 = Clock::now();
  const RunResult r = run_hil(config_for(sequence()), dut);
  EXPECT_LT(Clock::now() - t0, std::chrono::seconds(30));
  EXPECT_EQ(r.error, "");
  EXPECT_EQ(r.restarts_hung, 1u);
  EXPECT_EQ(dut.starts, 2);
  EXPECT_EQ(r.unaccounted, 0u);
  const FrameRecord* lost = first_with(r, Fate::kLostInRestart);
  ASSERT_NE(lost, nullptr);
  EXPECT_NE(lost->reason.find("hung"), std::string::npos);
  EXPECT_EQ(r.frames.back().fate, Fate::kPose);
  EXPECT_EQ(r.frames.back().reference, 1);
}

TEST(HilRun, ADutThatNeverStartsEndsTheRunWithAReason) {
  auto dut = make_process_dut("none", {"/bin/sh", "-c", "exec sleep 30"}, "", std::chrono::milliseconds(300));
  const auto t0 = Clock::now();
  const RunResult r = run_hil(config_for(sequence()), *dut);
  EXPECT_LT(Clock::now() - t0, std::chrono::seconds(10));
  EXPECT_NE(r.error.find("did not answer HELLO"), std::string::npos) << r.error;
  bool handshake_failed = false;
  for (const Check& c : run_checks(r)) handshake_failed |= c.name == "handshake" && !c.passed;
  EXPECT_TRUE(handshake_failed);
  auto gone = make_process_dut("none", {"/nonexistent/dut"}, "", std::chrono::milliseconds(300));
  EXPECT_NE(run_hil(config_for(sequence()), *gone).error, "");
}

TEST(HilReport, WritesEveryFileWithATestcasePerCheckAndFault) {
  InprocessOptions o;
  o.table_path = sequence().table;
  auto dut = make_inprocess_dut(o);
  RunConfig c = config_for(sequence());
  c.faults = read_fault_file(write_temp("two", "5 drop\n9 bitflip\n"), c.max_frames);
  const RunResult r = run_hil(c, *dut);
  const std::string dir = (fs::temp_directory_path() / ("gabarit_hil_report_" + std::to_string(::getpid()))).string();
  write_report(dir, c, r, app::read_pose_csv(sequence().dir + "/gt.csv"));
  for (const char* f : {"frames.csv", "poses.csv", "summary.json", "junit.xml", "faults.csv", "report.md", "error.svg",
                        "trajectory.svg", "latency.svg", "faults.svg"})
    EXPECT_TRUE(fs::exists(fs::path(dir) / f)) << f;
  std::ifstream junit(fs::path(dir) / "junit.xml");
  const std::string xml((std::istreambuf_iterator<char>(junit)), std::istreambuf_iterator<char>());
  std::size_t testcases = 0;
  for (std::size_t at = xml.find("<testcase"); at != std::string::npos; at = xml.find("<testcase", at + 1)) ++testcases;
  EXPECT_EQ(testcases, run_checks(r).size());
  EXPECT_NE(xml.find("fault.0.drop.frame5"), std::string::npos);
  EXPECT_NE(xml.find("fault.1.bitflip.frame9"), std::string::npos);
  EXPECT_NE(xml.find("latency_us.p99"), std::string::npos);
  // poses.csv is gabarit track's format: gabarit eval reads it.
  const auto poses = app::read_pose_csv((fs::path(dir) / "poses.csv").string());
  EXPECT_EQ(poses.size(), 118u);
  EXPECT_EQ(read_fault_file((fs::path(dir) / "faults.csv").string(), 120).faults.size(), 2u);
  // The frame-cost ledger: the reference's work per phase, in the summary and per frame.
  std::ifstream summary(fs::path(dir) / "summary.json");
  const std::string json((std::istreambuf_iterator<char>(summary)), std::istreambuf_iterator<char>());
  EXPECT_NE(json.find("\"work_per_frame\": {\"frames\": 118, \"features\": "), std::string::npos) << json;
  std::ifstream frames(fs::path(dir) / "frames.csv");
  std::string header;
  std::getline(frames, header);
  EXPECT_NE(header.find(",features_work,vote_work,verify_work,depth_work,recovery_work,survey_work,other_work"), std::string::npos) << header;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace gabarit::hil
