#include "suite_ledger.hpp"

#include <cstdio>

namespace gabarit::bench {
namespace {

// v with `digits` decimals, into a stream (string concatenation trips
// GCC 12's -Wrestrict false positive at -O3).
struct Fixed {
  double v;
  int digits;
};
std::ostream& operator<<(std::ostream& o, Fixed f) {
  char text[48];
  std::snprintf(text, sizeof text, "%.*f", f.digits, f.v);
  return o << text;
}
Fixed fixed(double v, int digits) { return {v, digits}; }

const char* phase_name(std::uint32_t p) { return frame_phase_name(static_cast<FramePhase>(p)); }

}  // namespace

void LedgerTally::add(const app::TrackRow& row) {
  ++rows_;
  all_ = all_ && row.has_ledger;
  for (std::uint32_t p = 0; p < kFramePhaseCount; ++p) sum_.add(static_cast<FramePhase>(p), row.ledger.work[p], row.ledger.ticks[p]);
  sum_.pixels_scanned += row.ledger.pixels_scanned;
  sum_.features += row.ledger.features;
  sum_.votes += row.ledger.votes;
  sum_.correlations += row.ledger.correlations;
  io_us_ += row.io_micros;
}

LedgerMeans LedgerTally::means() const {
  LedgerMeans m;
  if (!all_ || rows_ == 0) return m;
  const double n = static_cast<double>(rows_);
  m.present = true;
  for (std::uint32_t p = 0; p < kFramePhaseCount; ++p) {
    m.phase_us[p] = static_cast<double>(sum_.ticks[p]) / 1000.0 / n;  // HostedSession's clock: nanoseconds
    m.phase_work[p] = static_cast<double>(sum_.work[p]) / n;
  }
  m.io_us = io_us_ / n;
  m.pixels = static_cast<double>(sum_.pixels_scanned) / n;
  m.features = static_cast<double>(sum_.features) / n;
  m.votes = static_cast<double>(sum_.votes) / n;
  m.correlations = static_cast<double>(sum_.correlations) / n;
  return m;
}

std::string ledger_csv_header() {
  std::ostringstream s;
  for (std::uint32_t p = 0; p < kFramePhaseCount; ++p) s << ',' << phase_name(p) << "_us";
  for (std::uint32_t p = 0; p < kFramePhaseCount; ++p) s << ',' << phase_name(p) << "_work";
  s << ",io_us,pixels,features,votes,correlations";
  return s.str();
}

std::string ledger_csv_columns(const LedgerMeans& m) {
  if (!m.present) return std::string(2 * kFramePhaseCount + 5, ',');
  std::ostringstream s;
  for (double v : m.phase_us) s << ',' << fixed(v, 2);
  for (double v : m.phase_work) s << ',' << fixed(v, 0);
  s << ',' << fixed(m.io_us, 2) << ',' << fixed(m.pixels, 0) << ',' << fixed(m.features, 0) << ',' << fixed(m.votes, 0) << ','
    << fixed(m.correlations, 2);
  return s.str();
}

void ledger_table(const std::string& title, const std::vector<std::pair<std::string, std::vector<LedgerMeans>>>& methods,
                  std::ostringstream& md) {
  md << "#### " << title << ": where each frame's time goes (us per frame, mean over scenes; docs/performance.md)\n\n| method |";
  for (std::uint32_t p = 0; p < kFramePhaseCount; ++p) md << " " << phase_name(p) << " |";
  md << " total | reading frames | pixels scanned | features | votes | correlations |\n|---|";
  for (std::uint32_t p = 0; p < kFramePhaseCount + 6; ++p) md << "---:|";
  md << "\n";
  for (const auto& [name, scenes] : methods) {
    if (scenes.empty() || !scenes[0].present) continue;
    LedgerMeans mean;
    const double n = static_cast<double>(scenes.size());
    for (const LedgerMeans& r : scenes) {
      for (std::uint32_t p = 0; p < kFramePhaseCount; ++p) mean.phase_us[p] += r.phase_us[p] / n;
      mean.io_us += r.io_us / n, mean.pixels += r.pixels / n, mean.features += r.features / n;
      mean.votes += r.votes / n, mean.correlations += r.correlations / n;
    }
    double total = 0;
    md << "| " << name << " |";
    for (double v : mean.phase_us) md << " " << fixed(v, 1) << " |", total += v;
    md << " " << fixed(total, 1) << " | " << fixed(mean.io_us, 1) << " | " << fixed(mean.pixels, 0) << " | " << fixed(mean.features, 0)
       << " | " << fixed(mean.votes, 0) << " | " << fixed(mean.correlations, 1) << " |\n";
  }
  md << "\n";
}

}  // namespace gabarit::bench
