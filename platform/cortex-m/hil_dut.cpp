// The HIL firmware: a device under test for `gabarit hil run --dut cortex-m`.
// It validates the table in its flash slot once (which the harness fills
// before reset), then serves the HIL link on UART0 (COBS-framed,
// docs/hil-protocol.md), and prints on UART1, its console, a line at boot and
// the host's NOTEs (a board farm reads its verdicts there: docs/hil-farm.md).
// Frames in, the firmware's session
// (firmware_session.hpp: gabarit track's defaults less the search's shared
// features, the static twin of app::HostedSession), poses out. Timestamps count SysTick at the core
// clock; under QEMU -icount that is guest time.
// Every buffer is static, sized by the kernel's constexpr formulas; a table
// too big for them, or none, is refused in CAPS (no-valid-table).
// Built with GABARIT_HIL_PARTICLE (gabarit-firmware-hil-particle), it runs
// the particle tracker instead (firmware_particle_session.hpp: gabarit track
// --tracker particle's defaults, 1,000 particles) on frames of up to
// kMaxParticleFrameSide pixels a side.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

#include "board.hpp"
#include "gabarit/crc32.hpp"
#include "gabarit/link/cobs.hpp"
#include "gabarit/link/dut_endpoint.hpp"
#include "gabarit/link/session_report.hpp"
#include "gabarit/table_format.hpp"
#include "gabarit/table_view.hpp"
#if GABARIT_HIL_PARTICLE
#include "firmware_particle_session.hpp"
#else
#include "firmware_session.hpp"
#endif
#include "tracker_capacity.hpp"
#include "uart.hpp"

extern "C" {
extern const std::byte gabarit_table_slot[], gabarit_table_slot_end[];
}

namespace {

using namespace gabarit;

// Frames up to 384 x 288 (the scene suite's size; the particle tracker's:
// up to 256 x 256, whose edge map it holds whole) and messages of up to 1 KiB.
#if GABARIT_HIL_PARTICLE
constexpr std::uint32_t kMaxFrameBytes = mcu::kMaxParticleFrameSide * mcu::kMaxParticleFrameSide;
#else
constexpr std::uint32_t kMaxFrameBytes = 384u * 288u;
#endif
constexpr std::size_t kMaxPayload = 1024;
constexpr std::size_t kMaxStackDepths = 16;

// A test double, never a product image: built with GABARIT_HIL_FAULTY_FRAME=N
// (gabarit-firmware-hil-faulty) it reports frame N's pose a pixel to the
// right, as a firmware bug would, so that the path of a failing frame through
// a board farm can be tested (tests/hil/lava_run_test.sh, lava_farm_test.sh).
// 0, no frame, in every other image.
#ifndef GABARIT_HIL_FAULTY_FRAME
#define GABARIT_HIL_FAULTY_FRAME 0
#endif
constexpr std::uint32_t kFaultyFrame = GABARIT_HIL_FAULTY_FRAME;

RoiPoint g_features[mcu::kFeatureCapacity];
VoteCounter g_counters[mcu::kCounterCount];
std::uint8_t g_roi_mask[mcu::kMaskBytes];
std::uint16_t g_magnitudes[mcu::kMagnitudeEntries];
std::uint8_t g_frame[link::dut_frame_memory_bytes(1, kMaxFrameBytes)];
std::byte g_rx[link::message_bytes(kMaxPayload)];
std::uint8_t g_tx[link::cobs_encoded_capacity(link::message_bytes(link::kMinPayload))];
ImageView g_stack_views[kMaxStackDepths];

#if GABARIT_HIL_PARTICLE
// The particle tracker's cloud, its radix sort's indices, the frame's edge
// map and the intensity measures; the tracker scratch above serves the
// proposals' vote.
Particle g_cloud[particle_scratch_particles(mcu::kMaxParticles)];
Particle g_next[particle_scratch_particles(mcu::kMaxParticles)];
std::uint32_t g_order[particle_scratch_order(mcu::kMaxParticles)];
std::uint64_t g_edge_bits[mcu::kEdgeMapWords];
RoiPoint g_edge_features[mcu::kEdgeMapFeatures];
IntensityCorrelationMeasure g_intensity[2];
static_assert(mcu::kFirmwareParticleProfile.particles <= mcu::kMaxParticles, "the cloud's arrays hold the profile's particles");

// The particle tracker behind the stencil session's interface.
class HilSession {
 public:
  HilSession(const TableView& table, std::span<ImageView> stack_views) noexcept
      : session_(table, {{g_cloud, g_next, g_order}, g_edge_bits, g_edge_features, {}, stack_views, g_intensity}) {}
  std::uint32_t mode() const noexcept { return session_.mode(); }
  [[nodiscard]] bool start(const Pose& initial) noexcept { return session_.start(initial); }
  bool started() const noexcept { return session_.started(); }
  // `fine`: the proposals' vote (set once: the table never changes).
  [[nodiscard]] Status step(const ImageView& image, TrackerScratch fine, SessionResult& out) noexcept {
    session_.use_proposer_scratch(fine);
    return session_.step(image, out);
  }

