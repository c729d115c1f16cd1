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

// Buffers for tables whose ROI is at most kMaxRoiSide pixels a side, centred
// on the reference point, with up to kMaxCells cells, sized by the kernel's
// constexpr formulas; a larger table is refused at start-up.
constexpr std::uint16_t kMaxRoiSide = 192;
constexpr std::int16_t kMaxRoiOrigin = -kMaxRoiSide / 2;
constexpr std::size_t kMaxFeatures = gabarit::tracker_feature_capacity(kMaxRoiSide, kMaxRoiSide, kMaxRoiOrigin, kMaxRoiOrigin);
constexpr std::size_t kMaxMaskBytes = gabarit::tracker_mask_bytes(kMaxRoiSide, kMaxRoiSide);
constexpr std::uint32_t kMaxCells = 4096;
constexpr std::uint32_t kFrameSide = 256;
static_assert(kMaxFeatures == 273 * 273, "the window a 192 x 192 ROI needs at any angle");

gabarit::RoiPoint features[kMaxFeatures];
gabarit::VoteCounter counters[kMaxCells];
std::uint8_t mask[kMaxMaskBytes];
std::uint8_t frame[kFrameSide * kFrameSide];

}  // namespace

// Exit status: 0 as expected, 1 the table is invalid, 2 it does not fit the
// buffers, 3 track_step failed, 4 an unexpected result.
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
  if (gabarit::track_step(table, image, gabarit::Pose{128.0f, 128.0f, 0.0f, 0}, scratch, step) != gabarit::Status::kOk) return 3;
  // A blank frame has no features: nothing voted, the target is lost.
  return step.state == gabarit::TrackState::kLost && step.features == 0 ? 0 : 4;
}
