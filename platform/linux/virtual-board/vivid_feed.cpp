// gabarit-vivid-feed — plays a recorded sequence into the virtual board's
// camera. vivid's "Loop Video" control hands every frame written to its video
// output back on its capture device, byte for byte, so the board application
// captures the recording through the real V4L2 stack.
//
//   gabarit-vivid-feed setup --capture /dev/video0 --output /dev/video1 --size WxH
//       selects vivid's S-Video input and output, loop video on, OSD text off,
//       GREY at WxH on both sides (vivid loops only between equal formats)
//   gabarit-vivid-feed play --output /dev/video1 --frames SEQ.y4m [--hold-ms MS] [--first-hold-ms MS]
//       queues each frame and keeps it on the output for MS (default 150); the
//       first frame for --first-hold-ms (default MS), so a capture started
//       meanwhile begins on the recording's first frame
//   gabarit-vivid-feed disconnect --capture /dev/video0
//       vivid's Disconnect control: its device nodes go away as in an unplug
//   gabarit-vivid-feed error --capture /dev/video0
//       vivid's error injection: the next captured buffer is flagged
//       V4L2_BUF_FLAG_ERROR
//
// vivid keeps showing the last queued output buffer until another is queued,
// so a capture sees each frame one or more times; the test maps captured
// frames back to the recording by their CRC (gabarit-board --frame-crc).
#include <cstdio>
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "gabarit/app/args.hpp"
#include "gabarit/app/image_io.hpp"
#include "vivid.hpp"

namespace {

namespace vivid = gabarit::vivid;

std::string option(const std::vector<std::string>& args, const std::string& name, const std::string& fallback) {
  for (std::size_t i = 0; i + 1 < args.size(); ++i)
    if (args[i] == name) return args[i + 1];
  if (fallback.empty()) throw std::runtime_error("missing " + name);
  return fallback;
}

void check(bool ok, const std::string& error) {
  if (!ok) throw std::runtime_error(error);
}

void setup(const std::vector<std::string>& args) {
  const gabarit::app::FrameSize size = gabarit::app::parse_size(option(args, "--size", ""), "--size", 8, 8192);
  std::string error;
  check(vivid::setup(option(args, "--capture", "/dev/video0"), option(args, "--output", "/dev/video1"), size.width,
                     size.height, error),
        error);
}

void play(const std::vector<std::string>& args) {
  const int hold_ms = std::stoi(option(args, "--hold-ms", "150"));
  const int first_hold_ms = std::stoi(option(args, "--first-hold-ms", std::to_string(hold_ms)));
  vivid::Output out;
  std::string error;
  check(out.open(option(args, "--output", "/dev/video1"), error), error);
  auto frames = gabarit::app::open_frames(option(args, "--frames", ""));
  gabarit::app::GrayImage frame;
  std::uint32_t count = 0;
  while (frames->next(frame)) {
    if (frame.width != out.width() || frame.height != out.height())
      throw std::runtime_error("frame size differs from the output format: run setup with the sequence's size");
    check(out.show(frame.pixels.data(), frame.width, frame.height, 0, error), error);
    ++count;
    std::this_thread::sleep_for(std::chrono::milliseconds(count == 1 ? first_hold_ms : hold_ms));
  }
  std::fprintf(stderr, "gabarit-vivid-feed: played %u frames\n", count);
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  try {
    if (args.empty() || args[0] == "--help") {
      std::fputs("usage: gabarit-vivid-feed setup --capture DEV --output DEV --size WxH\n"
                 "       gabarit-vivid-feed play --output DEV --frames SEQ.y4m [--hold-ms MS] [--first-hold-ms MS]\n"
                 "       gabarit-vivid-feed disconnect --capture DEV\n"
                 "       gabarit-vivid-feed error --capture DEV\n",
                 args.empty() ? stderr : stdout);
      return args.empty() ? 2 : 0;
    }
    if (args[0] == "setup") setup(args);
    else if (args[0] == "play") play(args);
    else if (args[0] == "error" || args[0] == "disconnect") {
      std::string error;
      check(vivid::set_control(option(args, "--capture", "/dev/video0"), args[0] == "error" ? vivid::kDqbufError : vivid::kDisconnect,
                               1, error),
            error);
    }
    else throw std::runtime_error("unknown command " + args[0]);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gabarit-vivid-feed: %s\n", e.what());
    return 1;
  }
}