 private:
  mcu::FirmwareParticleSession session_;
};
#else
using HilSession = mcu::FirmwareSession;
#endif

// SysTick (every Cortex-M core has one) as a 64-bit clock at the core clock:
// a 24-bit down-counter read at every message and every frame, so it never
// wraps twice between two reads within a frame (2^24 cycles is over half a
// second of guest time; a frame takes about a millisecond).
class Timer {
 public:
  void start() noexcept {
    reg(kReload) = 0x00FFFFFFu;
    reg(kCurrent) = 0;                    // any write clears it
    reg(kControl) = kEnable | kCoreClock;  // no interrupt
    last_ = reg(kCurrent);
  }
  std::uint64_t now() noexcept {
    const std::uint32_t v = reg(kCurrent);
    elapsed_ += (last_ - v) & 0x00FFFFFFu;  // counts down, modulo 2^24
    last_ = v;
    return elapsed_;
  }

 private:
  static constexpr std::uintptr_t kControl = 0xE000E010u, kReload = 0xE000E014u, kCurrent = 0xE000E018u;
  static constexpr std::uint32_t kEnable = 1u << 0, kCoreClock = 1u << 2;
  static volatile std::uint32_t& reg(std::uintptr_t address) noexcept {
    return *reinterpret_cast<volatile std::uint32_t*>(address);
  }
  std::uint32_t last_ = 0;
  std::uint64_t elapsed_ = 0;
};

class UartOutput {
 public:
  explicit UartOutput(mcu::Uart& uart) noexcept : uart_(uart) {}
  void send(std::span<const std::byte> message) noexcept {
    std::size_t n = 0;
    if (link::cobs_encode(message, std::as_writable_bytes(std::span(g_tx)), n) != Status::kOk) return;
    uart_.write(g_tx, n);
  }

 private:
  mcu::Uart& uart_;
};

class FirmwareDut {
 public:
  // `table` is `view` when it opened, else null (and `view` is never used).
  FirmwareDut(const TableView& view, const TableView* table, Timer& timer, mcu::Uart& console) noexcept
      : table_(table), timer_(timer), console_(console),
        session_(view, table != nullptr ? std::span(g_stack_views) : std::span<ImageView>()) {}
  std::uint32_t mode() const noexcept { return session_.mode(); }

  // The host's line for the console (printable ASCII: the endpoint checked).
  void note(const link::Note& note) noexcept {
    console_.write(note.text);
    console_.write("\r\n");
  }

  link::Refusal start(const link::Hello& hello) noexcept {
    if (table_ == nullptr) return link::Refusal::kNoTable;
    return session_.start(hello.initial) ? link::Refusal::kNone : link::Refusal::kBadPose;
  }
  std::uint64_t now() noexcept { return timer_.now(); }

