// The frame-cost ledger in `gabarit bench --suite` (docs/performance.md):
// a run's rows summed into means per frame, their CSV columns and the
// Markdown table of a half's scenes.
#pragma once

#include <sstream>
#include <string>
#include <vector>

#include "gabarit/app/pose_row.hpp"
#include "gabarit/frame_ledger.hpp"

namespace gabarit::bench {

// Means per frame of one method on one scene (ticks in microseconds).
struct LedgerMeans {
  bool present = false;  // every row had a ledger (sessions and the particle filter; not the NCC bank)
  double phase_us[kFramePhaseCount] = {}, phase_work[kFramePhaseCount] = {};
  double io_us = 0, pixels = 0, features = 0, votes = 0, correlations = 0;
};

class LedgerTally {
 public:
  void add(const app::TrackRow& row);
  LedgerMeans means() const;

 private:
  FrameLedger sum_;
  double io_us_ = 0;
  std::size_t rows_ = 0;
  bool all_ = true;
};

// ",features_us,...,other_us,features_work,...,io_us,pixels,features,votes,correlations"
std::string ledger_csv_header();
// The same columns for `m` (empty where it has no ledger).
std::string ledger_csv_columns(const LedgerMeans& m);
// A half's table: one row per method (name, its scenes' means); methods
// without a ledger are left out.
void ledger_table(const std::string& title, const std::vector<std::pair<std::string, std::vector<LedgerMeans>>>& methods,
                  std::ostringstream& md);

}  // namespace gabarit::bench
