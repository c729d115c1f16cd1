// The harness's verdicts as lines for a DUT's console (`gabarit hil run
// --console-verdicts`). The harness sends each line as a NOTE; a DUT with a
// console prints it (the Cortex-M firmware, on UART1). A board farm that
// reads only the console, such as LAVA's `monitors` test, makes its own test
// cases of them (docs/hil-farm.md, which gives the patterns):
//
//   gabarit-hil: frames
//   gabarit-hil case=frame-000012 result=pass measurement=0.031 units=px
//   ...
//   gabarit-hil: frames over
//   gabarit-hil: checks
//   gabarit-hil case=poses_match_reference result=pass
//   ...
//   gabarit-hil: run over, 0 of 9 checks failed
//
// A frame passes when its pose came back bit-identical to the host's
// reference from the pixels sent; a frame a fault was planned on is a skip
// (its fault's check judges it); any other frame fails. The measurement is
// the pose's position error against gt.csv in pixels; `units=none` (and 0)
// where there is no pose or no ground truth for the frame.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "gabarit/app/evaluation.hpp"
#include "gabarit/hil/harness.hpp"

namespace gabarit::hil {

inline constexpr const char* kConsoleFramesStart = "gabarit-hil: frames";
inline constexpr const char* kConsoleFramesEnd = "gabarit-hil: frames over";
inline constexpr const char* kConsoleChecksStart = "gabarit-hil: checks";
inline constexpr const char* kConsoleRunEnd = "gabarit-hil: run over";

class ConsoleVerdicts {
 public:
  explicit ConsoleVerdicts(const std::vector<app::PoseSample>& truth);
  std::string frame_line(const FrameRecord& record) const;
  // The closing lines: the frames' end, then one per check, then the end.
  std::vector<std::string> closing_lines(const RunResult& result) const;
  // Hooks the lines into a run's configuration.
  void attach(RunConfig& config) const;

 private:
  std::map<std::uint32_t, app::PoseSample> truth_;
};

}  // namespace gabarit::hil
