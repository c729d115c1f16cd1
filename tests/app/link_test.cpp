// The HIL link's codec and device endpoint (app/include/gabarit/link/).
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "gabarit/crc32.hpp"
#include "gabarit/link/cobs.hpp"
#include "gabarit/link/dut_endpoint.hpp"
#include "gabarit/link/protocol.hpp"

namespace gabarit::link {
namespace {

std::vector<std::byte> random_bytes(std::size_t n, std::uint32_t seed, int zero_one_in) {
  std::mt19937 rng(seed);
  std::vector<std::byte> v(n);
  for (auto& b : v) b = (rng() % static_cast<unsigned>(zero_one_in)) == 0 ? std::byte{0} : std::byte(1 + rng() % 255);
  return v;
}

std::vector<std::byte> cobs(const std::vector<std::byte>& in) {
  std::vector<std::byte> out(cobs_encoded_capacity(in.size()));
  std::size_t n = 0;
  EXPECT_EQ(cobs_encode(in, out, n), Status::kOk);
  out.resize(n);
  return out;
}

TEST(Cobs, RoundTripsAwkwardLengthsAndHasNoZeroBeforeTheDelimiter) {
  for (std::size_t n : {0u, 1u, 2u, 253u, 254u, 255u, 256u, 508u, 509u, 1000u, 4096u}) {
    for (int zeros : {1, 3, 1000000}) {  // all zeros, many, none
      const auto in = random_bytes(n, static_cast<std::uint32_t>(n * 7 + static_cast<std::size_t>(zeros)), zeros);
      const auto enc = cobs(in);
      ASSERT_LE(enc.size(), cobs_encoded_capacity(n));
      ASSERT_EQ(enc.back(), std::byte{0});
      for (std::size_t i = 0; i + 1 < enc.size(); ++i) ASSERT_NE(enc[i], std::byte{0}) << n;
      std::vector<std::byte> dec(n + 1);
      std::size_t w = 0;
      ASSERT_EQ(cobs_decode(std::span(enc).first(enc.size() - 1), dec, w), Status::kOk) << n;
      dec.resize(w);
      EXPECT_EQ(dec, in) << "length " << n << ", zero one in " << zeros;
    }
  }
}

TEST(Cobs, RefusesShortBuffersAndMalformedRuns) {
  const std::vector<std::byte> in(10, std::byte{7});
  std::vector<std::byte> out(cobs_encoded_capacity(10) - 1);
  std::size_t w = 0;
  EXPECT_EQ(cobs_encode(in, out, w), Status::kBufferTooSmall);
  std::vector<std::byte> dec(64);
  const std::byte runs_past_end[] = {std::byte{5}, std::byte{1}, std::byte{2}};
  EXPECT_EQ(cobs_decode(runs_past_end, dec, w), Status::kBadHeaderField);
  const std::byte has_zero[] = {std::byte{3}, std::byte{0}, std::byte{2}};
  EXPECT_EQ(cobs_decode(has_zero, dec, w), Status::kBadHeaderField);
  const auto enc = cobs(std::vector<std::byte>(100, std::byte{1}));
  std::vector<std::byte> small(50);
  EXPECT_EQ(cobs_decode(std::span(enc).first(enc.size() - 1), small, w), Status::kBufferTooSmall);
}

TEST(CobsStreamDecoder, ResynchronisesAfterGarbageAndCountsIt) {
  std::vector<std::byte> buffer(300);
  CobsStreamDecoder d(buffer);
  std::vector<std::vector<std::byte>> got;
  const auto feed = [&](const std::vector<std::byte>& bytes) {
    for (std::byte b : bytes)
      if (d.push(b) == CobsStreamDecoder::Event::kMessage) got.emplace_back(d.message().begin(), d.message().end());
  };
  const auto a = random_bytes(40, 1, 5), b = random_bytes(280, 2, 9), too_long = random_bytes(400, 3, 1000000);
  feed({std::byte{9}, std::byte{1}});  // the tail of a message joined mid-way: no delimiter yet
  feed(cobs(a));                        // that run ends at a's delimiter: malformed, a lost with it
  feed(cobs(a));
  feed(cobs(too_long));                 // longer than the buffer: discarded
  feed(cobs(b));
  auto cut = cobs(a);
  cut.erase(cut.begin() + 20, cut.end() - 1);  // a block cut short by the delimiter
  feed(cut);
  feed(cobs({}));
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[0], a);
  EXPECT_EQ(got[1], b);
  EXPECT_TRUE(got[2].empty());
  EXPECT_EQ(d.overlong(), 1u);
  EXPECT_EQ(d.malformed(), 2u);
}

TEST(Protocol, SequenceNumbersCompareAcrossTheWrap) {
  EXPECT_TRUE(seq_after(1, 0));
  EXPECT_FALSE(seq_after(0, 0));
  EXPECT_FALSE(seq_after(0, 1));
  EXPECT_TRUE(seq_after(0, 0xFFFFFFFFu));
  EXPECT_TRUE(seq_after(5, 0xFFFFFFF0u));
  EXPECT_FALSE(seq_after(0xFFFFFFF0u, 5));
  EXPECT_TRUE(seq_after(0x7FFFFFFFu, 0));
  EXPECT_FALSE(seq_after(0x80000000u, 0));
}

std::vector<std::byte> message(MessageType type, std::span<const std::byte> payload, std::uint32_t seq = 0) {
  Header h;
  h.type = type;
  h.seq = seq;
  std::vector<std::byte> out(message_bytes(payload.size()));
  std::size_t w = 0;
  EXPECT_EQ(encode_message(h, payload, out, w), Status::kOk);
  return out;
}

TEST(Protocol, EveryMessageRoundTripsAndEachDecodeErrorHasItsCode) {
  Header h;
  h.type = MessageType::kStats;
  h.seq = 0xFFFFFFFEu;
  h.ack = 77;
  h.credits = 3;
  const std::byte payload[] = {std::byte{1}, std::byte{2}, std::byte{3}};
  std::vector<std::byte> out(message_bytes(3));
  std::size_t w = 0;
  ASSERT_EQ(encode_message(h, payload, out, w), Status::kOk);
  ASSERT_EQ(w, 27u);
  EXPECT_EQ(out[0], std::byte{0x47});  // "GL"
  EXPECT_EQ(out[1], std::byte{0x4C});
  Header back;
  std::span<const std::byte> p;
  ASSERT_EQ(decode_message(out, back, p), Status::kOk);
  EXPECT_EQ(back.type, MessageType::kStats);
  EXPECT_EQ(back.seq, h.seq);
  EXPECT_EQ(back.ack, 77u);
  EXPECT_EQ(back.credits, 3u);
  ASSERT_EQ(p.size(), 3u);
  EXPECT_EQ(p[2], std::byte{3});

  EXPECT_EQ(decode_message(std::span(out).first(23), back, p), Status::kTruncated);
  auto bad = out;
  bad[0] = std::byte{0};
  EXPECT_EQ(decode_message(bad, back, p), Status::kBadMagic);
  bad = out;
  bad[2] = std::byte{2};
  EXPECT_EQ(decode_message(bad, back, p), Status::kUnsupportedVersion);
  EXPECT_EQ(decode_message(std::span(out).first(26), back, p), Status::kSizeMismatch);
  for (std::size_t bit = 0; bit < out.size() * 8; ++bit) {  // every single-bit flip is caught
    bad = out;
    bad[bit / 8] ^= std::byte(1u << (bit % 8));
    EXPECT_NE(decode_message(bad, back, p), Status::kOk) << "bit " << bit;
  }
  bad = out;
  bad[3] = std::byte{200};  // an unknown type decodes; the receiver skips it
  const std::uint32_t crc = crc32c(std::span(bad).first(23));
  for (int i = 0; i < 4; ++i) bad[23 + static_cast<std::size_t>(i)] = std::byte((crc >> (8 * i)) & 0xFF);
  EXPECT_EQ(decode_message(bad, back, p), Status::kOk);
  EXPECT_STREQ(message_type_name(back.type), "unknown");

  std::byte buf[kMaxPayload];
  Hello hello{1, 512, 0xDEADBEEFu, 42, Pose{1.5f, -2.25f, 3.0f, 2}, 9};
  Hello hello2;
  ASSERT_EQ(encode(hello, buf), kHelloBytes);
  ASSERT_EQ(decode(std::span(buf, kHelloBytes), hello2), Status::kOk);
  EXPECT_EQ(hello2.table_crc, hello.table_crc);
  EXPECT_EQ(hello2.initial.y, -2.25f);
  EXPECT_EQ(hello2.initial.depth, 2);
  EXPECT_EQ(decode(std::span(buf, kHelloBytes - 1), hello2), Status::kTruncated);

  Caps caps;
  caps.max_payload = 1024;
  caps.clock_hz = 25000000;
  caps.frame_slots = 1;
  caps.device_id = 0x0123456789ABCDEFull;
  set_text(caps.kind, "cortex-m-with-a-very-long-name");
  Caps caps2;
  ASSERT_EQ(encode(caps, buf), kCapsBytes);
  ASSERT_EQ(decode(std::span(buf, kCapsBytes), caps2), Status::kOk);
  EXPECT_EQ(caps2.device_id, caps.device_id);
  EXPECT_STREQ(caps2.kind, "cortex-m-with-a");  // truncated to the field, NUL-ended
  caps.frame_slots = 0;
  ASSERT_EQ(encode(caps, buf), kCapsBytes);
  EXPECT_EQ(decode(std::span(buf, kCapsBytes), caps2), Status::kBadHeaderField);

  PoseReport pose;
  pose.frame_id = 5;
  pose.pose = Pose{0.1f, 0.2f, -0.3f, 1};
  pose.state = 1;
  pose.votes = 1ull << 40;
  pose.cycles = 123456789012ull;
  PoseReport pose2;
  ASSERT_EQ(encode(pose, buf), kPoseBytes);
  ASSERT_EQ(decode(std::span(buf, kPoseBytes), pose2), Status::kOk);
  EXPECT_EQ(std::memcmp(&pose2.pose.x, &pose.pose.x, 4), 0);
  EXPECT_EQ(pose2.votes, pose.votes);
  EXPECT_EQ(pose2.cycles, pose.cycles);
  buf[18] = std::byte{4};  // state 4 is not a TrackState (3 is kAmbiguous)
  EXPECT_EQ(decode(std::span(buf, kPoseBytes), pose2), Status::kBadHeaderField);

  const std::byte pixels[6] = {};
  FrameFragment frag{7, 99, 3, 2, 0, 6, pixels};
  FrameFragment frag2;
  const std::size_t n = encode(frag, buf);
  ASSERT_EQ(n, kFrameFixedBytes + 6);
  ASSERT_EQ(decode(std::span(buf, n), frag2), Status::kOk);
  EXPECT_EQ(frag2.pixels.size(), 6u);
  frag.offset = 1;  // runs past the frame
  EXPECT_EQ(decode(std::span(buf, encode(frag, buf)), frag2), Status::kBadHeaderField);
  frag.offset = 0;
  frag.total_bytes = 7;  // not width x height
  EXPECT_EQ(decode(std::span(buf, encode(frag, buf)), frag2), Status::kBadHeaderField);

  Event e{EventKind::kSkipped, EventReason::kOutOfOrder, 3, 4, 5};
  Event e2;
  ASSERT_EQ(decode(std::span(buf, encode(e, buf)), e2), Status::kOk);
  EXPECT_EQ(e2.reason, EventReason::kOutOfOrder);
  buf[0] = std::byte{0};
  EXPECT_EQ(decode(std::span(buf, kEventBytes), e2), Status::kBadHeaderField);
  EXPECT_EQ(encode(Stats{}, std::span(buf, kStatsBytes - 1)), 0u);  // a short buffer writes nothing
}

// 1.1's additions: INJECT and INJECTED, POSE's camera stages and STATS's
// resident memory, appended so that a 1.0 peer's shorter messages decode.
TEST(Protocol, RigFaultMessagesAndTheAppendedFieldsRoundTripAndOldLengthsDecode) {
  std::byte buf[512];
  const Inject in{77, 9};
  Inject in2;
  ASSERT_EQ(encode(in, buf), kInjectBytes);
  ASSERT_EQ(decode(std::span(buf, kInjectBytes), in2), Status::kOk);
  EXPECT_EQ(in2.token, 77u);
  EXPECT_EQ(in2.kind, 9u);
  EXPECT_EQ(decode(std::span(buf, 4), in2), Status::kTruncated);

  Injected a;
  a.token = 5;
  a.kind = 3;
  a.outcome = InjectOutcome::kDetected;
  a.attempts = 2;
  a.started = 1000;
  a.ended = 2500;
  set_text(a.evidence, "board: camera lost (1) and reopened (1)");
  Injected a2;
  ASSERT_EQ(encode(a, buf), kInjectedBytes);
  ASSERT_EQ(decode(std::span(buf, kInjectedBytes), a2), Status::kOk);
  EXPECT_EQ(a2.token, 5u);
  EXPECT_EQ(a2.outcome, InjectOutcome::kDetected);
  EXPECT_EQ(a2.attempts, 2u);
  EXPECT_EQ(a2.ended, 2500u);
  EXPECT_STREQ(a2.evidence, "board: camera lost (1) and reopened (1)");
  buf[5] = std::byte{4};  // no such outcome
  EXPECT_EQ(decode(std::span(buf, kInjectedBytes), a2), Status::kBadHeaderField);
  EXPECT_STREQ(inject_outcome_name(InjectOutcome::kUndetected), "undetected");

  PoseReport p;
  p.frame_id = 3;
  p.captured = 111;
  p.strobed = 222;
  PoseReport p2;
  ASSERT_EQ(encode(p, buf), kPoseBytes);
  ASSERT_EQ(decode(std::span(buf, kPoseBytes), p2), Status::kOk);
  EXPECT_EQ(p2.captured, 111u);
  EXPECT_EQ(p2.strobed, 222u);
  ASSERT_EQ(decode(std::span(buf, kPoseBytesV10), p2), Status::kOk);  // a 1.0 POSE: no stages
  EXPECT_EQ(p2.captured, 0u);
  EXPECT_EQ(p2.strobed, 0u);

  Stats st;
  st.frames_tracked = 9;
  st.resident_kib = 4321;
  Stats st2;
  ASSERT_EQ(encode(st, buf), kStatsBytes);
  ASSERT_EQ(decode(std::span(buf, kStatsBytes), st2), Status::kOk);
  EXPECT_EQ(st2.resident_kib, 4321u);
  ASSERT_EQ(decode(std::span(buf, kStatsBytes - 4), st2), Status::kOk);  // 1.0's 48 bytes
  EXPECT_EQ(st2.resident_kib, 0u);
  EXPECT_EQ(st2.frames_tracked, 9u);

  Event e{EventKind::kError, EventReason::kCameraLost, kNoFrame, 1, 0};
  Event e2;
  ASSERT_EQ(decode(std::span(buf, encode(e, buf)), e2), Status::kOk);
  EXPECT_EQ(e2.reason, EventReason::kCameraLost);
  EXPECT_STREQ(event_reason_name(EventReason::kSequenceWrap), "camera-sequence-wrap");
  buf[1] = std::byte{kLastEventReason + 1};
  EXPECT_EQ(decode(std::span(buf, kEventBytes), e2), Status::kBadHeaderField);
}

// A DUT endpoint with a recording output and an application that accepts.
struct Recorder {
  void send(std::span<const std::byte> m) noexcept { sent.emplace_back(m.begin(), m.end()); }
  std::vector<std::vector<std::byte>> sent;
};
struct App {
  Refusal start(const Hello& h) noexcept {
    started = h;
    ++starts;
    return Refusal::kNone;
  }
  std::uint64_t now() noexcept { return ++clock; }
  void note(const Note& n) noexcept { notes.emplace_back(n.text); }
  Hello started;
  std::vector<std::string> notes;  // a console's lines
  int starts = 0;
  std::uint64_t clock = 0;
};

struct EndpointFixture : ::testing::Test {
  EndpointFixture() : memory(2 * 64), endpoint(caps(), memory) {}
  static Caps caps() {
    Caps c;
    c.max_payload = 256;
    c.table_crc = 0x1234;
    c.clock_hz = 1000;
    c.frame_slots = 2;
    c.max_frame_bytes = 64;
    return c;
  }
  void deliver(MessageType type, std::span<const std::byte> payload) { link::deliver(endpoint, message(type, payload, seq++), app, out); }
  void flush() { link::flush(endpoint, out); }
  void hello(std::uint32_t run, std::uint32_t table_crc = 0x1234) {
    std::byte b[kHelloBytes];
    deliver(MessageType::kHello, std::span(b, encode(Hello{1, 256, table_crc, run, {}, 0}, b)));
  }
  // Frame `id`, 8x8, in fragments of `step` pixels from `from` to `to`.
  void frame(std::uint32_t id, std::uint32_t from = 0, std::uint32_t to = 64, std::uint32_t step = 32) {
    std::vector<std::byte> pixels(64);
    for (std::size_t i = 0; i < 64; ++i) pixels[i] = std::byte(id + i);
    std::byte b[kMaxPayload];
    for (std::uint32_t at = from; at < to; at += step) {
      const FrameFragment f{id, 0, 8, 8, at, 64, std::span(pixels).subspan(at, std::min(step, 64 - at))};
      deliver(MessageType::kFrame, std::span(b, encode(f, b)));
    }
  }
  // The messages sent since the last call, decoded by type.
  std::vector<Header> take(std::vector<Event>* events = nullptr, std::vector<PoseReport>* poses = nullptr, Caps* caps = nullptr) {
    std::vector<Header> headers;
    for (const auto& m : out.sent) {
      Header h;
      std::span<const std::byte> p;
      EXPECT_EQ(decode_message(m, h, p), Status::kOk);
      headers.push_back(h);
      if (h.type == MessageType::kEvent && events) {
        events->emplace_back();
        EXPECT_EQ(decode(p, events->back()), Status::kOk);
      }
      if (h.type == MessageType::kPose && poses) {
        poses->emplace_back();
        EXPECT_EQ(decode(p, poses->back()), Status::kOk);
      }
      if (h.type == MessageType::kCaps && caps) {
        EXPECT_EQ(decode(p, *caps), Status::kOk);
      }
    }
    out.sent.clear();
    return headers;
  }
  std::vector<std::uint8_t> memory;
  Recorder out;
  App app;
  DutEndpoint endpoint;
  std::uint32_t seq = 0;
};

TEST_F(EndpointFixture, HelloIsAnsweredWithCapsAndAWrongTableIsRefused) {
  hello(7, 0x9999);
  Caps c;
  auto h = take(nullptr, nullptr, &c);
  ASSERT_EQ(h.size(), 1u);
  EXPECT_EQ(h[0].type, MessageType::kCaps);
  EXPECT_EQ(c.refusal, Refusal::kTableMismatch);
  EXPECT_FALSE(endpoint.running());
  EXPECT_EQ(app.starts, 0);
  hello(8);
  take(nullptr, nullptr, &c);
  EXPECT_EQ(c.refusal, Refusal::kNone);
  EXPECT_EQ(c.run_id, 8u);
  EXPECT_TRUE(endpoint.running());
  hello(8);  // the same run again: CAPS again, no restart
  EXPECT_EQ(take().size(), 1u);
  EXPECT_EQ(app.starts, 1);
}

TEST_F(EndpointFixture, FragmentsAssembleInOrderAndEachFrameGetsOneAnswer) {
  hello(1);
  take();
  frame(0);
  frame(1);
  ReadyFrame f;
  ASSERT_TRUE(endpoint.next_frame(f));
  EXPECT_EQ(f.frame_id, 0u);
  EXPECT_EQ(f.pixels[63], 63);
  EXPECT_FALSE(endpoint.next_frame(f)) << "one frame out at a time";
  endpoint.report_pose(PoseReport{}, app.now());
  flush();
  ASSERT_TRUE(endpoint.next_frame(f));
  EXPECT_EQ(f.frame_id, 1u);
  EXPECT_EQ(f.pixels[0], 1);
  endpoint.report_failure(EventKind::kError, EventReason::kTracking, 3, app.now());
  flush();
  std::vector<Event> events;
  std::vector<PoseReport> poses;
  take(&events, &poses);
  ASSERT_EQ(poses.size(), 1u);
  EXPECT_EQ(poses[0].frame_id, 0u);
  std::vector<std::byte> px(64);
  for (std::size_t i = 0; i < 64; ++i) px[i] = std::byte(i);
  EXPECT_EQ(poses[0].frame_crc, crc32c(px));
  EXPECT_LT(poses[0].received, poses[0].done);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].frame_id, 1u);
  EXPECT_EQ(events[0].reason, EventReason::kTracking);
}

