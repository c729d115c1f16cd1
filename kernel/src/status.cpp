#include "gabarit/status.hpp"

namespace gabarit {

const char* status_name(Status status) noexcept {
  switch (status) {
    case Status::kOk: return "ok";
    case Status::kInvalidArgument: return "invalid-argument";
    case Status::kBufferTooSmall: return "buffer-too-small";
    case Status::kTruncated: return "truncated";
    case Status::kBadMagic: return "bad-magic";
    case Status::kUnsupportedVersion: return "unsupported-version";
    case Status::kSizeMismatch: return "size-mismatch";
    case Status::kBadChecksum: return "bad-checksum";
    case Status::kBadHeaderField: return "bad-header-field";
    case Status::kCountTooLarge: return "count-too-large";
    case Status::kSectionOutOfBounds: return "section-out-of-bounds";
    case Status::kOffsetsNotMonotonic: return "offsets-not-monotonic";
    case Status::kReferenceOutOfRange: return "reference-out-of-range";
    case Status::kReferencesNotSorted: return "references-not-sorted";
    case Status::kStencilSizeMismatch: return "stencil-size-mismatch";
    case Status::kFeatureOutOfRoi: return "feature-out-of-roi";
  }
  return "unknown-status";
}

}  // namespace gabarit
