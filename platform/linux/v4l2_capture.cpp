#include "v4l2_capture.hpp"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace gabarit::board {
namespace {

static_assert(kFourccGrey == V4L2_PIX_FMT_GREY && kFourccYuyv == V4L2_PIX_FMT_YUYV && kFourccNv12 == V4L2_PIX_FMT_NV12);

// ioctl, retried when a signal interrupts it.
int xioctl(int fd, unsigned long request, void* arg) {
  int r;
  do r = ::ioctl(fd, request, arg);
  while (r < 0 && errno == EINTR);
  return r;
}


}  // namespace

bool V4l2Capture::fail(const std::string& what, int err) {
  error_ = options_device_ + ": " + what + (err != 0 ? std::string(": ") + std::strerror(err) : std::string());
  close();
  return false;
}

bool V4l2Capture::open(const CaptureOptions& options) {
  close();
  options_device_ = options.device;
  fd_ = ::open(options.device.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) return fail("cannot open", errno);

  v4l2_capability cap{};
  if (xioctl(fd_, VIDIOC_QUERYCAP, &cap) < 0) return fail("not a V4L2 device (VIDIOC_QUERYCAP)", errno);
  const std::uint32_t caps = (cap.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? cap.device_caps : cap.capabilities;
  if ((caps & V4L2_CAP_VIDEO_CAPTURE) == 0)
    return fail("not a single-planar video capture device (multi-planar devices are not supported)", 0);
  if ((caps & V4L2_CAP_STREAMING) == 0) return fail("no streaming I/O", 0);

  // The format: the one asked for, else the first luma-friendly one offered.
  std::uint32_t chosen = options.pixel_format;
  if (chosen == 0) {
    bool offered[3] = {false, false, false};
    const std::uint32_t preference[3] = {kFourccGrey, kFourccYuyv, kFourccNv12};
    for (std::uint32_t i = 0;; ++i) {
      v4l2_fmtdesc desc{};
      desc.index = i;
      desc.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      if (xioctl(fd_, VIDIOC_ENUM_FMT, &desc) < 0) break;
      for (int k = 0; k < 3; ++k) offered[k] = offered[k] || desc.pixelformat == preference[k];
    }
    for (int k = 2; k >= 0; --k)
      if (offered[k]) chosen = preference[k];
    if (chosen == 0) return fail("offers none of GREY, YUYV, NV12", 0);
  }
  v4l2_format fmt{};
  fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(fd_, VIDIOC_G_FMT, &fmt) < 0) return fail("VIDIOC_G_FMT", errno);
  fmt.fmt.pix.pixelformat = chosen;
  if (options.width != 0) fmt.fmt.pix.width = options.width;
  if (options.height != 0) fmt.fmt.pix.height = options.height;
  fmt.fmt.pix.field = V4L2_FIELD_NONE;
  fmt.fmt.pix.bytesperline = 0;  // let the driver choose its stride
  if (xioctl(fd_, VIDIOC_S_FMT, &fmt) < 0) return fail("VIDIOC_S_FMT", errno);
  if (fmt.fmt.pix.pixelformat != chosen)
    return fail(std::string("does not accept pixel format ") + fourcc_text(chosen).text + " (it chose " +
                    fourcc_text(fmt.fmt.pix.pixelformat).text + ")",
                0);
  layout_ = {fmt.fmt.pix.pixelformat, fmt.fmt.pix.width, fmt.fmt.pix.height, fmt.fmt.pix.bytesperline};
  if (layout_.bytes_per_line == 0) layout_.bytes_per_line = layout_.width * (chosen == kFourccYuyv ? 2 : 1);
  if (frame_bytes(layout_) == 0 || layout_.width == 0 || layout_.height == 0) return fail("unusable frame layout", 0);

  v4l2_requestbuffers req{};
  req.count = options.buffers;
  req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  req.memory = V4L2_MEMORY_MMAP;
  if (xioctl(fd_, VIDIOC_REQBUFS, &req) < 0) return fail("VIDIOC_REQBUFS (memory-mapped streaming)", errno);
  if (req.count < 2) return fail("too few capture buffers", 0);
  buffers_.resize(req.count);
  for (std::uint32_t i = 0; i < req.count; ++i) {
    v4l2_buffer buf{};
    buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buf.memory = V4L2_MEMORY_MMAP;
    buf.index = i;
    if (xioctl(fd_, VIDIOC_QUERYBUF, &buf) < 0) return fail("VIDIOC_QUERYBUF", errno);
    void* address = ::mmap(nullptr, buf.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, buf.m.offset);
    if (address == MAP_FAILED) return fail("mmap", errno);
    buffers_[i] = {address, buf.length};
    if (xioctl(fd_, VIDIOC_QBUF, &buf) < 0) return fail("VIDIOC_QBUF", errno);
  }
  v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(fd_, VIDIOC_STREAMON, &type) < 0) return fail("VIDIOC_STREAMON", errno);
  streaming_ = true;
  error_.clear();
  return true;
}

void V4l2Capture::close() {
  if (fd_ >= 0 && streaming_) {
    v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    (void)xioctl(fd_, VIDIOC_STREAMOFF, &type);  // may fail on a device already gone; nothing to do then
  }
  streaming_ = false;
  for (const Mapping& m : buffers_)
    if (m.address != nullptr) ::munmap(m.address, m.length);
  buffers_.clear();
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

CaptureEvent V4l2Capture::dequeue(CapturedFrame& frame) {
  v4l2_buffer buf{};
  buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buf.memory = V4L2_MEMORY_MMAP;
  if (xioctl(fd_, VIDIOC_DQBUF, &buf) < 0) {
    if (errno == EAGAIN) return CaptureEvent::kNoFrame;
    error_ = options_device_ + ": VIDIOC_DQBUF: " + std::strerror(errno);
    return CaptureEvent::kDeviceLost;  // ENODEV after an unplug; any other failure here leaves the stream unusable too
  }
  if (buf.index >= buffers_.size() || buf.bytesused > buffers_[buf.index].length) {
    error_ = options_device_ + ": driver returned an out-of-range buffer";
    return CaptureEvent::kDeviceLost;
  }
  if ((buf.flags & V4L2_BUF_FLAG_ERROR) != 0) {
    frame.sequence = buf.sequence;  // still a frame of the sequence: not a drop
    frame.data = nullptr;
    if (!requeue(buf.index)) return CaptureEvent::kDeviceLost;
    return CaptureEvent::kErrorFrame;
  }
  frame.index = buf.index;
  frame.sequence = buf.sequence;
  frame.timestamp_us = static_cast<std::uint64_t>(buf.timestamp.tv_sec) * 1000000u + static_cast<std::uint64_t>(buf.timestamp.tv_usec);
  frame.data = static_cast<const std::uint8_t*>(buffers_[buf.index].address);
  frame.bytes_used = buf.bytesused;
  return CaptureEvent::kFrame;
}

bool V4l2Capture::requeue(std::uint32_t index) {
  v4l2_buffer buf{};
  buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buf.memory = V4L2_MEMORY_MMAP;
  buf.index = index;
  if (xioctl(fd_, VIDIOC_QBUF, &buf) < 0) {
    error_ = options_device_ + ": VIDIOC_QBUF: " + std::strerror(errno);
    return false;
  }
  return true;
}

}  // namespace gabarit::board
