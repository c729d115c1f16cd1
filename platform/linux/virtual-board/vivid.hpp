// vivid, the virtual board's camera: its set-up for Loop Video (frames
// written to its output device come back on its capture device byte for
// byte), its controls looked up by name (their IDs are private to the driver
// and move between kernel versions), and a writer for its output device.
// Shared by gabarit-vivid-feed and gabarit-hil-relay. Errors are returned
// as text, never thrown.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace gabarit::vivid {

// vivid's control names (drivers/media/test-drivers/vivid/vivid-ctrls.c).
inline constexpr const char* kLoopVideo = "Loop Video";
inline constexpr const char* kOsdTextMode = "OSD Text Mode";
inline constexpr const char* kDisconnect = "Disconnect";
inline constexpr const char* kDqbufError = "Inject V4L2_BUF_FLAG_ERROR";
inline constexpr const char* kDroppedPercent = "Percentage of Dropped Buffers";
inline constexpr const char* kWrapSequence = "Wrap Sequence Number";

// Sets the control called `name` on the device open as `fd`.
bool set_control(int fd, const char* name, int value, std::string& error);
// Opens `device`, sets the control, closes it.
bool set_control(const std::string& device, const char* name, int value, std::string& error);

// Selects the S-Video input and output, turns Loop Video on and the OSD
// text off, and sets GREY at width x height on both sides (vivid loops only
// between equal formats).
bool setup(const std::string& capture, const std::string& output, std::uint32_t width, std::uint32_t height, std::string& error);

// vivid's output device, streaming: show() queues a frame, which vivid then
// shows on its capture side until the next one is queued.
class Output {
 public:
  Output() = default;
  ~Output() { close(); }
  Output(const Output&) = delete;
  Output& operator=(const Output&) = delete;
  bool open(const std::string& device, std::string& error);
  void close();
  bool is_open() const { return fd_ >= 0; }
  std::uint32_t width() const { return width_; }
  std::uint32_t height() const { return height_; }
  // `pixels` is width x height, row-major; it goes to the top-left corner
  // of the output frame, whose other pixels stay `background`.
  bool show(const std::uint8_t* pixels, std::uint32_t width, std::uint32_t height, std::uint8_t background, std::string& error);

 private:
  int fd_ = -1;
  std::uint32_t width_ = 0, height_ = 0, stride_ = 0, field_ = 0, queued_ = 0;
  bool streaming_ = false;
  std::vector<std::pair<std::uint8_t*, std::size_t>> maps_;
};

}  // namespace gabarit::vivid
