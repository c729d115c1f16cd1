// The fault scheduler: which frames the harness faults on the host side of
// the link, and how. A plan is read from a file or drawn from a seed; the
// plan a run used is written to its report (faults.csv), which replays it.
//
// File format, one fault per line, '#' starts a comment:
//   FRAME KIND        e.g. "120 drop"
// KIND: drop (the frame's messages are not sent), duplicate (sent twice),
// reorder (sent after the next frame's), corrupt (one byte of one
// fragment's payload changed after its CRC), bitflip (1 to 3 bits of one
// fragment flipped on the wire, framing included), restart (the DUT is
// restarted before the frame is sent).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace gabarit::hil {

enum class FaultKind : std::uint8_t {
  kDrop, kDuplicate, kReorder, kCorrupt, kBitflip, kRestart,
  // The rig's (link::RigFault, in the same order).
  kCameraError, kCameraDrop, kSequenceWrap, kCameraDisconnect, kModuleReload,
  kUsbStall, kUsbUnplug, kUsbTimeout, kBoardKill, kUsbCorrupt,
};
// The harness's own kinds: what random:P draws from.
inline constexpr FaultKind kAllFaultKinds[] = {FaultKind::kDrop,    FaultKind::kDuplicate, FaultKind::kReorder,
                                               FaultKind::kCorrupt, FaultKind::kBitflip,   FaultKind::kRestart};
inline constexpr FaultKind kRigFaultKinds[] = {
    FaultKind::kCameraError, FaultKind::kCameraDrop, FaultKind::kSequenceWrap, FaultKind::kCameraDisconnect,
    FaultKind::kModuleReload, FaultKind::kUsbStall, FaultKind::kUsbUnplug, FaultKind::kUsbTimeout,
    FaultKind::kBoardKill, FaultKind::kUsbCorrupt};
constexpr bool is_rig_fault(FaultKind kind) { return kind >= FaultKind::kCameraError; }
// INJECT's kind for a rig fault (link::RigFault's value).
constexpr std::uint8_t rig_fault_number(FaultKind kind) {
  return static_cast<std::uint8_t>(static_cast<std::uint8_t>(kind) - static_cast<std::uint8_t>(FaultKind::kCameraError) + 1);
}
const char* fault_name(FaultKind kind);
FaultKind parse_fault_kind(const std::string& text, const std::string& where);  // throws app::Error

struct PlannedFault {
  std::uint32_t frame = 0;
  FaultKind kind = FaultKind::kDrop;
};

// Sorted by frame, at most one fault per frame, no fault on the frame after
// a reorder (the two are swapped), no reorder on the last frame.
struct FaultPlan {
  std::vector<PlannedFault> faults;
  const PlannedFault* at(std::uint32_t frame) const;
};

// "FILE", "random:P" (0 <= P <= 1, per frame, the harness's kinds drawn
// uniformly) or "cycle:N:KIND,KIND,..." (one fault every N frames from frame
// N, the kinds in turn: every kind equally often) for `frames` frames;
// `seed` draws the random plan and each fault's bytes and bits.
FaultPlan parse_fault_plan(const std::string& spec, std::uint32_t frames, std::uint64_t seed);
FaultPlan cycle_fault_plan(std::uint32_t every, const std::vector<FaultKind>& kinds, std::uint32_t frames);
FaultPlan read_fault_file(const std::string& path, std::uint32_t frames);
FaultPlan random_fault_plan(double probability, std::uint32_t frames, std::uint64_t seed);
std::string fault_file_text(const FaultPlan& plan);  // the file format above

}  // namespace gabarit::hil
