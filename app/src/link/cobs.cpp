#include "gabarit/link/cobs.hpp"

namespace gabarit::link {

Status cobs_encode(std::span<const std::byte> in, std::span<std::byte> out, std::size_t& written) noexcept {
  written = 0;
  if (out.size() < cobs_encoded_capacity(in.size())) return Status::kBufferTooSmall;
  std::size_t code_at = 0;  // where the current block's code byte goes
  std::size_t w = 1;
  std::uint8_t code = 1;
  for (const std::byte b : in) {
    if (b == std::byte{0}) {
      out[code_at] = std::byte{code};
      code_at = w++;
      code = 1;
      continue;
    }
    out[w++] = b;
    if (++code == 0xFF) {
      out[code_at] = std::byte{code};
      code_at = w++;
      code = 1;
    }
  }
  out[code_at] = std::byte{code};
  out[w++] = std::byte{0};
  written = w;
  return Status::kOk;
}

Status cobs_decode(std::span<const std::byte> in, std::span<std::byte> out, std::size_t& written) noexcept {
  written = 0;
  std::size_t r = 0;
  while (r < in.size()) {
    const auto code = static_cast<std::uint8_t>(in[r++]);
    if (code == 0) return Status::kBadHeaderField;
    const std::size_t data = code - 1u;
    if (data > in.size() - r) return Status::kBadHeaderField;
    if (data > out.size() - written) return Status::kBufferTooSmall;
    for (std::size_t i = 0; i < data; ++i) {
      if (in[r] == std::byte{0}) return Status::kBadHeaderField;
      out[written++] = in[r++];
    }
    if (code != 0xFF && r < in.size()) {
      if (written == out.size()) return Status::kBufferTooSmall;
      out[written++] = std::byte{0};
    }
  }
  return Status::kOk;
}

void CobsStreamDecoder::reset() noexcept {
  size_ = 0;
  block_left_ = 0;
  block_adds_zero_ = false;
  at_block_start_ = true;
  discarding_ = false;
  started_ = false;
}

CobsStreamDecoder::Event CobsStreamDecoder::push(std::byte byte) noexcept {
  if (byte == std::byte{0}) {
    // The delimiter: a run ends. Valid only at a block boundary.
    const bool had_bytes = started_;
    const bool valid = !discarding_ && block_left_ == 0 && had_bytes;
    const bool was_discarding = discarding_;
    const std::size_t size = size_;
    reset();
    if (valid) {
      message_size_ = size;
      return Event::kMessage;
    }
    if (had_bytes && !was_discarding) ++malformed_;  // a block cut short by the delimiter
    return had_bytes ? Event::kDiscarded : Event::kNone;
  }
  started_ = true;
  if (discarding_) return Event::kNone;
  if (at_block_start_) {
    // The zero the previous block implies, now known not to be the last.
    if (block_adds_zero_) {
      if (size_ == buffer_.size()) {
        ++overlong_;
        discarding_ = true;
        return Event::kNone;
      }
      buffer_[size_++] = std::byte{0};
    }
    const auto code = static_cast<std::uint8_t>(byte);
    block_left_ = static_cast<std::uint8_t>(code - 1u);
    block_adds_zero_ = code != 0xFF;
    at_block_start_ = block_left_ == 0;
    return Event::kNone;
  }
  if (size_ == buffer_.size()) {
    ++overlong_;
    discarding_ = true;
    return Event::kNone;
  }
  buffer_[size_++] = byte;
  at_block_start_ = --block_left_ == 0;
  return Event::kNone;
}

}  // namespace gabarit::link