TEST_F(EndpointFixture, LostFragmentsLateFramesRepeatsAndAFullQueueAreReported) {
  hello(1);
  take();
  frame(0, 0, 32);  // first half only
  frame(1);         // frame 0 can no longer complete
  frame(3, 32, 64); // its first fragment lost
  frame(2);         // older than 3: out of order
  frame(1);         // a repeat of a taken frame
  frame(4);         // slot 2 of 2 (frame 1 holds the other)
  frame(5);         // no slot left
  std::vector<Event> events;
  take(&events);
  ASSERT_EQ(events.size(), 5u);
  EXPECT_EQ(events[0].frame_id, 0u);
  EXPECT_EQ(events[0].reason, EventReason::kIncomplete);
  EXPECT_EQ(events[1].frame_id, 3u);
  EXPECT_EQ(events[1].kind, EventKind::kDropped);
  EXPECT_EQ(events[2].frame_id, 2u);
  EXPECT_EQ(events[2].reason, EventReason::kOutOfOrder);
  EXPECT_EQ(events[3].kind, EventKind::kDuplicate);
  EXPECT_EQ(events[4].frame_id, 5u);
  EXPECT_EQ(events[4].reason, EventReason::kQueueFull);
  EXPECT_EQ(endpoint.queued(), 2u);
  // Ping: the DUT's view of the run.
  std::byte b[kPingBytes];
  deliver(MessageType::kPing, std::span(b, encode(Ping{9, 1}, b)));
  const auto h = take();
  ASSERT_EQ(h.size(), 1u);
  EXPECT_EQ(h[0].type, MessageType::kPong);
  EXPECT_EQ(h[0].credits, 0u);
  EXPECT_EQ(h[0].ack, seq - 1);
}

