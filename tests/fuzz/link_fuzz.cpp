// Fuzz target: the HIL link as both ends parse it. The input is a byte
// stream as a UART or socket delivers it: COBS runs into the device's
// endpoint (HELLO, FRAME fragments, PING, STATS, BYE, garbage), frames taken
// and answered as a DUT would; and each message decoded as every payload
// type the harness reads, re-encoded and decoded again to the same bytes.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "gabarit/link/cobs.hpp"
#include "gabarit/link/dut_endpoint.hpp"
#include "gabarit/link/protocol.hpp"

namespace {

using namespace gabarit::link;

struct App {
  Refusal start(const Hello& h) noexcept { return h.initial.depth == 7 ? Refusal::kBadPose : Refusal::kNone; }
  std::uint64_t now() noexcept { return ++clock; }
  std::uint64_t clock = 0;
};

struct Sink {
  void send(std::span<const std::byte> m) noexcept {
    Header h;
    std::span<const std::byte> p;
    if (decode_message(m, h, p) != gabarit::Status::kOk) std::abort();  // the endpoint's own messages are valid
    ++sent;
  }
  std::size_t sent = 0;
};

template <class M>
void round_trip(std::span<const std::byte> payload) {
  M m;
  if (decode(payload, m) != gabarit::Status::kOk) return;
  std::byte a[kMaxPayload], b[kMaxPayload];
  const std::size_t n = encode(m, a);
  if (n == 0) std::abort();
  M again;
  if (decode(std::span(a, n), again) != gabarit::Status::kOk) std::abort();
  if (encode(again, b) != n || std::memcmp(a, b, n) != 0) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Caps caps;
  caps.max_payload = 512;
  caps.table_crc = 0x12345678u;
  caps.clock_hz = 1000;
  caps.frame_slots = 2;
  caps.max_frame_bytes = 4096;
  static std::vector<std::uint8_t> memory(dut_frame_memory_bytes(2, 4096));
  DutEndpoint endpoint(caps, memory);
  App app;
  Sink out;
  std::vector<std::byte> buffer(message_bytes(512));
  CobsStreamDecoder decoder(buffer);
  for (std::size_t i = 0; i < size; ++i) {
    switch (decoder.push(static_cast<std::byte>(data[i]))) {
      case CobsStreamDecoder::Event::kMessage: {
        const auto m = decoder.message();
        Header h;
        std::span<const std::byte> p;
        if (decode_message(m, h, p) == gabarit::Status::kOk) {
          round_trip<Hello>(p);
          round_trip<Caps>(p);
          round_trip<PoseReport>(p);
          round_trip<Event>(p);
          round_trip<Pong>(p);
          round_trip<Stats>(p);
          round_trip<Bye>(p);
          round_trip<Inject>(p);
          round_trip<Injected>(p);
          FrameFragment f;
          if (decode(p, f) == gabarit::Status::kOk && (f.pixels.data() < p.data() || f.pixels.data() + f.pixels.size() > p.data() + p.size()))
            std::abort();
        }
        deliver(endpoint, m, app, out);
        break;
      }
      case CobsStreamDecoder::Event::kDiscarded: endpoint.on_framing_error(); break;
      case CobsStreamDecoder::Event::kNone: break;
    }
    ReadyFrame f;
    while (endpoint.next_frame(f)) {
      if (f.pixels.size() != std::size_t{f.width} * f.height || f.pixels.data() < memory.data() ||
          f.pixels.data() + f.pixels.size() > memory.data() + memory.size())
        std::abort();
      std::uint32_t sum = 0;
      for (const std::uint8_t px : f.pixels) sum += px;  // read every pixel handed out
      if ((sum & 1u) != 0) endpoint.report_pose(PoseReport{}, app.now());
      else endpoint.report_failure(EventKind::kError, EventReason::kTracking, sum, app.now());
      flush(endpoint, out);
    }
    if (endpoint.queued() > caps.frame_slots) std::abort();
  }
  return 0;
}
