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
#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <chrono>
#include <thread>
#include <vector>

#include "gabarit/app/args.hpp"
#include "gabarit/app/image_io.hpp"

namespace {

// vivid's private control IDs (drivers/media/test-drivers/vivid/vivid-ctrls.c).
constexpr std::uint32_t kVividCidLoopVideo = 0x00f0f025;
constexpr std::uint32_t kVividCidOsdTextMode = 0x00f0f001;
constexpr std::uint32_t kVividCidDisconnect = 0x00f0f041;
constexpr std::uint32_t kVividCidDqbufError = 0x00f0f042;  // the next buffer comes back flagged V4L2_BUF_FLAG_ERROR
constexpr int kOsdTextModeNone = 2;
constexpr int kSvideoInput = 2;  // with vivid's default input_types 0xe4
constexpr int kSvideoOutput = 0; // with vivid's default output_types 0x02

[[noreturn]] void die(const std::string& what) {
  throw std::runtime_error(what + (errno != 0 ? std::string(": ") + std::strerror(errno) : std::string()));
}

int xioctl(int fd, unsigned long request, void* arg) {
  int r;
  do r = ::ioctl(fd, request, arg);
  while (r < 0 && errno == EINTR);
  return r;
}

int open_device(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) die("open " + path);
  return fd;
}

void set_format(int fd, v4l2_buf_type type, std::uint32_t w, std::uint32_t h, const char* side) {
  v4l2_format f{};
  f.type = type;
  if (xioctl(fd, VIDIOC_G_FMT, &f) < 0) die(std::string("VIDIOC_G_FMT ") + side);
  f.fmt.pix.pixelformat = V4L2_PIX_FMT_GREY;
  f.fmt.pix.width = w;
  f.fmt.pix.height = h;
  f.fmt.pix.bytesperline = 0;
  if (xioctl(fd, VIDIOC_S_FMT, &f) < 0) die(std::string("VIDIOC_S_FMT ") + side);
  if (f.fmt.pix.pixelformat != V4L2_PIX_FMT_GREY || f.fmt.pix.width != w || f.fmt.pix.height != h) {
    errno = 0;
    die(std::string(side) + " refused GREY " + std::to_string(w) + "x" + std::to_string(h) + " (got " +
        std::to_string(f.fmt.pix.width) + "x" + std::to_string(f.fmt.pix.height) + ")");
  }
}

void set_control(int fd, std::uint32_t id, int value, const char* name) {
  v4l2_control c{id, value};
  if (xioctl(fd, VIDIOC_S_CTRL, &c) < 0) die(std::string("setting ") + name);
}

std::string option(const std::vector<std::string>& args, const std::string& name, const std::string& fallback) {
  for (std::size_t i = 0; i + 1 < args.size(); ++i)
    if (args[i] == name) return args[i + 1];
  if (fallback.empty()) {
    errno = 0;
    die("missing " + name);
  }
  return fallback;
}

void setup(const std::vector<std::string>& args) {
  std::uint32_t w = 0, h = 0;
  try {
    const gabarit::app::FrameSize size = gabarit::app::parse_size(option(args, "--size", ""), "--size", 8, 8192);
    w = size.width;
    h = size.height;
  } catch (const gabarit::app::Error& e) {
    errno = 0;
    die(e.what());
  }
  const int cap = open_device(option(args, "--capture", "/dev/video0"));
  const int out = open_device(option(args, "--output", "/dev/video1"));
  int input = kSvideoInput, output = kSvideoOutput;
  if (xioctl(cap, VIDIOC_S_INPUT, &input) < 0) die("VIDIOC_S_INPUT");
  if (xioctl(out, VIDIOC_S_OUTPUT, &output) < 0) die("VIDIOC_S_OUTPUT");
  set_format(cap, V4L2_BUF_TYPE_VIDEO_CAPTURE, w, h, "capture");
  set_format(out, V4L2_BUF_TYPE_VIDEO_OUTPUT, w, h, "output");
  set_control(cap, kVividCidOsdTextMode, kOsdTextModeNone, "OSD text mode");
  set_control(cap, kVividCidLoopVideo, 1, "loop video");
  ::close(out);
  ::close(cap);
}

