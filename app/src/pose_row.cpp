#include "gabarit/app/pose_row.hpp"

#include <chrono>
#include <cstdio>

namespace gabarit::app {

std::uint64_t steady_nanoseconds() noexcept {
  return static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count());
}

void fill_row(TrackRow& row, const SessionResult& result) {
  row.step = result.step;
  row.step.pose = result.pose;
  row.step.state = result.state;
  row.step.score = result.score;
  row.confidence = result.confidence;
  row.reacquired = result.reacquired;
  row.work = result.work;
  row.has_ledger = true;
  row.ledger = result.ledger;
}

std::string pose_csv_row(const TrackRow& row) {
  char line[192];
  std::snprintf(line, sizeof line, "%u,%.3f,%.3f,%.3f,%u,%u,%.6f,%s", row.frame, static_cast<double>(row.step.pose.x),
                static_cast<double>(row.step.pose.y), static_cast<double>(row.step.pose.theta_deg), row.step.pose.depth,
                row.step.best.votes, static_cast<double>(row.step.score), track_state_name(row.step.state));
  return line;
}

}  // namespace gabarit::app
