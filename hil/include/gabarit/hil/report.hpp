// A run's report, in the folder given to `gabarit hil run --report DIR`:
//   frames.csv     one row per frame: gabarit track's columns
//                  (frame,x,y,theta_deg,depth,votes,score,status; empty
//                  without a pose), then fate, reason, reference, latency_us,
//                  dut_us, cycles, wire_bytes, fault
//   poses.csv      the poses alone, exactly as gabarit track writes them
//                  (gabarit eval reads it)
//   results.jsonl  one JSON object per frame as its fate is known (written
//                  during the run: a crash leaves what was known)
//   summary.json   the DUT's identity, the counts, the checks, latency,
//                  overhead, accuracy against ground truth
//   junit.xml      one testcase per check and per injected fault,
//                  measurements as properties
//   faults.csv     the fault plan the run used (replay with --faults)
//   report.md      the summary with SVG plots: error over time, trajectory
//                  against truth, latency histogram, fault timeline
#pragma once

#include <string>
#include <vector>

#include "gabarit/hil/harness.hpp"
#include "gabarit/app/evaluation.hpp"

namespace gabarit::hil {

struct Check {
  std::string name;
  bool passed = false;
  std::string message;  // why it failed, or what it measured
};

// The run's checks, in report order: the handshake, every frame accounted
// for, poses in order, poses bit-identical to the reference, the pixels the
// DUT tracked are those sent, every injected fault detected and recovered from.
std::vector<Check> run_checks(const RunResult& result);

// One results.jsonl line (no newline).
std::string frame_json(const FrameRecord& record);

// Writes every file but results.jsonl (the caller streams that one).
// `truth` may be empty (no gt.csv).
void write_report(const std::string& dir, const RunConfig& config, const RunResult& result,
                  const std::vector<app::PoseSample>& truth);

}  // namespace gabarit::hil