void play(const std::vector<std::string>& args) {
  const int out = open_device(option(args, "--output", "/dev/video1"));
  const int hold_ms = std::stoi(option(args, "--hold-ms", "150"));
  const int first_hold_ms = std::stoi(option(args, "--first-hold-ms", std::to_string(hold_ms)));
  v4l2_format f{};
  f.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
  if (xioctl(out, VIDIOC_G_FMT, &f) < 0) die("VIDIOC_G_FMT output");
  v4l2_requestbuffers req{};
  req.count = 3;
  req.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
  req.memory = V4L2_MEMORY_MMAP;
  if (xioctl(out, VIDIOC_REQBUFS, &req) < 0 || req.count < 2) die("VIDIOC_REQBUFS output");
  std::vector<std::pair<std::uint8_t*, std::size_t>> maps;
  for (std::uint32_t i = 0; i < req.count; ++i) {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = i;
    if (xioctl(out, VIDIOC_QUERYBUF, &b) < 0) die("VIDIOC_QUERYBUF output");
    void* p = ::mmap(nullptr, b.length, PROT_READ | PROT_WRITE, MAP_SHARED, out, b.m.offset);
    if (p == MAP_FAILED) die("mmap output");
    maps.emplace_back(static_cast<std::uint8_t*>(p), b.length);
  }
  auto frames = gabarit::app::open_frames(option(args, "--frames", ""));
  gabarit::app::GrayImage frame;
  std::uint32_t count = 0;
  bool streaming = false;
  while (frames->next(frame)) {
    if (frame.width != f.fmt.pix.width || frame.height != f.fmt.pix.height) {
      errno = 0;
      die("frame size differs from the output format: run setup with the sequence's size");
    }
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
    b.memory = V4L2_MEMORY_MMAP;
    if (count < req.count) {
      b.index = count;
    } else {
      pollfd p{out, POLLOUT, 0};
      if (::poll(&p, 1, 5000) <= 0) die("waiting for a free output buffer");
      if (xioctl(out, VIDIOC_DQBUF, &b) < 0) die("VIDIOC_DQBUF output");
    }
    auto [data, length] = maps[b.index];
    const std::size_t stride = f.fmt.pix.bytesperline;
    if (stride * frame.height > length) die("output buffer too small");
    for (std::uint32_t y = 0; y < frame.height; ++y) std::memcpy(data + y * stride, &frame.pixels[std::size_t{y} * frame.width], frame.width);
    b.bytesused = static_cast<std::uint32_t>(stride * frame.height);
    b.field = f.fmt.pix.field;
    if (xioctl(out, VIDIOC_QBUF, &b) < 0) die("VIDIOC_QBUF output");
    if (!streaming) {
      v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
      if (xioctl(out, VIDIOC_STREAMON, &type) < 0) die("VIDIOC_STREAMON output");
      streaming = true;
    }
    ++count;
    std::this_thread::sleep_for(std::chrono::milliseconds(count == 1 ? first_hold_ms : hold_ms));
  }
  std::fprintf(stderr, "gabarit-vivid-feed: played %u frames\n", count);
  ::close(out);  // stops streaming
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
    else if (args[0] == "error") {
      const int cap = open_device(option(args, "--capture", "/dev/video0"));
      set_control(cap, kVividCidDqbufError, 1, "buffer error injection");
      ::close(cap);
    } else if (args[0] == "disconnect") {
      const int cap = open_device(option(args, "--capture", "/dev/video0"));
      set_control(cap, kVividCidDisconnect, 1, "disconnect");
      ::close(cap);
    }
    else throw std::runtime_error("unknown command " + args[0]);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gabarit-vivid-feed: %s\n", e.what());
    return 1;
  }
}
