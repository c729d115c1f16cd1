// A feature pixel in ROI coordinates: column and row inside the table's ROI,
// whose pixel (0, 0) sits at (roi_origin_x, roi_origin_y) from the ROI centre.
#pragma once

#include <cstdint>

namespace gabarit {

struct RoiPoint {
  std::uint16_t col = 0;
  std::uint16_t row = 0;
};

}  // namespace gabarit
