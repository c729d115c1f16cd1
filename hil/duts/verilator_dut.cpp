// gabarit-hil-verilator: the hardware voter as a HIL device under test. The
// Verilated gbt_voter votes; around it, the thesis's loop runs as the CPU
// beside an FPGA voter would run it: the kernel places the ROI and extracts
// the features (prepare_frame), the voter counts, the counters are read
// back, and the kernel ranks them and updates the pose (finish_frame). The
// voter's best cell and runner-up are checked against the kernel's ranking
// of the voter's own counters every frame (EVENT hardware-mismatch if not).
//
// It speaks the HIL link COBS-framed on stdin/stdout (the harness's socket
// pair); diagnostics go to stderr. Its clock is the voter's: timestamps
// count simulated clock cycles, reported at --clock-hz.
#include <poll.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "Vvoter_hil.h"
#include "gabarit/app/error.hpp"
#include "gabarit/app/files.hpp"
#include "gabarit/app/scratch.hpp"
#include "gabarit/app/session_profile.hpp"
#include "gabarit/crc32.hpp"
#include "gabarit/app/hdl_export.hpp"
#include "gabarit/app/rng.hpp"
#include "gabarit/link/cobs.hpp"
#include "gabarit/link/dut_endpoint.hpp"
#include "gabarit/motion_filter.hpp"
#include "gabarit/tracker.hpp"
#include "voter_harness.hpp"

namespace {

using namespace gabarit;

// The capacities and lane count gabarit-hil-verilator is verilated with (hil/CMakeLists.txt).
constexpr std::uint32_t kLanes = GABARIT_HIL_LANES;
constexpr std::uint32_t kCells = GABARIT_HIL_CELLS;
constexpr std::uint32_t kPixels = GABARIT_HIL_PIXELS;
constexpr std::uint32_t kRefsPerLane = GABARIT_HIL_REFS_PER_LANE;

class StdoutOutput {
 public:
  void send(std::span<const std::byte> message) noexcept {
    std::byte wire[link::cobs_encoded_capacity(link::message_bytes(link::kMinPayload))];
    std::size_t n = 0;
    if (link::cobs_encode(message, wire, n) != Status::kOk) return;
    for (std::size_t at = 0; at < n;) {
      const ssize_t w = ::write(1, wire + at, n - at);
      if (w > 0) {
        at += static_cast<std::size_t>(w);
      } else if (w < 0 && errno != EINTR && errno != EAGAIN) {
        std::_Exit(0);  // the harness is gone
      }
    }
  }
};

class VoterDut {
 public:
  VoterDut(const TableView& table, bool fits)
      : table_(table), fits_(fits), buffers_(table, app::VoterChoice::kCsr), voter_({}, kCells, kRefsPerLane) {
    if (fits_) voter_.load(app::hdl_layout(table, kLanes), kLanes);
    voter_.model().cell_count_i = table.cell_count();
    voter_.model().roi_width_i = table.roi_width() * table.orientation_channels();  // slots per row (app::hdl_features)
    voter_.model().roi_height_i = table.roi_height();
  }

  link::Refusal start(const link::Hello& hello) noexcept {
    if (!fits_) return link::Refusal::kNoTable;
    if (!pose_in_range(hello.initial) || hello.initial.depth >= table_.depth_count()) return link::Refusal::kBadPose;
    pose_ = hello.initial;
    grader_.reset(MotionFilterParams{}, hello.initial);  // grades confidence as the plain session does
    return link::Refusal::kNone;
  }
  std::uint64_t now() noexcept { return voter_.cycle(); }

  bool track_next(link::DutEndpoint& endpoint) {
    link::ReadyFrame frame;
    if (!endpoint.next_frame(frame)) return false;
    const ImageView image{frame.pixels.data(), frame.width, frame.height, frame.width};
    TrackerScratch scratch = buffers_.scratch();
    PreparedFrame prepared;
    if (const Status s = prepare_frame(table_, detector_of(table_), image, pose_, scratch, prepared); s != Status::kOk) {
      endpoint.report_failure(link::EventKind::kError, link::EventReason::kTracking, static_cast<std::uint32_t>(s), now());
      return true;
    }
    const std::vector<RoiPoint> features =
        app::hdl_features(table_, std::span<const RoiPoint>(scratch.features).first(prepared.features));
    hdl::Outcome hw;
    try {
      hw = voter_.frame(features, table_.cell_count(), 0.0, rng_);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "frame %u: the voter stalled: %s\n", frame.frame_id, e.what());
      endpoint.report_failure(link::EventKind::kError, link::EventReason::kHardware, 0, now());
      return true;
    }
    std::copy(hw.counters.begin(), hw.counters.end(), scratch.counters.begin());
    const VoteTally tally{table_.channel_bits() != 0 ? hw.features / 2 : hw.features, hw.votes};  // two slots per feature with channels
    StepResult step;
    if (const Status s = finish_frame(table_, pose_, prepared, scratch.counters, tally, step); s != Status::kOk) {
      endpoint.report_failure(link::EventKind::kError, link::EventReason::kTracking, static_cast<std::uint32_t>(s), now());
      return true;
    }
    // The voter's own ranking against the kernel's ranking of its counters.
    const bool runner_agrees = step.runner_up.cell == hw.runner_cell && (hw.runner_cell == kNoCell || step.runner_up.votes == hw.runner_votes);
    if (hw.overflow || hw.roi_error || step.best.cell != hw.best_cell || step.best.votes != hw.best_votes || !runner_agrees) {
      std::fprintf(stderr, "frame %u: the voter's result disagrees with the kernel's ranking of its counters\n", frame.frame_id);
      endpoint.report_failure(link::EventKind::kError, link::EventReason::kHardware, hw.best_cell, now());
      return true;
    }
    // The plain loop: a lost frame keeps the previous pose (TrackingSession with kPlainSession).
    if (step.state != TrackState::kLost) pose_ = step.pose;
    link::PoseReport report;
    report.pose = pose_;
    report.state = static_cast<std::uint8_t>(step.state);
    report.confidence = static_cast<std::uint8_t>(grader_.grade(step.score, normalised_score(step.runner_up)));
    report.best_votes = step.best.votes;
    report.score = step.score;
    report.features = step.features;
    report.features_dropped = step.features_dropped;
    report.votes = step.votes;
    report.cycles = hw.cycles;
    endpoint.report_pose(report, now());
    return true;
  }

