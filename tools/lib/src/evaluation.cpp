#include "gabarit/host/evaluation.hpp"

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include "gabarit/host/error.hpp"

namespace gabarit::host {

std::vector<PoseSample> read_pose_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open");
  std::string line;
  if (!std::getline(in, line) || line.rfind("frame,x,y,theta_deg,depth", 0) != 0) {
    throw Error(path + ":1: expected header starting 'frame,x,y,theta_deg,depth'");
  }
  const bool has_visible = line.find(",visible") != std::string::npos;
  std::vector<PoseSample> out;
  for (std::size_t n = 2; std::getline(in, line); ++n) {
    if (line.empty()) continue;
    std::vector<std::string> fields;
    std::stringstream ss(line);
    std::string f;
    while (std::getline(ss, f, ',')) fields.push_back(f);
    try {
      if (fields.size() < 5) throw std::invalid_argument("too few fields");
      PoseSample s;
      s.frame = static_cast<std::uint32_t>(std::stoul(fields[0]));
      s.x = std::stod(fields[1]);
      s.y = std::stod(fields[2]);
      s.theta_deg = std::stod(fields[3]);
      s.depth = static_cast<std::uint32_t>(std::stoul(fields[4]));
      if (has_visible && fields.size() >= 6) s.visible = std::stoi(fields[5]) != 0;
      out.push_back(s);
    } catch (const std::exception&) {
      throw Error(path + ":" + std::to_string(n) + ": malformed row '" + line + "'");
    }
  }
  return out;
}

Accuracy evaluate(const std::vector<PoseSample>& poses, const std::vector<PoseSample>& truth) {
  std::map<std::uint32_t, const PoseSample*> by_frame;
  for (const PoseSample& p : poses) by_frame[p.frame] = &p;
  Accuracy a;
  double sum = 0;
  for (const PoseSample& t : truth) {
    if (!t.visible) continue;
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
  }
  a.mean_error_px = a.frames ? sum / static_cast<double>(a.frames) : 0;
  return a;
}

std::string accuracy_json(const Accuracy& a) {
  std::ostringstream o;
  o << "{\n  \"frames\": " << a.frames << ",\n  \"exact\": " << a.exact << ",\n  \"wrong\": " << a.wrong_frames.size()
    << ",\n  \"missing\": " << a.missing << ",\n  \"within_1px\": " << a.within_1px << ",\n  \"within_2px\": " << a.within_2px
    << ",\n  \"mean_error_px\": " << a.mean_error_px << ",\n  \"max_error_px\": " << a.max_error_px
    << ",\n  \"wrong_frames\": [";
  for (std::size_t i = 0; i < a.wrong_frames.size() && i < 100; ++i) o << (i ? ", " : "") << a.wrong_frames[i];
  o << "]\n}\n";
  return o.str();
}

}  // namespace gabarit::host
