// Accuracy of tracked poses against ground truth (gt.csv from `gabarit synth`).
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace gabarit::app {

struct PoseSample {
  std::uint32_t frame = 0;
  double x = 0, y = 0, theta_deg = 0;
  std::uint32_t depth = 0;
  bool visible = true;  // ground truth only
};

// Reads POSES.csv (frame,x,y,theta_deg,depth,...) or gt.csv
// (frame,x,y,theta_deg,depth,visible); the header line is required. Frames
// are counts up to 2^32 - 1, depths up to 65535, x, y, theta finite numbers
// within +-1e9, visible 0 or 1; anything else is refused naming the line.
std::vector<PoseSample> read_pose_csv(const std::string& path);
std::vector<PoseSample> read_pose_csv(std::istream& in, const std::string& name);

struct Accuracy {
  std::size_t frames = 0;          // visible ground-truth frames with a pose
  std::size_t exact = 0;           // |dx| < 0.5 and |dy| < 0.5 (the right pixel)
  std::size_t within_1px = 0;      // Euclidean error <= 1 px
  std::size_t within_2px = 0;
  std::size_t within_5px = 0;
  // The thesis's error buckets (Fig. 6.60): < 6, < 12, > 12, > 20, > 40 px.
  std::size_t below_6px = 0, below_12px = 0, above_12px = 0, above_20px = 0, above_40px = 0;
  // Failures (VOT-style): visible frames more than 5 px off whose previous
  // visible frame was within 5 px (or that are the first visible frame):
  // each time the track is lost, counted once.
  std::size_t failures = 0;
  std::size_t missing = 0;         // visible truth frames with no pose row
  double mean_error_px = 0;
  double max_error_px = 0;
  std::size_t within_1deg = 0;     // |theta error| <= 1 degree
  double mean_error_deg = 0;
  double max_error_deg = 0;
  std::size_t depth_exact = 0;     // depth index equal to the truth's
  // For each return to visibility after hidden frames (an occlusion): frames
  // from the first visible one until the pose is within 2 px (-1: never).
  std::vector<int> reacquired_after;
  std::vector<std::uint32_t> wrong_frames;  // not exact
};

Accuracy evaluate(const std::vector<PoseSample>& poses, const std::vector<PoseSample>& truth);
std::string accuracy_json(const Accuracy& a);

}  // namespace gabarit::app
