#include "gabarit/app/evaluation.hpp"

#include <cctype>
#include <cmath>
#include <map>
#include <sstream>

#include "gabarit/app/error.hpp"
#include "gabarit/app/files.hpp"

namespace gabarit::app {

namespace {

// A whole field as a number: finite and within +-1e9 (so every error computed
// from it is finite too), nothing after it.
double finite_field(const std::string& f) {
  std::size_t used = 0;
  const double v = std::stod(f, &used);
  if (used != f.size() || !std::isfinite(v) || std::fabs(v) > 1e9) throw std::invalid_argument("not a finite number");
  return v;
}

// A whole field as an integer in [0, max].
std::uint32_t count_field(const std::string& f, std::uint32_t max) {
  if (f.empty() || !std::isdigit(static_cast<unsigned char>(f[0]))) throw std::invalid_argument("not a count");
  std::size_t used = 0;
  const unsigned long long v = std::stoull(f, &used);
  if (used != f.size() || v > max) throw std::out_of_range("count out of range");
  return static_cast<std::uint32_t>(v);
}

}  // namespace

std::vector<PoseSample> read_pose_csv(const std::string& path) {
  std::istringstream in(read_text(path));
  return read_pose_csv(in, path);
}

std::vector<PoseSample> read_pose_csv(std::istream& in, const std::string& path) {
  std::string line;
  if (!std::getline(in, line) || line.rfind("frame,x,y,theta_deg,depth", 0) != 0) {
    throw app::Error(path + ":1: expected header starting 'frame,x,y,theta_deg,depth'");
  }
  const bool has_visible = line.find(",visible") != std::string::npos;
  std::vector<PoseSample> out;
  for (std::size_t n = 2; std::getline(in, line); ++n) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    std::vector<std::string> fields;
    std::stringstream ss(line);
    std::string f;
    while (std::getline(ss, f, ',')) fields.push_back(f);
    try {
      if (fields.size() < 5) throw std::invalid_argument("too few fields");
      PoseSample s;
      s.frame = count_field(fields[0], 0xFFFFFFFFu);
      s.x = finite_field(fields[1]);
      s.y = finite_field(fields[2]);
      s.theta_deg = finite_field(fields[3]);
      s.depth = count_field(fields[4], 0xFFFFu);
      if (has_visible && fields.size() >= 6) s.visible = count_field(fields[5], 1) != 0;
      out.push_back(s);
    } catch (const std::exception&) {
      throw app::Error(path + ":" + std::to_string(n) + ": malformed row '" + line.substr(0, 200) +
                       "' (want frame,x,y,theta_deg,depth with a count, finite numbers and a depth count)");
    }
  }
  return out;
}

Accuracy evaluate(const std::vector<PoseSample>& poses, const std::vector<PoseSample>& truth) {
  std::map<std::uint32_t, const PoseSample*> by_frame;
  for (const PoseSample& p : poses) by_frame[p.frame] = &p;
  Accuracy a;
  double sum = 0, sum_deg = 0;
  bool hidden_before = false;
  int pending = -1;  // frames since the last return to visibility, while not reacquired
  bool on_target = true;  // the previous visible frame within 5 px (true before the first)
  for (const PoseSample& t : truth) {
    if (!t.visible) {
      hidden_before = true;
      continue;
    }
    if (hidden_before) {
      if (pending >= 0) a.reacquired_after.push_back(-1);  // hidden again before reacquiring
      pending = 0;
      hidden_before = false;
    }
    const auto it = by_frame.find(t.frame);
    if (it == by_frame.end()) {
      ++a.missing;
      continue;
    }
    const double dx = it->second->x - t.x, dy = it->second->y - t.y;
    const double e = std::hypot(dx, dy);
    ++a.frames;
    sum += e;
    a.max_error_px = std::max(a.max_error_px, e);
    if (std::fabs(dx) < 0.5 && std::fabs(dy) < 0.5) {
      ++a.exact;
    } else {
      a.wrong_frames.push_back(t.frame);
    }
    if (e <= 1.0) ++a.within_1px;
    if (e <= 2.0) ++a.within_2px;
    if (e <= 5.0) ++a.within_5px;
    a.below_6px += e < 6.0, a.below_12px += e < 12.0, a.above_12px += e > 12.0, a.above_20px += e > 20.0, a.above_40px += e > 40.0;
    if (e > 5.0 && on_target) ++a.failures;
    on_target = e <= 5.0;
    const double de = std::fabs(it->second->theta_deg - t.theta_deg);
    sum_deg += de;
    a.max_error_deg = std::max(a.max_error_deg, de);
    if (de <= 1.0) ++a.within_1deg;
    if (it->second->depth == t.depth) ++a.depth_exact;
    if (pending >= 0) {
      if (e <= 2.0) {
        a.reacquired_after.push_back(pending);
        pending = -1;
      } else {
        ++pending;
      }
    }
  }
  if (pending >= 0) a.reacquired_after.push_back(-1);
  a.mean_error_px = a.frames ? sum / static_cast<double>(a.frames) : 0;
  a.mean_error_deg = a.frames ? sum_deg / static_cast<double>(a.frames) : 0;
  return a;
}

std::string accuracy_json(const Accuracy& a) {
  std::ostringstream o;
  o << "{\n  \"frames\": " << a.frames << ",\n  \"exact\": " << a.exact << ",\n  \"wrong\": " << a.wrong_frames.size()
    << ",\n  \"missing\": " << a.missing << ",\n  \"within_1px\": " << a.within_1px << ",\n  \"within_2px\": " << a.within_2px
    << ",\n  \"within_5px\": " << a.within_5px << ",\n  \"below_6px\": " << a.below_6px << ",\n  \"below_12px\": " << a.below_12px
    << ",\n  \"above_12px\": " << a.above_12px << ",\n  \"above_20px\": " << a.above_20px
    << ",\n  \"above_40px\": " << a.above_40px << ",\n  \"failures\": " << a.failures
    << ",\n  \"mean_error_px\": " << a.mean_error_px << ",\n  \"max_error_px\": " << a.max_error_px
    << ",\n  \"within_1deg\": " << a.within_1deg << ",\n  \"mean_error_deg\": " << a.mean_error_deg
    << ",\n  \"max_error_deg\": " << a.max_error_deg << ",\n  \"depth_exact\": " << a.depth_exact
    << ",\n  \"reacquired_after_frames\": [";
  for (std::size_t i = 0; i < a.reacquired_after.size(); ++i) o << (i ? ", " : "") << a.reacquired_after[i];
  o << "],\n  \"wrong_frames\": [";
  for (std::size_t i = 0; i < a.wrong_frames.size() && i < 100; ++i) o << (i ? ", " : "") << a.wrong_frames[i];
  o << "]\n}\n";
  return o.str();
}

}  // namespace gabarit::app
