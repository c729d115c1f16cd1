// `gabarit tables export-hdl` end to end: a voter whose memories were loaded
// by $readmemh from the exported images (no table port writes at all) must
// vote exactly like the kernel on the same table file.
#include <gtest/gtest.h>

#include "Vvoter_preload.h"
#include "gabarit/host/runs/voter_trials.hpp"
#include "gabarit/features.hpp"
#include "gabarit/app/files.hpp"
#include "gabarit/host/scenes/thesis_shapes.hpp"
#include "voter_harness.hpp"

namespace gabarit::hdl {
namespace {

TEST(VoterPreload, ExportedImagesLoadedByReadmemhVoteLikeTheKernel) {
  const auto bytes = app::read_file(GABARIT_PRELOAD_TABLE);
  TableView t;
  ASSERT_EQ(TableView::open(bytes, t), Status::kOk);
  Harness<Vvoter_preload> h;
  h.model().cell_count_i = t.cell_count();
  h.model().roi_width_i = t.roi_width();
  h.model().roi_height_i = t.roi_height();
  const host::Shape shape = host::make_shape("curve", host::thesis_curve());
  const auto trials = host::make_trials(shape, 0.3, 10, 5);
  for (std::size_t i = 0; i < trials.size(); ++i) {
    const auto f = trial_features(t, trials[i].frame, trials[i].previous.x, trials[i].previous.y);
    app::Rng rng(i);
    EXPECT_EQ(compare(h.frame(f, t.cell_count(), 0.1, rng), kernel_outcome(t, f)), "") << "frame " << i;
  }
}

}  // namespace
}  // namespace gabarit::hdl