  bool track_next(link::DutEndpoint& endpoint) noexcept {
    link::ReadyFrame frame;
    if (!endpoint.next_frame(frame)) return false;
    if (!session_.started()) {
      endpoint.report_failure(link::EventKind::kSkipped, link::EventReason::kNotStarted, 0, now());
      return true;
    }
    TrackerScratch fine;
    fine.features = g_features;
    fine.counters = std::span<VoteCounter>(g_counters, voter_counter_count(table_->cell_count()));
    fine.roi_mask = g_roi_mask;
    fine.magnitudes = g_magnitudes;
    const ImageView image{frame.pixels.data(), frame.width, frame.height, frame.width};
    SessionResult result;
    if (const Status s = session_.step(image, fine, result); s != Status::kOk) {
      endpoint.report_failure(link::EventKind::kError, link::EventReason::kTracking, static_cast<std::uint32_t>(s), now());
      return true;
    }
    link::PoseReport report = link::session_report(result);
    if (kFaultyFrame != 0 && frame.frame_id == kFaultyFrame) report.pose.x += 1.0f;
    endpoint.report_pose(report, now());
    return true;
  }

 private:
  const TableView* table_;
  Timer& timer_;
  mcu::Uart& console_;
  HilSession session_;
};

// The table in the slot, validated once: its header's size, then the
// kernel's checks (structure, CRC). Null when there is none or it does not fit.
const TableView* open_slot_table(TableView& view, std::uint32_t& bytes, std::uint32_t& crc) noexcept {
  const std::size_t slot = static_cast<std::size_t>(gabarit_table_slot_end - gabarit_table_slot);
  std::uint32_t declared = 0;
  std::memcpy(&declared, gabarit_table_slot + 16, 4);  // file_bytes (docs/table-format.md)
  if (declared < table_format::kHeaderBytes || declared > slot) return nullptr;
  const std::span<const std::byte> file(gabarit_table_slot, declared);
  if (TableView::open(file, view) != Status::kOk || !mcu::table_fits(view)) return nullptr;
  bytes = declared;
  crc = crc32(file);
  return &view;
}

}  // namespace

extern "C" int app_main() {
  mcu::Uart uart(mcu::board::kUart0Base);
  uart.enable_tx_rx();
  Timer timer;
  timer.start();
  TableView view;
  link::DeviceDescription device;
  const TableView* table = open_slot_table(view, device.table_bytes, device.table_crc);
  mcu::Uart console(mcu::board::kUart1Base);
  console.enable_tx();
  console.write("gabarit-hil: ready, ");
  console.write(mcu::board::kName);
  console.write(table != nullptr ? ", a table in the slot\r\n" : ", no valid table in the slot\r\n");
  FirmwareDut app(view, table, timer, console);
  device.max_payload = static_cast<std::uint16_t>(kMaxPayload);
  device.clock_hz = mcu::board::kCoreClockHz;
  device.max_frame_bytes = kMaxFrameBytes;
  device.mode = app.mode();
  device.kind = "cortex-m";
  device.board = mcu::board::kName;
  link::DutEndpoint endpoint(link::make_caps(device), g_frame);
  link::CobsStreamDecoder decoder(g_rx);
  UartOutput out(uart);
  for (;;) {
    const int b = uart.read();
    if (b < 0) continue;
    switch (decoder.push(static_cast<std::byte>(b))) {
      case link::CobsStreamDecoder::Event::kMessage: link::deliver(endpoint, decoder.message(), app, out); break;
      case link::CobsStreamDecoder::Event::kDiscarded: endpoint.on_framing_error(); break;
      case link::CobsStreamDecoder::Event::kNone: break;
    }
    // A whole frame is tracked before another byte is read (the UART holds
    // the sender back meanwhile).
    while (app.track_next(endpoint)) link::flush(endpoint, out);
  }
}
