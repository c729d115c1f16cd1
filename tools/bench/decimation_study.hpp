// The thesis's section 6.2 protocol re-run for decimation (`gabarit bench
// --decimation`): every decimation policy (decimation.hpp) at 11 keep
// ratios against 26 noise levels, on the thesis's shapes (the tuning half:
// the ~194-point hand-like curve and the ~2800-point watch) and on shapes
// nothing was tuned on (the held-out half: two other random curves and the
// edges of two other Debian photographs), two ways:
//   - one-step trials (experiments.hpp's protocol): independent frames, a
//     frame wrong unless the estimate is the true pixel;
//   - continuous sequences (the thesis's): a velocity random walk within
//     +-4 px per frame, 500 frames for the small shapes and 800 for the
//     large ones, tracked by the plain loop from the first position, so a
//     lost frame is lost for good; a sequence passes when every frame is exact.
// Also table bytes and voting time per keep ratio (CSR, dense and the cost
// model's choice, interleaved in one run). Writes DIR/decimation.md, CSVs
// and SVG heat maps (thesis Figs. 6.16-6.19, 6.28-6.30).
#pragma once

#include <string>

namespace gabarit::bench {

struct DecimationStudyOptions {
  std::string out = "bench-out";
  bool quick = false;  // 6 noise levels, 4 keep ratios, short sequences (seconds)
  unsigned threads = 1;
};
int run_decimation_study(const DecimationStudyOptions& options);

}  // namespace gabarit::bench
