// The largest table the firmware images' RAM is sized for: a ROI of up to
// kMaxRoiSide x kMaxRoiSide pixels centred on the reference point and up to
// kMaxCells cells; and the particle tracker's cloud and frame below. Each
// image's static buffers use these sizes, computed by the kernel's constexpr
// formulas, and refuse a bigger table (or cloud, or frame) at start-up.
#pragma once

#include <cstddef>
#include <cstdint>

#include "gabarit/particle_measures.hpp"
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

// The particle tracker's replay (particle.gbp): up to kMaxParticles
// particles (gabarit track --tracker particle's default count) on frames of
// up to kMaxParticleFrameSide pixels a side, whose edge map it holds whole.
inline constexpr std::uint32_t kMaxParticles = 1000;
inline constexpr std::uint32_t kMaxParticleFrameSide = 256;
inline constexpr std::size_t kEdgeMapWords = edge_map_words(kMaxParticleFrameSide, kMaxParticleFrameSide);
inline constexpr std::size_t kEdgeMapFeatures = edge_map_features(kMaxParticleFrameSide);

inline bool table_fits(const TableView& table) noexcept {
  return tracker_feature_capacity(table) <= kFeatureCapacity && table.cell_count() <= kMaxCells &&
         tracker_mask_bytes(table) <= kMaskBytes;
}

}  // namespace gabarit::mcu
