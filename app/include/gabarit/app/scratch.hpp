// Scratch for hosted programs (gabarit track, gabarit-board): the kernel's
// buffers allocated once per table, sized by the kernel's constexpr formulas
// (tracker.hpp, recovery_search.hpp). Firmware sizes the same buffers
// statically against the same formulas instead.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "gabarit/depth_by_intensity.hpp"
#include "gabarit/model_finder.hpp"
#include "gabarit/table_view.hpp"
#include "gabarit/tracker.hpp"
#include "gabarit/tracking_session.hpp"

namespace gabarit::app {

// Which voter track_step uses: the CSR lists, word-parallel masks
// (dense_voter.hpp; tables of at most kDenseMaxCells cells), or the one the
// cost model expects to be faster (dense_voter_pays_off). Results are
// bit-identical; only the time differs.
enum class VoterChoice { kAuto, kCsr, kDense };

// Scratch for track_step on one table. Throws app::Error when kDense is asked
// of a table too large for it.
class TrackerBuffers {
 public:
  TrackerBuffers(const TableView& table, VoterChoice voter);
  TrackerScratch scratch();

 private:
  std::vector<RoiPoint> features_;
  std::vector<VoteCounter> counters_;
  std::vector<std::uint8_t> mask_;
  std::vector<std::uint64_t> masks_, dense_scratch_;
  std::vector<std::uint32_t> expanded_;  // a compact table's offsets, for the CSR voter
  std::vector<std::uint16_t> magnitudes_;  // the Canny detector's rows of gradient magnitudes
};

// Scratch for a TrackingSession: the fine table's, the coarse table's when
// there is one, and the recovery search's shared features when asked for
// (recovery_search.hpp; only without a coarse table, which votes its own,
// and only up to kMaxSearchFeatures: beyond, each placement is a full
// track_step).
class SessionBuffers {
 public:
  SessionBuffers(const TableView& fine, const TableView* coarse, VoterChoice voter, bool search_features);
  SessionScratch scratch();
  bool shares_search_features() const { return !search_features_.empty(); }

 private:
  TrackerBuffers fine_;
  std::optional<TrackerBuffers> coarse_;
  std::vector<RoiPoint> search_features_;
};

// Scratch for a ModelFinder (model_finder.hpp) on frames of one size with
// one set of options; the fine table's tracker scratch is the caller's
// (a session's, or a TrackerBuffers). Frames of another size need new buffers.
class FinderBuffers {
 public:
  FinderBuffers(const TableView& table, const Detector& detector, const FinderOptions& options, std::uint32_t width,
                std::uint32_t height);
  FinderScratch scratch(TrackerScratch fine);
  const FinderGeometry& geometry() const { return geometry_; }
  std::uint32_t width() const { return width_; }
  std::uint32_t height() const { return height_; }

 private:
  FinderGeometry geometry_;
  std::uint32_t width_ = 0, height_ = 0;
  std::vector<std::uint8_t> coarse_image_;
  std::vector<RoiPoint> coarse_features_;
  std::vector<std::int32_t> feature_index_;
  std::vector<std::uint16_t> accumulator_;
  std::vector<OrientedPoint> model_;
  std::vector<std::int32_t> rotated_;
  std::vector<FinderCandidate> candidates_;
  std::vector<std::uint8_t> held_frame_;  // a search spread over frames holds its first frame
};

// The focus stack a table carries (format 1.1: the model images it was built
// from), as TrackingSession::use_focus_stack takes it. get() is null for a
// table without images. The table must outlive it; it is not copyable (the
// stack points at its own views).
class TableFocusStack {
 public:
  explicit TableFocusStack(const TableView& table);
  TableFocusStack(const TableFocusStack&) = delete;
  TableFocusStack& operator=(const TableFocusStack&) = delete;
  const FocusStack* get() const { return views_.empty() ? nullptr : &stack_; }

 private:
  std::vector<ImageView> views_;
  FocusStack stack_;
};

}  // namespace gabarit::app
