#include "gabarit/app/scratch.hpp"

#include <string>

#include "gabarit/app/error.hpp"
#include "gabarit/dense_voter.hpp"

namespace gabarit::app {

TrackerBuffers::TrackerBuffers(const TableView& table, VoterChoice voter)
    : features_(tracker_feature_capacity(table)),
      counters_(voter_counter_count(table.cell_count())),
      mask_(tracker_mask_bytes(table)),
      magnitudes_(tracker_magnitude_entries(table)) {
  const bool fits = table.cell_count() <= kDenseMaxCells;
  if (voter == VoterChoice::kDense && !fits) {
    throw Error("the dense voter takes at most " + std::to_string(kDenseMaxCells) + " cells; this table has " +
                std::to_string(table.cell_count()));
  }
  if (voter == VoterChoice::kDense || (voter == VoterChoice::kAuto && dense_voter_pays_off(table))) {
    masks_.resize(dense_mask_words(table.roi_slots(), table.cell_count()));
    dense_scratch_.resize(dense_scratch_words(table.cell_count()));
    if (build_dense_masks(table, masks_) != Status::kOk) throw Error("internal error: building dense masks failed");
  } else if (table.offset_delta_bytes() != 0) {
    // The CSR voter on a compact table: decode its offsets once, not per feature.
    expanded_.resize(expanded_offsets_count(table));
    if (expand_offsets(table, expanded_) != Status::kOk) throw Error("internal error: expanding the offsets failed");
  }
}

TrackerScratch TrackerBuffers::scratch() { return {features_, counters_, mask_, masks_, dense_scratch_, expanded_, magnitudes_}; }

FinderBuffers::FinderBuffers(const TableView& table, const Detector& detector, const FinderOptions& options,
                             std::uint32_t width, std::uint32_t height)
    : geometry_(finder_geometry(table, detector, options, width, height)), width_(width), height_(height) {
  const FinderScratchSizes n = finder_scratch_sizes(geometry_, table);
  coarse_image_.resize(n.coarse_pixels);
  coarse_features_.resize(n.coarse_pixels);
  feature_index_.resize(n.coarse_pixels);
  accumulator_.resize(n.accumulator);
  model_.resize(n.model_points);
  rotated_.resize(2 * n.model_points);
  candidates_.resize(kMaxFinderCandidates);
  held_frame_.resize(std::size_t{width} * height);
}

FinderScratch FinderBuffers::scratch(TrackerScratch fine) {
  return {coarse_image_, coarse_features_, feature_index_, accumulator_, model_, rotated_, candidates_, fine, held_frame_};
}

SessionBuffers::SessionBuffers(const TableView& fine, const TableView* coarse, VoterChoice voter, bool search_features)
    : fine_(fine, voter) {
  if (coarse != nullptr) {
    coarse_.emplace(*coarse, voter);
  } else if (search_features) {
    // Past the cap (a table with very wide x/y ranges) the search votes each
    // placement with a full track_step instead of allocating more.
    const std::size_t needed = search_feature_capacity(fine);
    if (needed <= kMaxSearchFeatures) search_features_.resize(needed);
  }
}

SessionScratch SessionBuffers::scratch() {
  return {fine_.scratch(), coarse_ ? coarse_->scratch() : TrackerScratch{}, search_features_};
}

TableFocusStack::TableFocusStack(const TableView& table) {
  if (!table.has_model_images()) return;
  for (std::uint16_t d = 0; d < table.depth_count(); ++d) views_.push_back(table.model_image(d));
  stack_ = FocusStack{views_, table.model_ref_x(), table.model_ref_y(), 2};
}

}  // namespace gabarit::app
