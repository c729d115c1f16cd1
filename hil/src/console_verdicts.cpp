#include "gabarit/hil/console_verdicts.hpp"

#include <cmath>
#include <cstdio>

#include "gabarit/hil/report.hpp"

namespace gabarit::hil {

ConsoleVerdicts::ConsoleVerdicts(const std::vector<app::PoseSample>& truth) {
  for (const app::PoseSample& t : truth) truth_[t.frame] = t;
}

std::string ConsoleVerdicts::frame_line(const FrameRecord& r) const {
  const bool matched = r.fate == Fate::kPose && r.reference != 0 && r.frame_crc_ok;
  const char* result = r.fault >= 0 ? "skip" : matched ? "pass" : "fail";
  double error = 0;
  const char* units = "none";
  const auto it = truth_.find(r.frame);
  if (r.pose && it != truth_.end() && it->second.visible) {
    error = std::hypot(r.pose->pose.x - it->second.x, r.pose->pose.y - it->second.y);
    units = "px";
  }
  char line[96];
  std::snprintf(line, sizeof line, "gabarit-hil case=frame-%06u result=%s measurement=%.3f units=%s", r.frame, result, error,
                units);
  return line;
}

std::vector<std::string> ConsoleVerdicts::closing_lines(const RunResult& result) const {
  std::vector<std::string> lines = {kConsoleFramesEnd, kConsoleChecksStart};
  std::size_t failed = 0;
  const std::vector<Check> checks = run_checks(result);
  for (const Check& c : checks) {
    failed += c.passed ? 0 : 1;
    // Case names are the checks' own (report.cpp), cut to fit a NOTE.
    lines.push_back(("gabarit-hil case=" + c.name).substr(0, 80) + (c.passed ? " result=pass" : " result=fail"));
  }
  lines.push_back(std::string(kConsoleRunEnd) + ", " + std::to_string(failed) + " of " + std::to_string(checks.size()) +
                  " checks failed");
  return lines;
}

void ConsoleVerdicts::attach(RunConfig& config) const {
  config.console_opening = kConsoleFramesStart;
  config.console_frame_line = [this](const FrameRecord& r) { return frame_line(r); };
  config.console_closing = [this](const RunResult& r) { return closing_lines(r); };
}

}  // namespace gabarit::hil
