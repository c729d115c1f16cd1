// Consistent Overhead Byte Stuffing (Cheshire and Baker, 1999): a message
// becomes a run of non-zero bytes, and a zero byte ends it, so a receiver that
// joins a byte stream mid-message, or loses bytes to noise, finds the next
// message at the next zero. The HIL link frames byte streams (UART, sockets,
// virtio-serial) this way (docs/hil-protocol.md, "Framing").
//
// Encoding: each block is a code byte n (1..255) followed by n - 1 data bytes
// containing no zero; a block with n < 255 stands for its bytes and one zero,
// the last block's implied zero dropped. Overhead: at most one byte per 254,
// plus the code byte, plus the delimiter: cobs_encoded_capacity(n).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "gabarit/status.hpp"

namespace gabarit::link {

// Bytes cobs_encode writes for `size` input bytes, at most (the delimiter included).
constexpr std::size_t cobs_encoded_capacity(std::size_t size) noexcept { return size + size / 254 + 2; }

// Encodes `in` into `out` and appends the zero delimiter. kBufferTooSmall if
// `out` is shorter than cobs_encoded_capacity(in.size()) (nothing is then
// promised about `out`).
Status cobs_encode(std::span<const std::byte> in, std::span<std::byte> out, std::size_t& written) noexcept;

// Decodes one encoded message without its delimiter. kBadHeaderField for a
// zero byte inside it or a block that runs past its end; kBufferTooSmall when
// the decoded bytes do not fit `out`.
Status cobs_decode(std::span<const std::byte> in, std::span<std::byte> out, std::size_t& written) noexcept;

// A streaming decoder with a fixed buffer (the caller's): push() bytes as
// they arrive; when one completes a message, push() returns kMessage and
// message() views it until the next push. Garbage is counted, never trusted:
// a run too long for the buffer or a malformed run is discarded up to the
// next delimiter.
class CobsStreamDecoder {
 public:
  enum class Event : std::uint8_t { kNone, kMessage, kDiscarded };

  explicit CobsStreamDecoder(std::span<std::byte> buffer) noexcept : buffer_(buffer) {}

  Event push(std::byte byte) noexcept;
  std::span<const std::byte> message() const noexcept { return buffer_.first(message_size_); }

  std::uint32_t overlong() const noexcept { return overlong_; }      // runs longer than the buffer
  std::uint32_t malformed() const noexcept { return malformed_; }    // runs that are not valid COBS
  void reset() noexcept;  // forget a partial run (after a reconnect)

 private:
  std::span<std::byte> buffer_;
  std::size_t size_ = 0;          // decoded bytes of the current run
  std::size_t message_size_ = 0;  // the last complete message
  std::uint8_t block_left_ = 0;   // data bytes left in the current block
  bool block_adds_zero_ = false;  // the current block ends with an implied zero
  bool at_block_start_ = true;
  bool discarding_ = false;
  bool started_ = false;  // bytes seen since the last delimiter
  std::uint32_t overlong_ = 0, malformed_ = 0;
};

}  // namespace gabarit::link
