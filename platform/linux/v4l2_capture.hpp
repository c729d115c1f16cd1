// Frame capture from a V4L2 video-capture device with memory-mapped
// streaming I/O: format negotiation (GREY, YUYV or NV12; luma is used), a
// small ring of driver buffers, non-blocking dequeue for a poll() loop, and
// device loss reported as such so the caller can reopen.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "luma.hpp"

namespace gabarit::board {

struct CaptureOptions {
  std::string device = "/dev/video0";
  std::uint32_t pixel_format = 0;  // 0: the first of GREY, YUYV, NV12 the device offers
  std::uint32_t width = 0;         // 0: keep the device's current size
  std::uint32_t height = 0;
  std::uint32_t buffers = 4;
};

struct CapturedFrame {
  std::uint32_t index = 0;      // driver buffer, handed back with requeue()
  std::uint32_t sequence = 0;   // the driver's frame count
  std::uint64_t timestamp_us = 0;
  const std::uint8_t* data = nullptr;
  std::size_t bytes_used = 0;
};

enum class [[nodiscard]] CaptureEvent {
  kFrame,        // `frame` is valid until requeue(frame.index)
  kNoFrame,      // nothing ready yet (EAGAIN)
  kErrorFrame,   // the driver flagged a corrupted buffer; it has been requeued (only frame.sequence is set)
  kDeviceLost,   // the device is gone (unplugged, module unloaded): close and reopen
};

class V4l2Capture {
 public:
  V4l2Capture() = default;
  ~V4l2Capture() { close(); }
  V4l2Capture(const V4l2Capture&) = delete;
  V4l2Capture& operator=(const V4l2Capture&) = delete;

  // Opens, negotiates the format, maps the buffers and starts streaming.
  // On failure returns false with error() set and everything released.
  [[nodiscard]] bool open(const CaptureOptions& options);
  void close();
  bool is_open() const { return fd_ >= 0; }
  int fd() const { return fd_; }
  const FrameLayout& layout() const { return layout_; }
  const std::string& error() const { return error_; }

  // Call when poll() reports the fd readable (or to check once).
  CaptureEvent dequeue(CapturedFrame& frame);
  // Gives the buffer back to the driver. False (with error()) if the device is gone.
  [[nodiscard]] bool requeue(std::uint32_t index);

 private:
  bool fail(const std::string& what, int err);
  struct Mapping {
    void* address = nullptr;
    std::size_t length = 0;
  };
  int fd_ = -1;
  bool streaming_ = false;
  FrameLayout layout_;
  std::vector<Mapping> buffers_;
  std::string options_device_;
  std::string error_;
};

}  // namespace gabarit::board
