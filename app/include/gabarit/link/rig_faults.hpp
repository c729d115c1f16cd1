// The faults a DUT's rig injects on its own side of the link (INJECT's kind):
// the camera, the USB cable and the board's program. The virtual board's
// relay injects them all; hil/faults.hpp schedules them beside the faults the
// harness makes on its side of the link. docs/hil-protocol.md describes each.
#pragma once

#include <cstdint>

namespace gabarit::link {

enum class RigFault : std::uint8_t {
  kCameraError = 1,       // vivid flags a captured buffer V4L2_BUF_FLAG_ERROR
  kCameraDrop = 2,        // vivid drops captured buffers (a sequence gap)
  kSequenceWrap = 3,      // the capture's sequence number wraps past 2^32
  kCameraDisconnect = 4,  // vivid's Disconnect: the device goes away; its module is reloaded at once
  kModuleReload = 5,      // the camera's module unloaded, absent for a second, loaded again
  kUsbStall = 6,          // the board's IN endpoint halted (the host must clear it)
  kUsbUnplug = 7,         // the gadget unbound from its controller and bound again
  kUsbTimeout = 8,        // host transfers expire (1 ms timeouts) while the board answers
  kBoardKill = 9,         // the board's program killed (SIGKILL) and started again
  kUsbCorrupt = 10,       // a message to the board with a bit flipped after its CRC
};
inline constexpr std::uint8_t kRigFaultCount = 10;

inline const char* rig_fault_name(RigFault f) noexcept {
  switch (f) {
    case RigFault::kCameraError: return "camera-error";
    case RigFault::kCameraDrop: return "camera-drop";
    case RigFault::kSequenceWrap: return "sequence-wrap";
    case RigFault::kCameraDisconnect: return "camera-disconnect";
    case RigFault::kModuleReload: return "module-reload";
    case RigFault::kUsbStall: return "usb-stall";
    case RigFault::kUsbUnplug: return "usb-unplug";
    case RigFault::kUsbTimeout: return "usb-timeout";
    case RigFault::kBoardKill: return "board-kill";
    case RigFault::kUsbCorrupt: return "usb-corrupt";
  }
  return "unknown";
}

}  // namespace gabarit::link
