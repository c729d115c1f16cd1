// See vivid.hpp.
#include "vivid.hpp"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace gabarit::vivid {

namespace {

constexpr int kOsdTextModeNone = 2;
constexpr int kSvideoInput = 2;   // with vivid's default input_types 0xe4
constexpr int kSvideoOutput = 0;  // with vivid's default output_types 0x02

int xioctl(int fd, unsigned long request, void* arg) {
  int r;
  do r = ::ioctl(fd, request, arg);
  while (r < 0 && errno == EINTR);
  return r;
}

std::string errno_text(const std::string& what) { return what + ": " + std::strerror(errno); }

bool set_format(int fd, v4l2_buf_type type, std::uint32_t w, std::uint32_t h, const char* side, std::string& error) {
  v4l2_format f{};
  f.type = type;
  if (xioctl(fd, VIDIOC_G_FMT, &f) < 0) return error = errno_text(std::string("VIDIOC_G_FMT ") + side), false;
  f.fmt.pix.pixelformat = V4L2_PIX_FMT_GREY;
  f.fmt.pix.width = w;
  f.fmt.pix.height = h;
  f.fmt.pix.bytesperline = 0;
  if (xioctl(fd, VIDIOC_S_FMT, &f) < 0) return error = errno_text(std::string("VIDIOC_S_FMT ") + side), false;
  if (f.fmt.pix.pixelformat != V4L2_PIX_FMT_GREY || f.fmt.pix.width != w || f.fmt.pix.height != h) {
    error = std::string(side) + " refused GREY " + std::to_string(w) + "x" + std::to_string(h) + " (got " +
            std::to_string(f.fmt.pix.width) + "x" + std::to_string(f.fmt.pix.height) + ")";
    return false;
  }
  return true;
}

}  // namespace

bool set_control(int fd, const char* name, int value, std::string& error) {
  v4l2_query_ext_ctrl q{};
  q.id = V4L2_CTRL_FLAG_NEXT_CTRL | V4L2_CTRL_FLAG_NEXT_COMPOUND;
  while (xioctl(fd, VIDIOC_QUERY_EXT_CTRL, &q) == 0) {
    if (std::strncmp(q.name, name, sizeof q.name) == 0) {
      v4l2_control c{q.id, value};
      if (xioctl(fd, VIDIOC_S_CTRL, &c) < 0) return error = errno_text(std::string("setting '") + name + "'"), false;
      return true;
    }
    q.id |= V4L2_CTRL_FLAG_NEXT_CTRL | V4L2_CTRL_FLAG_NEXT_COMPOUND;
  }
  error = std::string("the device has no control '") + name + "'";
  return false;
}

bool set_control(const std::string& device, const char* name, int value, std::string& error) {
  const int fd = ::open(device.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) return error = errno_text("open " + device), false;
  const bool ok = set_control(fd, name, value, error);
  ::close(fd);
  return ok;
}

bool setup(const std::string& capture, const std::string& output, std::uint32_t width, std::uint32_t height, std::string& error) {
  const int cap = ::open(capture.c_str(), O_RDWR | O_CLOEXEC);
  if (cap < 0) return error = errno_text("open " + capture), false;
  const int out = ::open(output.c_str(), O_RDWR | O_CLOEXEC);
  if (out < 0) {
    error = errno_text("open " + output);
    ::close(cap);
    return false;
  }
  int input = kSvideoInput, output_index = kSvideoOutput;
  bool ok = true;
  if (xioctl(cap, VIDIOC_S_INPUT, &input) < 0) ok = false, error = errno_text("VIDIOC_S_INPUT");
  if (ok && xioctl(out, VIDIOC_S_OUTPUT, &output_index) < 0) ok = false, error = errno_text("VIDIOC_S_OUTPUT");
  ok = ok && set_format(cap, V4L2_BUF_TYPE_VIDEO_CAPTURE, width, height, "capture", error);
  ok = ok && set_format(out, V4L2_BUF_TYPE_VIDEO_OUTPUT, width, height, "output", error);
  ok = ok && set_control(cap, kOsdTextMode, kOsdTextModeNone, error);
  ok = ok && set_control(cap, kLoopVideo, 1, error);
  ::close(out);
  ::close(cap);
  return ok;
}

