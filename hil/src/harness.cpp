#include "run.hpp"

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
namespace gabarit::hil {

const char* fate_name(Fate fate) {
  switch (fate) {
    case Fate::kPending: return "pending";
    case Fate::kPose: return "pose";
    case Fate::kDroppedByLink: return "dropped-by-link";
    case Fate::kDroppedByDut: return "dropped-by-dut";
    case Fate::kSkippedByDut: return "skipped-by-dut";
    case Fate::kDutError: return "dut-error";
    case Fate::kLostInRestart: return "lost-in-restart";
    case Fate::kNotSent: return "not-sent";
  }
  return "unknown";
}

LatencySummary summarise(std::vector<double> v) {
  LatencySummary s;
  s.samples = v.size();
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  const auto rank = [&](double q) {
    const auto r = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
    return v[std::clamp<std::size_t>(r, 1, v.size()) - 1];
  };
  s.p50 = rank(0.5);
  s.p99 = rank(0.99);
  s.max = v.back();
  double sum = 0;
  for (double x : v) sum += x;
  s.mean = sum / static_cast<double>(v.size());
  return s;
}

namespace detail {

std::uint64_t resident_kib() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::strtoull(line.c_str() + 6, nullptr, 10);
  return 0;
}

void Run::sample_soak(std::uint32_t frames_sent) {
  stats_received_ = false;
  send(encode(MessageType::kStats, {}));
  pump(Clock::now() + std::chrono::seconds(5), [&] { return stats_received_; });
  std::vector<double> latency;
  for (std::uint32_t i = soak_from_; i < frames_sent && i < result_.frames.size(); ++i)
    if (result_.frames[i].latency_us >= 0) latency.push_back(result_.frames[i].latency_us);
  const LatencySummary l = summarise(latency);
  SoakSample s;
  s.frames = frames_sent;
  s.seconds = since_start_us() / 1e6;
  s.host_rss_kib = resident_kib();
  s.dut_rss_kib = result_.dut_stats ? result_.dut_stats->resident_kib : 0;
  s.latency_p50_us = l.p50;
  s.latency_p99_us = l.p99;
  result_.soak.push_back(s);
  soak_from_ = frames_sent;
}

void Run::send_frame(std::uint32_t index, const app::GrayImage& image, const PlannedFault* fault) {
  const auto start = Clock::now();
  FrameRecord& record = result_.frames[index];
  const std::size_t total = image.pixels.size();
  const std::size_t per_message = link::frame_fragment_pixels(max_payload_);
  std::vector<std::vector<std::byte>> messages;
  std::vector<std::byte> payload(max_payload_);
  const auto host_time = static_cast<std::uint64_t>(since_start_us());
  for (std::size_t at = 0; at < total; at += per_message) {
    const std::size_t n = std::min(per_message, total - at);
    const link::FrameFragment f{index, host_time, static_cast<std::uint16_t>(image.width), static_cast<std::uint16_t>(image.height),
                                static_cast<std::uint32_t>(at), static_cast<std::uint32_t>(total),
                                std::as_bytes(std::span(image.pixels).subspan(at, n))};
    messages.push_back(encode(MessageType::kFrame, std::span(payload.data(), link::encode(f, payload))));
  }
  codec_seconds_ += std::chrono::duration<double>(Clock::now() - start).count();
  record.sent_us = since_start_us();
  record.run = run_id_ - 1;
  outstanding_.insert(index);
  newest_sent_ = index;
  result_.pixel_bytes_sent += total;
  record.pixel_bytes = static_cast<std::uint32_t>(total);
  const std::uint64_t before = wire().bytes_sent();
  std::size_t flip_message = messages.size();
  std::vector<std::uint64_t> flip_positions;
  if (fault != nullptr) {
    InjectedFault& injected = result_.faults[static_cast<std::size_t>(record.fault)];
    const auto pick = static_cast<std::size_t>(rng_.next_u64() % messages.size());
    switch (fault->kind) {
      case FaultKind::kDrop: injected.detail = "none of its " + std::to_string(messages.size()) + " messages sent"; break;
      case FaultKind::kDuplicate: injected.detail = "its " + std::to_string(messages.size()) + " messages sent twice"; break;
      case FaultKind::kReorder: injected.detail = "sent after frame " + std::to_string(index + 1); break;
      case FaultKind::kCorrupt: {
        auto& m = messages[pick];
        const std::size_t at = link::kHeaderBytes + rng_.next_u64() % (m.size() - link::kHeaderBytes - link::kTrailerBytes);
        const auto x = static_cast<std::uint8_t>(1 + rng_.next_u64() % 255);
        m[at] ^= std::byte{x};
        injected.detail = "message " + std::to_string(pick) + " of " + std::to_string(messages.size()) + ": byte " +
                          std::to_string(at) + " xor " + std::to_string(x);
        break;
      }
      case FaultKind::kBitflip: {
        flip_message = pick;
        const std::size_t bits = 1 + rng_.next_u64() % 3;
        std::vector<std::uint64_t> positions;
        const std::uint64_t span = wire().wire_size(messages[pick]) * 8;
        injected.detail = "message " + std::to_string(pick) + " of " + std::to_string(messages.size()) + ": wire bits";
        for (std::size_t i = 0; i < bits; ++i) {
          positions.push_back(rng_.next_u64() % span);
          injected.detail += " " + std::to_string(positions.back());
        }
        flip_positions = positions;  // armed just before that message goes, below
        break;
      }
      case FaultKind::kRestart: injected.detail = "the DUT stopped and started again before the frame"; break;
      default: break;  // a rig fault: done before the frame (inject)
    }
  }
  const bool drop = fault != nullptr && fault->kind == FaultKind::kDrop;
  const bool reorder = fault != nullptr && fault->kind == FaultKind::kReorder;
  std::vector<std::vector<std::byte>> held_before = std::move(held_);
  held_.clear();
  const std::uint32_t held_before_frame = held_frame_;
  held_frame_ = link::kNoFrame;
  if (reorder) {
    held_ = std::move(messages);
    held_frame_ = index;
  } else if (!drop) {
    const int copies = fault != nullptr && fault->kind == FaultKind::kDuplicate ? 2 : 1;
    for (int c = 0; c < copies; ++c) {
      for (std::size_t i = 0; i < messages.size(); ++i) {
        if (i == flip_message && c == 0) wire().flip_bits_on_next_send(flip_positions);
        send(messages[i]);
      }
    }
  }
  record.wire_bytes += wire().bytes_sent() - before;
  // A frame held back by a reorder goes after this one.
  if (!held_before.empty()) {
    const std::uint64_t held_start = wire().bytes_sent();
    for (const auto& m : held_before) send(m);
    result_.frames[held_before_frame].wire_bytes += wire().bytes_sent() - held_start;
  }
}

void Run::judge_faults() {
  const auto clean_pose_after = [&](std::uint32_t after) -> std::string {
    for (std::uint32_t j = after + 1; j < result_.frames.size(); ++j) {
      const FrameRecord& r = result_.frames[j];
      // Frames of other faults, frames never sent, and frames a planned
      // restart took are not evidence either way.
      const bool planned_loss = r.fate == Fate::kLostInRestart && r.reason.rfind("a planned restart", 0) == 0;
      if (r.fault >= 0 || r.fate == Fate::kNotSent || r.sent_us < 0 || planned_loss) continue;
      if (r.fate == Fate::kPose && r.reference == 1) return "";
      return "frame " + std::to_string(j) + ", the next unfaulted one: " + fate_name(r.fate) +
             (r.fate == Fate::kPose ? " not matching the reference" : "");
    }
    return "";  // no later frame to judge by
  };
  for (InjectedFault& f : result_.faults) {
    const FrameRecord& r = result_.frames[f.frame];
    const std::string fate = std::string(fate_name(r.fate)) + (r.reason.empty() ? "" : " (" + r.reason + ")");
    std::uint32_t last_affected = f.frame;
    switch (f.kind) {
      case FaultKind::kDrop:
      case FaultKind::kCorrupt:
      case FaultKind::kBitflip:
        f.detected = r.fate == Fate::kDroppedByLink || r.fate == Fate::kDroppedByDut || r.fate == Fate::kLostInRestart;
        f.evidence = "frame " + std::to_string(f.frame) + ": " + fate;
        // Bits flipped on a delimiter can take the next message with them.
        if (f.kind == FaultKind::kBitflip) last_affected = f.frame + 1;
        break;
      case FaultKind::kDuplicate:
        // A restart that took the frame before it was answered leaves nothing to tell.
        f.detected = (r.repeats >= 1 && r.fate == Fate::kPose) || r.fate == Fate::kLostInRestart;
        f.evidence = "frame " + std::to_string(f.frame) + ": " + fate + ", the DUT reported " + std::to_string(r.repeats) +
                     " repeat(s) and answered it once";
        break;
      case FaultKind::kReorder: {
        const FrameRecord& next = result_.frames[f.frame + 1];
        f.detected = r.fate == Fate::kSkippedByDut && next.fate == Fate::kPose;
        f.evidence = "frame " + std::to_string(f.frame) + ": " + fate + "; frame " + std::to_string(f.frame + 1) + ": " + fate_name(next.fate);
        last_affected = f.frame + 1;
        break;
      }
      case FaultKind::kCameraError:
      case FaultKind::kCameraDrop:
      case FaultKind::kSequenceWrap:
      case FaultKind::kCameraDisconnect:
      case FaultKind::kModuleReload:
      case FaultKind::kUsbStall:
      case FaultKind::kUsbUnplug:
      case FaultKind::kUsbTimeout:
      case FaultKind::kBoardKill:
      case FaultKind::kUsbCorrupt: {
        // The rig's own checks detected it (INJECTED); tracking again means a
        // pose matching the reference after the fault's end, within 1 s.
        if (!f.answered) f.evidence = f.evidence.empty() ? "the rig never answered" : f.evidence;
        last_affected = f.frame > 0 ? f.frame - 1 : 0;
        const std::string problem = clean_pose_after(last_affected);
        double first = -1;
        for (const FrameRecord& p : result_.frames)
          if (p.fate == Fate::kPose && p.reference == 1 && f.ended_us >= 0 && p.sent_us + p.latency_us >= f.ended_us) {
            const double at = p.sent_us + p.latency_us;
            if (first < 0 || at < first) first = at;
          }
        if (first >= 0) f.recovery_ms = (first - f.ended_us) / 1000.0;
        f.recovered = problem.empty() && f.answered && f.recovery_ms >= 0 && f.recovery_ms <= 1000.0;
        if (!problem.empty()) f.evidence += "; not recovered: " + problem;
        else if (f.recovery_ms > 1000.0) f.evidence += "; tracking again only after " + std::to_string(f.recovery_ms) + " ms";
        else if (f.recovery_ms >= 0) f.evidence += "; tracking again " + std::to_string(static_cast<int>(f.recovery_ms)) + " ms after";
        continue;
      }
      case FaultKind::kRestart:
        f.detected = r.run > 0;  // the DUT came back with a new run
        f.evidence = "the DUT restarted before frame " + std::to_string(f.frame) + " (run " + std::to_string(r.run) + "); frame " +
                     std::to_string(f.frame) + ": " + fate;
        last_affected = f.frame > 0 ? f.frame - 1 : 0;
        if (f.frame == 0) {
          f.recovered = r.fate == Fate::kPose && r.reference == 1;
          continue;
        }
        break;
    }
    const std::string problem = clean_pose_after(last_affected);
    f.recovered = problem.empty();
    if (!problem.empty()) f.evidence += "; not recovered: " + problem;
  }
}

void Run::execute() {
  const std::filesystem::path dir(config_.sequence_dir);
  const std::string frames_path = (dir / "frames.y4m").string();
  auto frames = app::open_frames(frames_path);
  Pose initial;
  if (config_.init) {
    initial = *config_.init;
  } else {
    const std::string gt = (dir / "gt.csv").string();
    if (!std::filesystem::exists(gt)) throw app::Error(config_.sequence_dir + ": no gt.csv to start from; give --init");
    const auto truth = app::read_pose_csv(gt);
    if (truth.empty()) throw app::Error(gt + ": no ground-truth rows to start from; give --init");
    initial = Pose{static_cast<float>(truth[0].x), static_cast<float>(truth[0].y), static_cast<float>(truth[0].theta_deg),
                   static_cast<std::uint16_t>(truth[0].depth)};
  }
  last_pose_ = initial;
  const std::uint32_t per_loop = config_.max_frames;
  const std::uint64_t total64 = std::uint64_t{per_loop} * std::max<std::uint32_t>(config_.loops, 1);
  if (total64 > 0xFFFFFFFEull) throw app::Error("--soak: too many frames in all");
  const auto total = static_cast<std::uint32_t>(total64);
  result_.frames_total = total;
  result_.frames.resize(total);
  for (std::uint32_t i = 0; i < total; ++i) result_.frames[i].frame = i;
  for (const PlannedFault& f : config_.faults.faults) {
    if (f.frame >= total) continue;
    result_.frames[f.frame].fault = static_cast<int>(result_.faults.size());
    result_.faults.push_back({f.frame, f.kind, "", false, false, ""});
  }
  try {
    dut_.start();
  } catch (const app::Error& e) {
    throw RunAborted{std::string("the DUT did not start: ") + e.what()};
  }
  result_.dut_description = dut_.description();
  t0_ = Clock::now();
  handshake(initial, 0);
  if (!config_.console_opening.empty()) notes_.emplace_back(link::kNoFrame, config_.console_opening);
  opened_ = true;
  auto last_progress = Clock::now();
  app::GrayImage image;
  const bool soak = config_.loops > 1;
  for (std::uint32_t k = 0; k < total; ++k) {
    if (k > 0 && k % per_loop == 0) frames = app::open_frames(frames_path);  // the next loop of a soak
    if (!frames->next(image)) throw RunAborted{frames_path + ": ended at frame " + std::to_string(k % per_loop)};
    if (soak && k > 0 && k % config_.soak_window == 0) sample_soak(k);
    if (image.width > 0xFFFF || image.height > 0xFFFF || image.pixels.size() > caps_.max_frame_bytes)
      throw RunAborted{"frame " + std::to_string(k) + " is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                       "; the DUT takes frames of at most " + std::to_string(caps_.max_frame_bytes) + " pixels"};
    const PlannedFault* fault = config_.faults.at(k);
    if (fault != nullptr && fault->kind == FaultKind::kRestart) {
      next_frame_ = k;
      restart(RestartCause::kPlanned, "a planned restart before frame " + std::to_string(k));
    }
    next_frame_ = k;
    const auto room = [&] { return outstanding_.size() - (held_.empty() ? 0 : 1) < window_; };
    if (config_.rate_fps > 0) {
      const auto due = t0_ + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(k / config_.rate_fps));
      pump(due, [] { return false; });
      if (!room()) {
        result_.frames[k].fate = Fate::kNotSent;
        result_.frames[k].reason = "the DUT was busy at the frame's time";
        if (config_.on_resolved) config_.on_resolved(result_.frames[k]);
        if (config_.console_frame_line) notes_.emplace_back(k, config_.console_frame_line(result_.frames[k]));
        continue;
      }
    } else {
      pump(Clock::time_point::max(), room);
    }
    next_frame_ = k;
    if (fault != nullptr && is_rig_fault(fault->kind)) inject(k, *fault);
    next_frame_ = k;
    send_notes();
    send_frame(k, image, fault);
    images_[k] = std::move(image);
    image = app::GrayImage{};
    pump(Clock::now(), [] { return false; });
    if (config_.progress && Clock::now() - last_progress >= std::chrono::seconds(1)) {
      config_.progress(k + 1 - static_cast<std::uint32_t>(outstanding_.size()), total);
      last_progress = Clock::now();
    }
  }
  next_frame_ = total;
  if (!held_.empty()) {  // cannot happen (no reorder on the last frame), but never leave one unsent
    for (const auto& m : held_) send(m);
    held_.clear();
    held_frame_ = link::kNoFrame;
  }
  pump(Clock::time_point::max(), [&] { return outstanding_.empty(); });
  // Rig faults that end on their own time (a sequence wrap) answer by now.
  pump(Clock::now() + dut_.hang_timeout(), [&] {
    for (const InjectedFault& f : result_.faults)
      if (is_rig_fault(f.kind) && !f.answered && result_.frames[f.frame].sent_us >= 0) return false;
    return true;
  });
  send_notes();
  if (soak) sample_soak(total);
  // The DUT's counters, then goodbye; neither is worth waiting long for.
  send(encode(MessageType::kStats, {}));
  pump(Clock::now() + std::chrono::seconds(5), [&] { return stats_received_; });
  std::byte b[link::kByeBytes];
  send(encode(MessageType::kBye, std::span(b, link::encode(link::Bye{0, total - 1}, b))));
  pump(Clock::now() + std::chrono::seconds(5), [&] { return bye_received_; });
  if (config_.progress) config_.progress(total, total);
  result_.host_codec_seconds = codec_seconds_ + wire().framing_seconds();
}

}  // namespace detail

RunResult run_hil(const RunConfig& config, DutDriver& dut) {
  RunResult result;
  const auto start = Clock::now();
  detail::Run run(config, dut, result);
  try {
    run.execute();
  } catch (const detail::RunAborted& a) {
    result.error = a.why;
  }
  run.judge_faults();
  for (const FrameRecord& r : result.frames)
    if (r.fate == Fate::kPending && r.sent_us >= 0) ++result.unaccounted;
  for (const FrameRecord& r : result.frames) result.wire_bytes += r.wire_bytes;
  if (config.console_closing) run.send_closing_notes(config.console_closing(result));
  dut.stop();
  result.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return result;
}

}  // namespace gabarit::hil

