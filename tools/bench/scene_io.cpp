#include "scene_io.hpp"

#include <opencv2/imgproc.hpp>
#if GABARIT_HAVE_OPENCV_TRACKING
#include <opencv2/tracking.hpp>
#include <opencv2/tracking/tracking_legacy.hpp>
#endif

#include <algorithm>
#include <chrono>
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

namespace gabarit::bench {

PyramidMatcher::PyramidMatcher(const std::vector<app::GrayImage>& models, int levels, double coarse_step_deg, int candidates)
    : levels_(levels), candidates_(candidates), step_(coarse_step_deg) {
  for (const auto& m : models)
    models_.push_back(cv::Mat(static_cast<int>(m.height), static_cast<int>(m.width), CV_8U, const_cast<std::uint8_t*>(m.pixels.data())).clone());
  const int angles = static_cast<int>(std::lround(360.0 / step_));
  for (const cv::Mat& m : models_) {
    std::vector<cv::Mat> bank;
    for (int a = 0; a < angles; ++a) {
      cv::Mat r = rotated(m, -180.0 + a * step_);
      for (int l = 0; l < levels_; ++l) cv::pyrDown(r, r);
      bank.push_back(r);
    }
    coarse_bank_.push_back(std::move(bank));
  }
}

cv::Mat PyramidMatcher::rotated(const cv::Mat& m, double theta) const {
  cv::Mat r;
  const cv::Mat rot = cv::getRotationMatrix2D(cv::Point2f(static_cast<float>(m.cols / 2), static_cast<float>(m.rows / 2)), -theta, 1.0);
  cv::warpAffine(m, r, rot, m.size(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  return r;
}

std::vector<PyramidDetection> PyramidMatcher::detect(const app::GrayImage& frame) {
  const cv::Mat image(static_cast<int>(frame.height), static_cast<int>(frame.width), CV_8U, const_cast<std::uint8_t*>(frame.pixels.data()));
  cv::Mat top = image;
  for (int l = 0; l < levels_; ++l) cv::pyrDown(top, top);
  const double scale = static_cast<double>(1 << levels_);
  struct Peak { double x, y, theta, score; std::size_t depth; };
  std::vector<Peak> peaks;
  const double min_dist = 0.5 * std::min(models_[0].cols, models_[0].rows) / scale;
  cv::Mat result;
  for (std::size_t d = 0; d < coarse_bank_.size(); ++d)
    for (std::size_t a = 0; a < coarse_bank_[d].size(); ++a) {
      const cv::Mat& t = coarse_bank_[d][a];
      if (t.cols > top.cols || t.rows > top.rows) continue;
      cv::matchTemplate(top, t, result, cv::TM_CCOEFF_NORMED);
      // The best few local maxima of this angle (suppressing around each).
      for (int k = 0; k < candidates_; ++k) {
        double score = 0;
        cv::Point at;
        cv::minMaxLoc(result, nullptr, &score, nullptr, &at);
        const Peak p{at.x + t.cols / 2.0, at.y + t.rows / 2.0, -180.0 + static_cast<double>(a) * step_, score, d};
        cv::circle(result, at, std::max(1, static_cast<int>(min_dist)), cv::Scalar(-2), -1);
        bool merged = false;
        for (Peak& q : peaks)
          if (std::hypot(q.x - p.x, q.y - p.y) < min_dist) {
            if (p.score > q.score) q = p;
            merged = true;
            break;
          }
        if (!merged) peaks.push_back(p);
      }
    }
  std::sort(peaks.begin(), peaks.end(), [](const Peak& a, const Peak& b) { return a.score > b.score; });
  if (peaks.size() > static_cast<std::size_t>(candidates_)) peaks.resize(static_cast<std::size_t>(candidates_));
  std::vector<PyramidDetection> out;
  const int reach = (1 << levels_) + 1;
  for (const Peak& p : peaks) {
    const double cx = p.x * scale + (scale - 1) / 2, cy = p.y * scale + (scale - 1) / 2;
    PyramidDetection best{{static_cast<float>(cx), static_cast<float>(cy), static_cast<float>(p.theta), static_cast<std::uint16_t>(p.depth)}, -2};
    const auto match = [&](std::size_t depth, double theta) {
      const cv::Mat t = rotated(models_[depth], theta);
      const int x0 = static_cast<int>(std::lround(cx)) - t.cols / 2 - reach, y0 = static_cast<int>(std::lround(cy)) - t.rows / 2 - reach;
      const cv::Rect window = cv::Rect(x0, y0, t.cols + 2 * reach, t.rows + 2 * reach) & cv::Rect(0, 0, image.cols, image.rows);
      if (window.width < t.cols || window.height < t.rows) return;
      cv::matchTemplate(image(window), t, result, cv::TM_CCOEFF_NORMED);
      double score = 0;
      cv::Point at;
      cv::minMaxLoc(result, nullptr, &score, nullptr, &at);
      if (score > best.score)
        best = {{static_cast<float>(window.x + at.x + t.cols / 2), static_cast<float>(window.y + at.y + t.rows / 2),
                 static_cast<float>(theta), static_cast<std::uint16_t>(depth)}, score};
    };
    for (double dt = -step_ / 2; dt <= step_ / 2 + 1e-9; dt += 0.5) match(p.depth, p.theta + dt);
    const double theta = best.pose.theta_deg;
    for (std::size_t d = 0; d < models_.size(); ++d)
      if (d != p.depth) match(d, theta);
    out.push_back(best);
  }
  std::sort(out.begin(), out.end(), [](const PyramidDetection& a, const PyramidDetection& b) { return a.score > b.score; });
  return out;
}

#if GABARIT_HAVE_OPENCV_TRACKING
void opencv_box_trackers(const std::vector<app::GrayImage>& frames, const std::vector<app::GrayImage>& model_images, const Pose& init,
                         std::vector<MethodRun>& runs) {
  std::vector<cv::Mat> bgr;
  for (const auto& f : frames) {
    cv::Mat m;
    cv::cvtColor(cv::Mat(static_cast<int>(f.height), static_cast<int>(f.width), CV_8U, const_cast<std::uint8_t*>(f.pixels.data())), m,
                 cv::COLOR_GRAY2BGR);
    bgr.push_back(m);
  }
  const int side = model_images[0].width > 16 ? static_cast<int>(model_images[0].width) - 16 : static_cast<int>(model_images[0].width);
  const cv::Rect box(static_cast<int>(std::lround(init.x)) - side / 2, static_cast<int>(std::lround(init.y)) - side / 2, side, side);
  const auto run_cv = [&](const std::string& name, auto&& init_tracker, auto&& update) {
    MethodRun r{name, {}, 0, {}};
    double total = 0;
    cv::Rect2d at = box;  // a failed update keeps the last box
    for (std::uint32_t f = 0; f < frames.size(); ++f) {
      const auto t = std::chrono::steady_clock::now();
      if (f == 0) init_tracker(bgr[f], box);
      else update(bgr[f], at);
      r.micros.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t).count());
      total += r.micros.back();
      r.poses.push_back({f, at.x + at.width / 2, at.y + at.height / 2, 0, 0, true});
    }
    r.mean_us = total / static_cast<double>(frames.size());
    r.position_only = true;
    runs.push_back(r);
  };
  {
    cv::Ptr<cv::legacy::TrackerMOSSE> mosse = cv::legacy::TrackerMOSSE::create();
    run_cv("OpenCV MOSSE (position only)", [&](const cv::Mat& m, const cv::Rect& b) { mosse->init(m, cv::Rect2d(b)); },
           [&](const cv::Mat& m, cv::Rect2d& b) { mosse->update(m, b); });
  }
  for (const bool csrt : {false, true}) {
    cv::Ptr<cv::Tracker> tracker = csrt ? cv::Ptr<cv::Tracker>(cv::TrackerCSRT::create()) : cv::Ptr<cv::Tracker>(cv::TrackerKCF::create());
    run_cv(csrt ? "OpenCV CSRT (position only)" : "OpenCV KCF (position only)",
           [&](const cv::Mat& m, const cv::Rect& b) { tracker->init(m, b); },
           [&](const cv::Mat& m, cv::Rect2d& b) {
             cv::Rect r;
             if (tracker->update(m, r)) b = r;
           });
  }
}
#else
void opencv_box_trackers(const std::vector<app::GrayImage>&, const std::vector<app::GrayImage>&, const Pose&, std::vector<MethodRun>&) {}
#endif

}  // namespace gabarit::bench
