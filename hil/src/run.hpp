// The HIL harness's run (private to hil/src): the host's reference session,
// and the Run that replays a sequence into a DUT over the link. harness.cpp
// holds what a run does with frames (sending, faults, soak, judging) and the
// entry point run_hil; run_link.cpp what it does with messages (encoding,
// handling, the handshake, restarts).
#pragma once

#include "gabarit/hil/harness.hpp"

#include <optional>
#include <string>
#include <vector>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <filesystem>
#include <map>
#include <set>

#include "gabarit/app/error.hpp"
#include "gabarit/app/files.hpp"
#include "gabarit/app/image_io.hpp"
#include "gabarit/app/hosted_session.hpp"
#include "gabarit/app/scratch.hpp"
#include "gabarit/crc32.hpp"
#include "gabarit/app/evaluation.hpp"
#include "gabarit/app/rng.hpp"
#include "gabarit/link/dut_endpoint.hpp"
#include "gabarit/link/session_report.hpp"
#include "gabarit/tracking_session.hpp"

namespace gabarit::hil::detail {

using link::MessageType;

// The host's reference: the kernel on the same table, in the mode the DUT
// reports, fed the frames the DUT tracked in the order it tracked them.
class Reference {
 public:
  Reference(const TableView& table, std::uint32_t mode) : session_(table, app::profile_from_mode_bits(mode)) {}

  bool start(const Pose& initial) { return session_.start(initial); }

  // "" when the DUT's report is bit-identical to the reference's, else the first field that differs.
  // `ledger`: the reference's frame-cost ledger for the frame.
  std::string check(const app::GrayImage& frame, const link::PoseReport& dut, std::optional<FrameLedger>& ledger) {
    SessionResult r;
    if (const Status s = session_.step(frame.view(), r); s != Status::kOk)
      return std::string("the reference failed: ") + status_name(s);
    ledger = r.ledger;
    const link::PoseReport ref = link::session_report(r);
    const auto bits = [](float f) {
      std::uint32_t b;
      std::memcpy(&b, &f, 4);
      return b;
    };
    const auto differ = [](const char* field, double want, double got) {
      char text[160];
      std::snprintf(text, sizeof text, "%s: reference %.9g, DUT %.9g", field, want, got);
      return std::string(text);
    };
    if (bits(ref.pose.x) != bits(dut.pose.x)) return differ("x", ref.pose.x, dut.pose.x);
    if (bits(ref.pose.y) != bits(dut.pose.y)) return differ("y", ref.pose.y, dut.pose.y);
    if (bits(ref.pose.theta_deg) != bits(dut.pose.theta_deg)) return differ("theta_deg", ref.pose.theta_deg, dut.pose.theta_deg);
    if (ref.pose.depth != dut.pose.depth) return differ("depth", ref.pose.depth, dut.pose.depth);
    if (ref.state != dut.state) return differ("state", ref.state, dut.state);
    if (ref.confidence != dut.confidence) return differ("confidence", ref.confidence, dut.confidence);
    if (ref.best_votes != dut.best_votes) return differ("votes", ref.best_votes, dut.best_votes);
    if (bits(ref.score) != bits(dut.score)) return differ("score", ref.score, dut.score);
    if (ref.features != dut.features) return differ("features", ref.features, dut.features);
    if (ref.features_dropped != dut.features_dropped) return differ("features_dropped", ref.features_dropped, dut.features_dropped);
    if (ref.votes != dut.votes) return differ("counter increments", static_cast<double>(ref.votes), static_cast<double>(dut.votes));
    if (ref.flags != dut.flags) return differ("flags", ref.flags, dut.flags);
    return "";
  }

 private:
  app::HostedSession session_;
};

enum class RestartCause { kPlanned, kHung, kCrashed };

struct RunAborted {
  std::string why;
};

class Run {
 public:
  Run(const RunConfig& config, DutDriver& dut, RunResult& result)
      : config_(config), dut_(dut), result_(result), table_(config.table_path), rng_(config.seed ^ 0x5EEDull) {
    table_crc_ = crc32(table_.bytes());
  }

  void execute();
  void judge_faults();
  // The console's closing lines (RunConfig::console_closing), best effort:
  // the report says everything anyway.
  void send_closing_notes(const std::vector<std::string>& lines);