 private:
  const TableView& table_;
  bool fits_;
  app::TrackerBuffers buffers_;
  hdl::Harness<Vvoter_hil> voter_;
  app::Rng rng_{1};
  Pose pose_;
  MotionFilter grader_;
};

int run(int argc, char** argv) {
  std::string table_path;
  std::uint32_t clock_hz = 48000000;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--table" && i + 1 < argc) {
      table_path = argv[++i];
    } else if (a == "--clock-hz" && i + 1 < argc) {
      clock_hz = static_cast<std::uint32_t>(std::strtoul(argv[++i], nullptr, 10));
    } else {
      std::fprintf(stderr,
                   "usage: gabarit-hil-verilator --table T [--clock-hz N]\n"
                   "The hardware voter (Verilated, %u lanes, %u cells, %u ROI pixels, %u references per lane) as a HIL DUT\n"
                   "on stdin/stdout; run by `gabarit hil run --dut verilator`.\n",
                   kLanes, kCells, kPixels, kRefsPerLane);
      return 2;
    }
  }
  if (table_path.empty() || clock_hz == 0) {
    std::fprintf(stderr, "gabarit-hil-verilator: want --table T (and a non-zero --clock-hz)\n");
    return 2;
  }
  const app::TableFile table(table_path);
  const TableView& t = table.view();
  bool fits = t.cell_count() <= kCells && t.roi_pixels() <= kPixels;
  if (fits) {
    const app::HdlLayout layout = app::hdl_layout(t, kLanes);
    fits = layout.max_lane_refs() <= kRefsPerLane;
  }
  if (!fits)
    std::fprintf(stderr, "gabarit-hil-verilator: %s (%u cells, %u ROI pixels) exceeds the voter's build (%u cells, %u pixels, %u refs per lane)\n",
                 table_path.c_str(), t.cell_count(), t.roi_pixels(), kCells, kPixels, kRefsPerLane);
  VoterDut app(t, fits);
  char board[32];
  std::snprintf(board, sizeof board, "gbt_voter %u lanes (Verilator)", kLanes);
  link::DeviceDescription device;
  device.table_crc = crc32(table.bytes());
  device.table_bytes = static_cast<std::uint32_t>(table.bytes().size());
  device.clock_hz = clock_hz;
  device.max_frame_bytes = 1u << 20;
  device.mode = app::mode_bits(app::plain_profile(), false, false);  // the voter runs the thesis's loop
  device.kind = "verilator";
  device.board = board;
  const link::Caps caps = link::make_caps(device);
  std::vector<std::uint8_t> memory(link::dut_frame_memory_bytes(caps.frame_slots, caps.max_frame_bytes));
  StdoutOutput out;
  link::DutEndpoint endpoint(caps, memory);
  std::vector<std::byte> buffer(link::message_bytes(link::kMaxPayload));
  link::CobsStreamDecoder decoder(buffer);
  std::vector<std::byte> chunk(65536);
  while (!endpoint.bye_received()) {
    const ssize_t r = ::read(0, chunk.data(), chunk.size());
    if (r == 0) break;
    if (r < 0) {
      if (errno == EINTR) continue;
      break;
    }
    for (ssize_t i = 0; i < r; ++i) {
      switch (decoder.push(chunk[static_cast<std::size_t>(i)])) {
        case link::CobsStreamDecoder::Event::kMessage: link::deliver(endpoint, decoder.message(), app, out); break;
        case link::CobsStreamDecoder::Event::kDiscarded: endpoint.on_framing_error(); break;
        case link::CobsStreamDecoder::Event::kNone: break;
      }
      // Track as soon as a frame is whole: the next bytes wait in the socket.
      while (app.track_next(endpoint)) link::flush(endpoint, out);
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gabarit-hil-verilator: %s\n", e.what());
    return 1;
  }
}