TEST_F(EndpointFixture, GarbageIsCountedNeverTrusted) {
  hello(1);
  take();
  auto m = message(MessageType::kPing, {}, seq++);
  m[5] ^= std::byte{1};
  link::deliver(endpoint, m, app, out);
  link::deliver(endpoint, std::vector<std::byte>(3), app, out);
  Header h;
  h.type = static_cast<MessageType>(77);
  std::vector<std::byte> unknown(message_bytes(0));
  std::size_t w;
  ASSERT_EQ(encode_message(h, {}, unknown, w), Status::kOk);
  link::deliver(endpoint, unknown, app, out);
  seq = 10;  // a gap of messages
  deliver(MessageType::kStats, {});
  Stats s;
  Header hh;
  std::span<const std::byte> p;
  ASSERT_EQ(out.sent.size(), 1u);
  ASSERT_EQ(decode_message(out.sent[0], hh, p), Status::kOk);
  ASSERT_EQ(decode(p, s), Status::kOk);
  EXPECT_EQ(s.bad_crc + s.bad_message, 2u);
  EXPECT_EQ(s.unknown_type, 1u);
  EXPECT_GE(s.sequence_gaps, 8u);
}

TEST_F(EndpointFixture, AnInjectIsAnsweredUnsupportedByADutWithoutARigAndTheRigCanAnswerLater) {
  hello(1);
  take();
  std::byte b[kInjectBytes];
  deliver(MessageType::kInject, std::span(b, encode(Inject{42, 7}, b)));
  ASSERT_EQ(out.sent.size(), 1u);
  Header h;
  std::span<const std::byte> p;
  ASSERT_EQ(decode_message(out.sent[0], h, p), Status::kOk);
  EXPECT_EQ(h.type, MessageType::kInjected);
  Injected a;
  ASSERT_EQ(decode(p, a), Status::kOk);
  EXPECT_EQ(a.token, 42u);
  EXPECT_EQ(a.kind, 7u);
  EXPECT_EQ(a.outcome, InjectOutcome::kUnsupported);
  out.sent.clear();
  // A rig takes the request and answers when the fault is over.
  endpoint.on_message(message(MessageType::kInject, std::span(b, encode(Inject{43, 3}, b)), seq++), 0);
  Inject taken;
  ASSERT_TRUE(endpoint.take_inject(taken));
  Inject again;
  EXPECT_FALSE(endpoint.take_inject(again));
  EXPECT_EQ(endpoint.pending_inject(), nullptr);
  Injected later;
  later.token = taken.token;
  later.kind = taken.kind;
  later.outcome = InjectOutcome::kDetected;
  endpoint.report_injected(later);
  endpoint.report_event(EventKind::kRestart, EventReason::kBoot, 2, 5);
  flush();
  std::vector<Event> events;
  const auto hs = take(&events);
  ASSERT_EQ(hs.size(), 2u);
  EXPECT_EQ(hs[0].type, MessageType::kInjected);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, EventKind::kRestart);
  EXPECT_EQ(events[0].frame_id, kNoFrame);
}

