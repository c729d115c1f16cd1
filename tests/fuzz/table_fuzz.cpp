// Fuzz target: the table loader, then what the kernel computes with an
// accepted table: a tracking step, a motion-filtered session, a plain session
// that becomes lost and searches, and depth and angle by intensity. Any
// table TableView::open accepts must run without undefined behaviour, within
// the scratch its limits allow (table_format.hpp, "Limits"). The harness
// re-seals the CRC of every input long enough to hold one, so mutations reach
// the structural checks and the tracker instead of stopping at bad-checksum
// (the checksum has its own tests, and the seed corpus holds a table with a
// wrong one).
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "gabarit/byte_order.hpp"
#include "gabarit/depth_by_intensity.hpp"
#include "gabarit/table_view.hpp"
#include "gabarit/tracker.hpp"
#include "gabarit/tracking_session.hpp"

namespace {

using namespace gabarit;

constexpr std::uint32_t kSide = 64;

// A frame with a few features that depend on the table, so the vote is not
// always empty.
std::vector<std::uint8_t> frame_for(std::span<const std::byte> bytes) {
  std::vector<std::uint8_t> frame(kSide * kSide, 0);
  std::uint32_t h = 2166136261u;
  for (std::size_t i = 0; i < bytes.size(); i += 97) h = (h ^ std::to_integer<std::uint32_t>(bytes[i])) * 16777619u;
  for (int k = 0; k < 200; ++k) {
    h = h * 1103515245u + 12345u;
    frame[(h >> 8) % frame.size()] = static_cast<std::uint8_t>(h >> 24 | 1u);
  }
  return frame;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // 8-byte-aligned, exact-size storage (ASan sees reads past the end).
  std::vector<std::uint64_t> words((size + 7) / 8);
  if (size > 0) std::memcpy(words.data(), data, size);
  auto* writable = reinterpret_cast<std::byte*>(words.data());
  if (size >= table_format::kHeaderBytes && (data[size - 1] & 1u) == 0) {  // half the inputs: a CRC that matches
    store_le<std::uint32_t>(writable + table_format::offset::kCrc32, table_checksum({writable, size}));
  }
  const std::span<const std::byte> bytes(writable, size);
  TableView table;
  if (TableView::open(bytes, table) != Status::kOk) return 0;

  std::vector<RoiPoint> features(tracker_feature_capacity(table));
  std::vector<VoteCounter> counters(voter_counter_count(table.cell_count()));
  std::vector<std::uint8_t> mask(tracker_mask_bytes(table));
  const TrackerScratch scratch{features, counters, mask};
  const std::vector<std::uint8_t> pixels = frame_for(bytes);
  const ImageView frame{pixels.data(), kSide, kSide, kSide};
  const std::vector<std::uint8_t> blank(kSide * kSide, 0);
  const ImageView empty{blank.data(), kSide, kSide, kSide};
  const Pose start{kSide / 2.0f, kSide / 2.0f, 0.0f, 0};

  StepResult step;
  static_cast<void>(track_step(table, frame, start, scratch, step));

  SessionOptions filtered;
  filtered.recovery.budget = 1;  // the 9 near placements and 1 more: quick lost frames
  TrackingSession session(table, nullptr, detector_of(table));
  SessionResult result;
  if (session.start(filtered, start) == Status::kOk) {
    for (int f = 0; f < 3; ++f) static_cast<void>(session.step(frame, {scratch, {}, {}}, result));
  }
  SessionOptions plain = kPlainSession;
  plain.recover = true;
  plain.recovery.budget = 1;
  TrackingSession searching(table, nullptr, detector_of(table));
  if (searching.start(plain, start) == Status::kOk) {
    static_cast<void>(searching.step(empty, {scratch, {}, {}}, result));  // lost
    static_cast<void>(searching.step(frame, {scratch, {}, {}}, result));  // searches
  }
  // A table with model images: the default session with its own focus stack
  // (every stored image read through TableView::model_image).
  if (table.has_model_images()) {
    std::vector<ImageView> stored;
    for (std::uint16_t d = 0; d < table.depth_count() && d < 16; ++d) stored.push_back(table.model_image(d));
    const FocusStack own{stored, table.model_ref_x(), table.model_ref_y(), 2};
    TrackingSession with_stack(table, nullptr, detector_of(table));
    if (stored.size() == table.depth_count() && with_stack.start(filtered, start) == Status::kOk) {
      with_stack.use_focus_stack(&own);
      for (int f = 0; f < 2; ++f) static_cast<void>(with_stack.step(frame, {scratch, {}, {}}, result));
    }
  }
  // The intensity steps with the frame as every depth's image.
  if (table.depth_count() <= 16) {
    std::vector<ImageView> stack(table.depth_count(), frame);
    const FocusStack focus{stack, table.model_ref_x(), table.model_ref_y(), 2};
    std::uint16_t depth = 0;
    float theta = 0.0f;
    static_cast<void>(depth_by_intensity(frame, step.pose, focus, depth));
    static_cast<void>(angle_by_intensity(frame, step.pose, focus, theta));
  }
  return 0;
}
