// Frames the driver dropped, from the sequence numbers of the buffers it
// returns (struct v4l2_buffer.sequence counts every frame the device
// produced, delivered or not).
#pragma once

#include <cstdint>

namespace gabarit::board {

class FrameCounter {
 public:
  // Records a delivered frame's sequence number; returns how many frames were
  // dropped just before it. A sequence that goes backwards (the device was
  // reopened or restarted streaming) starts a new run without counting drops.
  std::uint32_t delivered(std::uint32_t sequence) {
    std::uint32_t dropped_now = 0;
    if (started_ && sequence > last_) dropped_now = sequence - last_ - 1;
    started_ = true;
    last_ = sequence;
    ++delivered_;
    dropped_ += dropped_now;
    return dropped_now;
  }
  // After reopening the device its sequence restarts.
  void restart() { started_ = false; }
  std::uint64_t delivered_count() const { return delivered_; }
  std::uint64_t dropped_count() const { return dropped_; }

 private:
  bool started_ = false;
  std::uint32_t last_ = 0;
  std::uint64_t delivered_ = 0, dropped_ = 0;
};

}  // namespace gabarit::board
