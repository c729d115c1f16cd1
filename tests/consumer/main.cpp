// The README's "Using gabarit in your firmware project", compiled: a table in
// read-only memory, validated once, static buffers checked against the
// kernel's size formulas, one tracking step on a blank frame.
#include <gabarit/table_view.hpp>
#include <gabarit/tracker.hpp>

#include <cstddef>
#include <cstdint>

extern "C" const std::byte consumer_table[];
extern "C" const std::byte consumer_table_end[];

namespace {

// Buffers for tables up to these sizes; a larger table is refused at start-up.
constexpr std::size_t kMaxFeatures = 64 * 64;
constexpr std::size_t kMaxCells = 2048;
constexpr std::size_t kMaxMaskBytes = 64 * 64 / 8;
constexpr std::uint32_t kFrameSide = 96;
// The formulas are constexpr: a fixed table geometry can be checked at compile time.
static_assert(gabarit::tracker_feature_capacity(21, 21, -10, -10) <= kMaxFeatures);
static_assert(gabarit::tracker_mask_bytes(21, 21) <= kMaxMaskBytes);

gabarit::RoiPoint features[kMaxFeatures];
gabarit::VoteCounter counters[kMaxCells];
std::uint8_t mask[kMaxMaskBytes];
std::uint8_t frame[kFrameSide * kFrameSide];

}  // namespace

int main() {
  gabarit::TableView table;
  const std::span<const std::byte> bytes(consumer_table, static_cast<std::size_t>(consumer_table_end - consumer_table));
  if (gabarit::TableView::open(bytes, table) != gabarit::Status::kOk) return 1;
  if (gabarit::tracker_feature_capacity(table) > kMaxFeatures || gabarit::voter_counter_count(table.cell_count()) > kMaxCells ||
      gabarit::tracker_mask_bytes(table) > kMaxMaskBytes) {
    return 2;
  }
  const gabarit::ImageView image{frame, kFrameSide, kFrameSide, kFrameSide};
  gabarit::StepResult step;
  const gabarit::TrackerScratch scratch{{features, gabarit::tracker_feature_capacity(table)},
                                        {counters, gabarit::voter_counter_count(table.cell_count())},
                                        {mask, gabarit::tracker_mask_bytes(table)}};
  if (gabarit::track_step(table, image, gabarit::Pose{48.0f, 48.0f, 0.0f, 0}, scratch, step) != gabarit::Status::kOk) return 3;
  // A blank frame has no features: nothing voted, the target is lost.
  return step.state == gabarit::TrackState::kLost && step.features == 0 ? 0 : 4;
}
