// make_link_seeds OUTDIR: seed streams for link_fuzz, COBS-framed as a UART
// carries them: a whole run (HELLO, a frame in fragments, PING, STATS, BYE),
// a frame with a lost fragment, a repeated and a late frame, and garbage
// between messages.
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "gabarit/link/cobs.hpp"
#include "gabarit/link/protocol.hpp"

namespace {

using namespace gabarit::link;

std::uint32_t g_seq = 0;

void put(std::vector<std::byte>& stream, MessageType type, std::span<const std::byte> payload) {
  Header h;
  h.type = type;
  h.seq = g_seq++;
  std::vector<std::byte> m(message_bytes(payload.size())), wire(cobs_encoded_capacity(m.size()));
  std::size_t n = 0, w = 0;
  if (encode_message(h, payload, m, n) != gabarit::Status::kOk || cobs_encode(m, wire, w) != gabarit::Status::kOk) std::abort();
  stream.insert(stream.end(), wire.begin(), wire.begin() + static_cast<std::ptrdiff_t>(w));
}

void hello(std::vector<std::byte>& s, std::uint32_t run) {
  std::byte b[kHelloBytes];
  put(s, MessageType::kHello, std::span(b, encode(Hello{1, 512, 0x12345678u, run, {10, 10, 0, 0}, 0}, b)));
}

void frame(std::vector<std::byte>& s, std::uint32_t id, bool lose_second = false) {
  std::vector<std::byte> pixels(24 * 20);
  for (std::size_t i = 0; i < pixels.size(); ++i) pixels[i] = std::byte((i * 7 + id) & 0xFF);
  std::byte b[kMaxPayload];
  for (std::uint32_t at = 0, k = 0; at < pixels.size(); at += 200, ++k) {
    if (lose_second && k == 1) continue;
    const std::size_t n = std::min<std::size_t>(200, pixels.size() - at);
    const FrameFragment f{id, 5, 24, 20, at, static_cast<std::uint32_t>(pixels.size()), std::span(pixels).subspan(at, n)};
    put(s, MessageType::kFrame, std::span(b, encode(f, b)));
  }
}

void write(const std::string& path, const std::vector<std::byte>& s) {
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(s.data()), static_cast<std::streamsize>(s.size()));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_link_seeds OUTDIR\n");
    return 2;
  }
  const std::string dir = argv[1];
  std::byte b[64];
  std::vector<std::byte> run;
  hello(run, 1);
  frame(run, 0);
  frame(run, 1);
  put(run, MessageType::kPing, std::span(b, encode(Ping{1, 2}, b)));
  put(run, MessageType::kStats, {});
  put(run, MessageType::kInject, std::span(b, encode(Inject{0, 9}, b)));
  {
    std::byte big[kInjectedBytes];
    Injected answer;
    set_text(answer.evidence, "a rig's answer, which a device never receives");
    put(run, MessageType::kInjected, std::span(big, encode(answer, big)));
  }
  {
    std::byte note[kNoteBytes];
    Note line;
    set_text(line.text, "gabarit-hil case=frame-000001 result=pass measurement=0.010 units=px");
    put(run, MessageType::kNote, std::span(note, encode(line, note)));
  }
  put(run, MessageType::kBye, std::span(b, encode(Bye{0, 1}, b)));
  write(dir + "/run.bin", run);
  std::vector<std::byte> faults;
  hello(faults, 2);
  frame(faults, 0, true);
  frame(faults, 2);
  frame(faults, 2);
  frame(faults, 1);
  faults.insert(faults.end(), {std::byte{0x41}, std::byte{0x42}, std::byte{0}, std::byte{7}});
  put(faults, MessageType::kPing, std::span(b, encode(Ping{2, 3}, b)));
  write(dir + "/faults.bin", faults);
  std::vector<std::byte> before_hello;
  frame(before_hello, 3);
  hello(before_hello, 3);
  hello(before_hello, 3);
  write(dir + "/before-hello.bin", before_hello);
  return 0;
}