 private:
  Transport& wire() { return dut_.transport(); }
  std::vector<std::byte> encode(MessageType type, std::span<const std::byte> payload);
  void send(std::span<const std::byte> message);
  void handle(const std::vector<std::byte>& message);
  // Receives and handles until done() or the deadline; restarts a hung or
  // crashed DUT on the way. false at the deadline.
  template <class Done>
  bool pump(Clock::time_point deadline, Done done);
  void handshake(const Pose& initial, std::uint32_t first_frame);
  void restart(RestartCause cause, const std::string& why);
  void resolve(std::uint32_t frame, Fate fate, const std::string& reason, const link::PoseReport* pose = nullptr);
  void send_frame(std::uint32_t index, const app::GrayImage& image, const PlannedFault* fault);
  void ping();
  void inject(std::uint32_t index, const PlannedFault& fault);
  void restart_reported();
  void sample_soak(std::uint32_t frames_sent);
  void send_notes();  // the console lines queued since the last call
  double since_start_us() const { return std::chrono::duration<double, std::micro>(Clock::now() - t0_).count(); }

  const RunConfig& config_;
  DutDriver& dut_;
  RunResult& result_;
  app::TableFile table_;
  std::uint32_t table_crc_ = 0;
  app::Rng rng_;
  Clock::time_point t0_ = Clock::now();
  std::optional<Reference> reference_;
  std::vector<std::pair<std::uint32_t, std::string>> notes_;  // frame (kNoFrame: the run), console line
  bool opened_ = false;  // the console's opening line is queued (the handshake succeeded)
  link::Caps caps_;
  bool awaiting_caps_ = false;
  std::uint32_t run_id_ = 0;
  link::Sequencer sequence_;  // the peer forgotten at a restart: a restarted DUT numbers from 0
  std::map<std::uint32_t, app::GrayImage> images_;  // sent, not yet resolved
  std::set<std::uint32_t> outstanding_;
  std::vector<std::vector<std::byte>> held_;  // a reordered frame's messages
  std::uint32_t held_frame_ = link::kNoFrame;
  std::uint32_t next_frame_ = 0;              // the next frame to send
  std::int64_t newest_sent_ = -1;
  std::int64_t last_pose_frame_ = -1;
  Pose last_pose_;
  bool ping_outstanding_ = false;
  std::uint32_t ping_token_ = 0;
  std::int64_t ping_covers_ = -1;
  Clock::time_point ping_sent_at_, last_activity_ = Clock::now();
  bool stats_received_ = false, bye_received_ = false;
  double codec_seconds_ = 0;
  std::uint32_t window_ = 1;
  std::size_t max_payload_ = link::kMinPayload;
  bool dut_restarted_ = false;  // an EVENT restart/boot: the rig restarted the DUT behind it
  std::uint32_t soak_from_ = 0;  // the first frame of the soak window being measured
};

template <class Done>
bool Run::pump(Clock::time_point deadline, Done done) {
  while (!done()) {
    const auto now = Clock::now();
    if (now >= deadline) return false;
    try {
      if (ping_outstanding_ && !awaiting_caps_ && now - ping_sent_at_ >= dut_.hang_timeout()) {
        restart(RestartCause::kHung, "the DUT hung: no answer to a PING in " + std::to_string(dut_.hang_timeout().count()) + " ms");
        continue;
      }
      // Ask when the DUT has gone quiet, or when a newer frame than one still
      // unanswered has come back (the older one is likely lost).
      const bool overtaken = !outstanding_.empty() && static_cast<std::int64_t>(*outstanding_.begin()) < last_pose_frame_;
      if (!ping_outstanding_ && !awaiting_caps_ && !outstanding_.empty() &&
          (overtaken || now - last_activity_ >= dut_.stall_interval()))
        ping();
      auto m = wire().receive(std::min(deadline, now + dut_.stall_interval()));
      if (m) {
        last_activity_ = Clock::now();
        handle(*m);
      }
      if (dut_restarted_ && !awaiting_caps_) restart_reported();
    } catch (const app::Error& e) {
      if (awaiting_caps_) throw RunAborted{std::string("the DUT did not start: ") + e.what()};
      restart(RestartCause::kCrashed, std::string("the DUT crashed or closed the link: ") + e.what());
    }
  }
  return true;
}


}  // namespace gabarit::hil::detail
