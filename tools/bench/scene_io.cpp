#include "scene_io.hpp"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>

namespace gabarit::bench {

// A whole sequence in memory, so no method is timed reading files.
std::vector<app::GrayImage> read_all_frames(const std::filesystem::path& y4m) {
  std::vector<app::GrayImage> frames;
  auto src = app::open_frames(y4m.string());
  app::GrayImage f;
  while (src->next(f)) frames.push_back(f);
  return frames;
}

// The model stack's image paths of a scene directory (model_NN.pgm).
std::vector<std::string> scene_model_paths(const std::filesystem::path& seq, int depths) {
  std::vector<std::string> paths;
  for (int d = 0; d < depths; ++d) {
    char name[32];
    std::snprintf(name, sizeof name, "model_%02d.pgm", d);
    paths.push_back((seq / name).string());
  }
  return paths;
}

NccBank::NccBank(const std::vector<app::GrayImage>& models, int range, double step_deg, int steps)
    : range_(range), step_(step_deg), steps_(steps) {
  for (const auto& m : models) models_.emplace_back(static_cast<int>(m.height), static_cast<int>(m.width), CV_8U,
                                                    const_cast<std::uint8_t*>(m.pixels.data()));
}

Pose NccBank::track(const app::GrayImage& frame, const Pose& previous) {
  const cv::Mat image(static_cast<int>(frame.height), static_cast<int>(frame.width), CV_8U, const_cast<std::uint8_t*>(frame.pixels.data()));
  double best = -2;
  Pose out = previous;
  for (std::size_t d = 0; d < models_.size(); ++d) {
    for (int s = -steps_; s <= steps_; ++s) {
      const double theta = previous.theta_deg + s * step_;
      const cv::Mat& templ = rotated(d, theta);
      const int cx = static_cast<int>(std::lround(previous.x)), cy = static_cast<int>(std::lround(previous.y));
      const cv::Rect window(cx - templ.cols / 2 - range_, cy - templ.rows / 2 - range_, templ.cols + 2 * range_, templ.rows + 2 * range_);
      if ((window & cv::Rect(0, 0, image.cols, image.rows)) != window) continue;
      cv::matchTemplate(image(window), templ, result_, cv::TM_CCOEFF_NORMED);
      double score = 0;
      cv::Point at;
      cv::minMaxLoc(result_, nullptr, &score, nullptr, &at);
      if (score > best) {
        best = score;
        out = {static_cast<float>(cx + at.x - range_), static_cast<float>(cy + at.y - range_), static_cast<float>(theta),
               static_cast<std::uint16_t>(d)};
      }
    }
  }
  return out;
}

const cv::Mat& NccBank::rotated(std::size_t depth, double theta) {
  const long key = static_cast<long>(depth) * 100000 + std::lround(std::fmod(std::fmod(theta, 360.0) + 360.0, 360.0) / 0.5);
  auto it = cache_.find(key);
  if (it != cache_.end()) return it->second;
  const cv::Mat& m = models_[depth];
  cv::Mat r;
  const cv::Mat rot = cv::getRotationMatrix2D(cv::Point2f(static_cast<float>(m.cols / 2), static_cast<float>(m.rows / 2)), -theta, 1.0);
  cv::warpAffine(m, r, rot, m.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(128));
  return cache_.emplace(key, r).first->second;
}

}  // namespace gabarit::bench
