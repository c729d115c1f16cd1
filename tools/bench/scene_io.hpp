// What the grayscale-scene benchmarks (--microscope, --suite) share: a scene
// held in memory, so no method is timed reading files, and the OpenCV NCC
// bank they are compared against.
#pragma once

#include <opencv2/core.hpp>

#include <algorithm>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "gabarit/app/evaluation.hpp"
#include "gabarit/app/image_io.hpp"
#include "gabarit/pose.hpp"

namespace gabarit::bench {

class MemoryFrames final : public app::FrameSource {
 public:
  explicit MemoryFrames(const std::vector<app::GrayImage>& f) : frames_(f) {}
  bool next(app::GrayImage& out) override {
    if (at_ >= frames_.size()) return false;
    out = frames_[at_++];
    return true;
  }

 private:
  const std::vector<app::GrayImage>& frames_;
  std::size_t at_ = 0;
};

std::vector<app::GrayImage> read_all_frames(const std::filesystem::path& y4m);
// The model stack's image paths of a scene directory (model_NN.pgm).
std::vector<std::string> scene_model_paths(const std::filesystem::path& seq, int depths);

// OpenCV's exhaustive normalised cross-correlation over the tracker's 4-DOF
// window: for every depth and every angle step of the table around the
// current estimate, the model image rotated to that angle (a bank of
// templates, rotated once per 0.5 degree and cached) is matched with
// TM_CCOEFF_NORMED at every translation of +-range px; the best match is the
// new pose.
// One method's run over a scene: its poses and its time per frame.
struct MethodRun {
  std::string name;
  std::vector<app::PoseSample> poses;
  double mean_us = 0;
  std::vector<double> micros;
  bool position_only = false;  // OpenCV's box trackers: angle and depth are not estimated
  double median_us() const {
    std::vector<double> v = micros;
    std::sort(v.begin(), v.end());
    return v.empty() ? 0 : v[v.size() / 2];
  }
};

// OpenCV's correlation-filter trackers (MOSSE, KCF, CSRT): position only (no
// angle or depth), initialised with the object's box in frame 0, on BGR
// copies of the frames (made before timing; KCF and CSRT use colour names
// otherwise); appended to `runs`. Nothing where OpenCV's tracking module
// (libopencv-contrib-dev) is not built.
void opencv_box_trackers(const std::vector<app::GrayImage>& frames, const std::vector<app::GrayImage>& model_images, const Pose& init,
                         std::vector<MethodRun>& runs);

class NccBank {
 public:
  NccBank(const std::vector<app::GrayImage>& models, int range, double step_deg, int steps);
  Pose track(const app::GrayImage& frame, const Pose& previous);

 private:
  const cv::Mat& rotated(std::size_t depth, double theta);
  std::vector<cv::Mat> models_;
  std::map<long, cv::Mat> cache_;
  cv::Mat result_;
  int range_;
  double step_;
  int steps_;
};

}  // namespace gabarit::bench

namespace gabarit::bench {

// The detector a user would write with OpenCV to find a model anywhere: an
// image pyramid (pyrDown `levels` times), matchTemplate TM_CCOEFF_NORMED of
// the model rotated every coarse_step_deg (a full turn) at every depth on the
// top level, the `candidates` best peaks (one per place), each refined at
// full resolution over +-(2^levels + 1) px and +-coarse_step/2 in 0.5-degree
// steps at its depth, then over every depth at its angle. Scores are NCC.
struct PyramidDetection {
  Pose pose;
  double score = 0;
};
class PyramidMatcher {
 public:
  PyramidMatcher(const std::vector<app::GrayImage>& models, int levels, double coarse_step_deg, int candidates);
  std::vector<PyramidDetection> detect(const app::GrayImage& frame);

 private:
  cv::Mat rotated(const cv::Mat& model, double theta) const;
  std::vector<cv::Mat> models_;                        // full resolution
  std::vector<std::vector<cv::Mat>> coarse_bank_;      // [depth][angle]
  int levels_, candidates_;
  double step_;
};

}  // namespace gabarit::bench
