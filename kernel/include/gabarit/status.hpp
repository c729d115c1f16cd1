// The kernel's one error model: every fallible entry point returns a Status,
// results go to an out-parameter the caller owns (so the caller also owns
// their storage), and the compiler refuses to let a caller ignore a Status.
// Programming errors (broken documented preconditions) are GABARIT_ASSERTs
// (assert.hpp), not Status values.
#pragma once

#include <cstdint>

namespace gabarit {

// Each failure has its own code so a caller (or a test) can tell a truncated
// table from a corrupted one from one written by a newer tool.
enum class [[nodiscard]] Status : std::uint8_t {
  kOk = 0,
  kInvalidArgument,       // a parameter outside its documented range
  kBufferTooSmall,        // a caller-owned buffer is smaller than its constexpr size
  kTruncated,             // the byte buffer ends before the table says it does
  kBadMagic,              // not a gabarit table
  kUnsupportedVersion,    // a major version this kernel does not read
  kSizeMismatch,          // header sizes disagree with each other or with the buffer
  kBadChecksum,           // CRC-32 over the payload does not match
  kBadHeaderField,        // a header field holds a value the format forbids
  kCountTooLarge,         // a count beyond the format's limits
  kSectionOutOfBounds,    // a section overlaps another or runs past the end
  kOffsetsNotMonotonic,   // CSR pixel offsets decrease or do not end at the reference count
  kReferenceOutOfRange,   // a pixel references a cell index >= cell count
  kReferencesNotSorted,   // a pixel lists a cell twice or out of increasing order
  kStencilSizeMismatch,   // cell descriptors' stencil sizes do not add up to the reference count
  kFeatureOutOfRoi,       // a feature handed to the voter lies outside the table's ROI
};

// A short stable name such as "bad-checksum" (for logs and CLI messages).
const char* status_name(Status status) noexcept;

}  // namespace gabarit

// Early return on failure, in the style of Pigweed's PW_TRY.
#define GABARIT_TRY(expr)                                       \
  do {                                                          \
    if (const ::gabarit::Status gabarit_try_status_ = (expr);   \
        gabarit_try_status_ != ::gabarit::Status::kOk) {        \
      return gabarit_try_status_;                               \
    }                                                           \
  } while (false)
