// The largest table the firmware images' RAM is sized for: a ROI of up to
// kMaxRoiSide x kMaxRoiSide pixels centred on the reference point and up to
// kMaxCells cells. Each image's static buffers use these sizes, computed by
// the kernel's constexpr formulas, and refuse a bigger table at start-up.
#pragma once

#include <cstddef>
#include <cstdint>

#include "gabarit/table_view.hpp"
#include "gabarit/tracker.hpp"
#include "gabarit/voter.hpp"

namespace gabarit::mcu {

inline constexpr std::uint16_t kMaxRoiSide = 192;
inline constexpr std::int16_t kMaxRoiOrigin = -static_cast<std::int16_t>(kMaxRoiSide / 2);
inline constexpr std::uint32_t kMaxCells = 4096;
inline constexpr std::size_t kFeatureCapacity = tracker_feature_capacity(kMaxRoiSide, kMaxRoiSide, kMaxRoiOrigin, kMaxRoiOrigin);
inline constexpr std::size_t kMaskBytes = tracker_mask_bytes(kMaxRoiSide, kMaxRoiSide);
inline constexpr std::size_t kCounterCount = voter_counter_count(kMaxCells);
// The Canny detector's rows of magnitudes (each pixel's gradient computed once).
inline constexpr std::size_t kMagnitudeEntries = tracker_magnitude_entries(kMaxRoiSide, kMaxRoiSide, kMaxRoiOrigin, kMaxRoiOrigin);

inline bool table_fits(const TableView& table) noexcept {
  return tracker_feature_capacity(table) <= kFeatureCapacity && table.cell_count() <= kMaxCells &&
         tracker_mask_bytes(table) <= kMaskBytes;
}

}  // namespace gabarit::mcu