bool Output::open(const std::string& device, std::string& error) {
  close();
  fd_ = ::open(device.c_str(), O_RDWR | O_CLOEXEC);
  if (fd_ < 0) return error = errno_text("open " + device), false;
  v4l2_format f{};
  f.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
  if (xioctl(fd_, VIDIOC_G_FMT, &f) < 0) return error = errno_text("VIDIOC_G_FMT output"), close(), false;
  width_ = f.fmt.pix.width;
  height_ = f.fmt.pix.height;
  stride_ = f.fmt.pix.bytesperline;
  field_ = f.fmt.pix.field;
  v4l2_requestbuffers req{};
  req.count = 3;
  req.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
  req.memory = V4L2_MEMORY_MMAP;
  if (xioctl(fd_, VIDIOC_REQBUFS, &req) < 0 || req.count < 2) return error = errno_text("VIDIOC_REQBUFS output"), close(), false;
  for (std::uint32_t i = 0; i < req.count; ++i) {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = i;
    if (xioctl(fd_, VIDIOC_QUERYBUF, &b) < 0) return error = errno_text("VIDIOC_QUERYBUF output"), close(), false;
    void* p = ::mmap(nullptr, b.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, b.m.offset);
    if (p == MAP_FAILED) return error = errno_text("mmap output"), close(), false;
    maps_.emplace_back(static_cast<std::uint8_t*>(p), b.length);
  }
  return true;
}

void Output::close() {
  for (auto [p, n] : maps_) ::munmap(p, n);
  maps_.clear();
  if (fd_ >= 0) ::close(fd_);  // stops streaming
  fd_ = -1;
  streaming_ = false;
  queued_ = 0;
}

bool Output::show(const std::uint8_t* pixels, std::uint32_t width, std::uint32_t height, std::uint8_t background,
                  std::string& error) {
  if (fd_ < 0) return error = "the output device is not open", false;
  if (width > width_ || height > height_) {
    error = "a " + std::to_string(width) + "x" + std::to_string(height) + " frame does not fit vivid's " +
            std::to_string(width_) + "x" + std::to_string(height_);
    return false;
  }
  v4l2_buffer b{};
  b.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
  b.memory = V4L2_MEMORY_MMAP;
  if (queued_ < maps_.size()) {
    b.index = queued_;
  } else {
    pollfd p{fd_, POLLOUT, 0};
    if (::poll(&p, 1, 2000) <= 0) return error = "no free output buffer in 2 s", false;
    if ((p.revents & (POLLERR | POLLHUP)) != 0 && (p.revents & POLLOUT) == 0) return error = "the output device went away", false;
    if (xioctl(fd_, VIDIOC_DQBUF, &b) < 0) return error = errno_text("VIDIOC_DQBUF output"), false;
  }
  auto [data, length] = maps_[b.index];
  if (std::size_t{stride_} * height_ > length) return error = "output buffer too small", false;
  for (std::uint32_t y = 0; y < height_; ++y) {
    std::uint8_t* row = data + std::size_t{y} * stride_;
    if (y < height) {
      std::memcpy(row, pixels + std::size_t{y} * width, width);
      std::memset(row + width, background, width_ - width);
    } else {
      std::memset(row, background, width_);
    }
  }
  b.bytesused = stride_ * height_;
  b.field = field_;
  if (xioctl(fd_, VIDIOC_QBUF, &b) < 0) return error = errno_text("VIDIOC_QBUF output"), false;
  ++queued_;
  if (!streaming_) {
    v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
    if (xioctl(fd_, VIDIOC_STREAMON, &type) < 0) return error = errno_text("VIDIOC_STREAMON output"), false;
    streaming_ = true;
  }
  return true;
}

}  // namespace gabarit::vivid
