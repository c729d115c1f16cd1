#include "gabarit/host/runs/detection_run.hpp"

#include <chrono>
#include <cstdio>

#include "gabarit/app/error.hpp"

namespace gabarit::host {

std::string detection_csv_row(std::uint64_t frame, std::size_t rank, const Detection& d) {
  char buf[192];
  std::snprintf(buf, sizeof buf, "%llu,%zu,%.3f,%.3f,%.3f,%u,%.4f,%.4f,%.4f", static_cast<unsigned long long>(frame), rank,
                static_cast<double>(d.pose.x), static_cast<double>(d.pose.y), static_cast<double>(d.pose.theta_deg),
                static_cast<unsigned>(d.pose.depth), static_cast<double>(d.score), static_cast<double>(d.coarse_score),
                static_cast<double>(d.vote_score));
  return buf;
}

FinderOptions finder_options_from(const app::Args& args, const TableView& table) {
  FinderOptions o;
  o.max_count = static_cast<std::uint32_t>(args.integer("--max-count", o.max_count, 1, kMaxFinderCandidates));
  o.candidates = static_cast<std::uint32_t>(args.integer("--candidates", std::max(o.candidates, o.max_count), 1, kMaxFinderCandidates));
  if (o.candidates < o.max_count) throw app::UsageError("--candidates must be at least --max-count");
  o.min_score = static_cast<float>(args.number("--min-score", o.min_score, 0.0, 1.0));
  o.min_distance_px = static_cast<float>(args.number("--min-distance", 0.0, 0.0, 1.0e4));
  if (args.has("--theta-range")) {
    const std::string text = args.get("--theta-range");
    const std::size_t colon = text.find(':');
    if (colon == std::string::npos) throw app::UsageError("--theta-range '" + text + "': want A:B (degrees)");
    const std::vector<double> a = app::parse_number_list(text.substr(0, colon), "--theta-range", 1, 1);
    const std::vector<double> b = app::parse_number_list(text.substr(colon + 1), "--theta-range", 1, 1);
    if (!(a[0] <= b[0]) || a[0] < -3600 || b[0] > 3600) throw app::UsageError("--theta-range '" + text + "': want A <= B within +-3600");
    o.theta_min_deg = static_cast<float>(a[0]);
    o.theta_max_deg = static_cast<float>(b[0]);
  }
  o.theta_step_deg = static_cast<float>(args.number("--theta-step", 0.0, 0.05, 90.0));
  o.pyramid_factor = static_cast<std::uint32_t>(args.integer("--pyramid", 0, 1, kMaxPyramidFactor));
  o.orientation = !args.has("--position-only");
  (void)table;
  if (!valid(o)) throw app::UsageError("the detection options are not usable together");
  return o;
}

FrameDetector::FrameDetector(const TableView& table, const Detector& detector, const FinderOptions& options,
                             app::VoterChoice voter, bool focus_stack)
    : table_(table), detector_(detector), options_(options), finder_(table, detector), fine_(table, voter), stack_(table) {
  if (focus_stack) finder_.use_focus_stack(stack_.get());
  if (!valid(options)) throw app::Error("detection: invalid options");
  fallback_ = finder_geometry(table, detector, options, 1, 1);
}

FrameDetections FrameDetector::detect(const ImageView& frame) {
  if (!buffers_ || buffers_->width() != frame.width || buffers_->height() != frame.height)
    buffers_.emplace(table_, detector_, options_, frame.width, frame.height);
  FrameDetections r;
  r.detections.resize(options_.max_count);
  std::uint32_t count = 0;
  const auto t0 = std::chrono::steady_clock::now();
  const Status s = finder_.find(frame, options_, buffers_->scratch(fine_.scratch()), r.detections, count);
  r.micros = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
  if (s != Status::kOk) throw app::Error(std::string("detection: ") + status_name(s));
  r.detections.resize(count);
  return r;
}

}  // namespace gabarit::host
