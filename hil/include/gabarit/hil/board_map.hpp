// A real board's hardware map (hil/boards/NAME.yaml): how the harness
// reaches the board's HIL relay, and what the board side uses (its USB
// gadget's identity, GPIO chip and lines, camera, frame path). The format is
// a small YAML subset: "key: value" lines, two-space indentation for one
// level of nesting, '#' comments; unknown keys are errors (a typo must not
// pass silently). docs/hil-boards.md describes every key.
#pragma once

#include <cstdint>
#include <string>

namespace gabarit::hil {

struct BoardMap {
  std::string name, description;
  std::string relay;          // the relay's port as the host sees it: a serial device, or tcp:HOST:PORT
  std::uint32_t baud = 115200;  // for a serial relay port
  std::string usb;            // VID:PID[:SERIAL] of the board application's gadget
  std::string gpio_chip;
  int lock_line = -1, strobe_line = -1;
  std::string camera = "/dev/video0";
  std::string frame_path = "vivid";  // how recorded frames reach the camera: vivid (the only one for now)
  std::uint32_t hang_timeout_ms = 60000;
  std::string source;         // the file it came from
};

// "NAME" (hil/boards/NAME.yaml in the source tree) or a path to a .yaml file.
// Throws app::Error naming the file and line for anything wrong.
BoardMap load_board_map(const std::string& name_or_path, const std::string& boards_dir);
BoardMap parse_board_map(const std::string& text, const std::string& where);

}  // namespace gabarit::hil