TEST(Protocol, ANoteRoundTripsAndOnlyPrintableTextDecodes) {
  Note n;
  n.frame_id = 12;
  set_text(n.text, "gabarit-hil case=frame-000012 result=pass");
  std::byte b[kNoteBytes];
  ASSERT_EQ(encode(n, b), kNoteBytes);
  Note back;
  ASSERT_EQ(decode(std::span<const std::byte>(b, kNoteBytes), back), Status::kOk);
  EXPECT_EQ(back.frame_id, 12u);
  EXPECT_STREQ(back.text, n.text);
  EXPECT_EQ(decode(std::span<const std::byte>(b, kNoteBytes - 1), back), Status::kTruncated);
  // A console must never be sent control bytes: not in the text, nor after its end.
  b[4 + 3] = std::byte{'\r'};
  EXPECT_EQ(decode(std::span<const std::byte>(b, kNoteBytes), back), Status::kBadHeaderField);
  b[4 + 3] = std::byte{'i'};
  b[kNoteBytes - 5] = std::byte{'x'};  // text after the padding began
  EXPECT_EQ(decode(std::span<const std::byte>(b, kNoteBytes), back), Status::kBadHeaderField);
  b[kNoteBytes - 5] = std::byte{0};
  b[4 + 5] = std::byte{0x80};
  EXPECT_EQ(decode(std::span<const std::byte>(b, kNoteBytes), back), Status::kBadHeaderField);
}

TEST_F(EndpointFixture, ANoteReachesTheApplicationsConsoleAndIsNeverAnswered) {
  hello(1);
  take();
  Note n;
  set_text(n.text, "gabarit-hil: frames");
  std::byte b[kNoteBytes];
  deliver(MessageType::kNote, std::span(b, encode(n, b)));
  set_text(n.text, "gabarit-hil: run over");
  deliver(MessageType::kNote, std::span(b, encode(n, b)));
  EXPECT_TRUE(out.sent.empty());
  EXPECT_EQ(app.notes, (std::vector<std::string>{"gabarit-hil: frames", "gabarit-hil: run over"}));
  const std::size_t bytes = encode(n, b);
  b[4] = std::byte{0x07};  // a bell: refused and counted, never printed
  deliver(MessageType::kNote, std::span(b, bytes));
  EXPECT_EQ(app.notes.size(), 2u);
  Note none;
  EXPECT_FALSE(endpoint.take_note(none));
  EXPECT_EQ(endpoint.stats().bad_message, 1u);
}

}  // namespace
}  // namespace gabarit::link
