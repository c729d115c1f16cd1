#include "gabarit/hil/faults.hpp"

#include <algorithm>
#include <cstdlib>
#include <sstream>

#include "gabarit/app/error.hpp"
#include "gabarit/app/files.hpp"
#include "gabarit/app/rng.hpp"
#include "gabarit/link/rig_faults.hpp"

namespace gabarit::hil {
namespace {

void check_plan(FaultPlan& plan, std::uint32_t frames, const std::string& where) {
  std::sort(plan.faults.begin(), plan.faults.end(), [](const PlannedFault& a, const PlannedFault& b) { return a.frame < b.frame; });
  for (std::size_t i = 0; i < plan.faults.size(); ++i) {
    const PlannedFault& f = plan.faults[i];
    if (f.frame >= frames)
      throw app::Error(where + ": a fault at frame " + std::to_string(f.frame) + ", the run has " + std::to_string(frames) + " frames");
    if (i > 0 && plan.faults[i - 1].frame == f.frame) throw app::Error(where + ": two faults at frame " + std::to_string(f.frame));
    if (f.kind == FaultKind::kReorder && f.frame + 1 >= frames)
      throw app::Error(where + ": reorder at frame " + std::to_string(f.frame) + " needs a frame after it");
    if (i > 0 && plan.faults[i - 1].kind == FaultKind::kReorder && plan.faults[i - 1].frame + 1 == f.frame)
      throw app::Error(where + ": a fault at frame " + std::to_string(f.frame) + ", which a reorder swaps with the one before");
  }
}

}  // namespace

const char* fault_name(FaultKind kind) {
  switch (kind) {
    case FaultKind::kDrop: return "drop";
    case FaultKind::kDuplicate: return "duplicate";
    case FaultKind::kReorder: return "reorder";
    case FaultKind::kCorrupt: return "corrupt";
    case FaultKind::kBitflip: return "bitflip";
    case FaultKind::kRestart: return "restart";
    default: return link::rig_fault_name(static_cast<link::RigFault>(rig_fault_number(kind)));
  }
}

FaultKind parse_fault_kind(const std::string& text, const std::string& where) {
  for (const FaultKind k : kAllFaultKinds)
    if (text == fault_name(k)) return k;
  for (const FaultKind k : kRigFaultKinds)
    if (text == fault_name(k)) return k;
  std::string all;
  for (const FaultKind k : kAllFaultKinds) all += std::string(all.empty() ? "" : ", ") + fault_name(k);
  for (const FaultKind k : kRigFaultKinds) all += std::string(", ") + fault_name(k);
  throw app::Error(where + ": unknown fault '" + text + "' (want one of " + all + ")");
}

const PlannedFault* FaultPlan::at(std::uint32_t frame) const {
  const auto it = std::lower_bound(faults.begin(), faults.end(), frame,
                                   [](const PlannedFault& f, std::uint32_t v) { return f.frame < v; });
  return it != faults.end() && it->frame == frame ? &*it : nullptr;
}

FaultPlan read_fault_file(const std::string& path, std::uint32_t frames) {
  std::istringstream in(app::read_text(path, 1u << 24));
  FaultPlan plan;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (const auto hash = line.find('#'); hash != std::string::npos) line.erase(hash);
    std::istringstream fields(line);
    std::string frame_text, kind_text, extra;
    if (!(fields >> frame_text)) continue;
    const std::string where = path + ":" + std::to_string(number);
    if (!(fields >> kind_text) || (fields >> extra)) throw app::Error(where + ": want 'FRAME KIND'");
    char* end = nullptr;
    const unsigned long frame = std::strtoul(frame_text.c_str(), &end, 10);
    if (frame_text.empty() || *end != '\0' || frame_text[0] == '-' || frame > 0xFFFFFFFEul)
      throw app::Error(where + ": frame '" + frame_text + "' is not a frame number");
    plan.faults.push_back({static_cast<std::uint32_t>(frame), parse_fault_kind(kind_text, where)});
  }
  check_plan(plan, frames, path);
  return plan;
}

FaultPlan random_fault_plan(double probability, std::uint32_t frames, std::uint64_t seed) {
  if (!(probability >= 0.0 && probability <= 1.0)) throw app::Error("--faults random:P wants 0 <= P <= 1");
  app::Rng rng(seed ^ 0xFA017ull);
  FaultPlan plan;
  for (std::uint32_t f = 0; f < frames; ++f) {
    const bool hit = rng.next_unit() < probability;
    auto kind = static_cast<FaultKind>(rng.uniform_int(0, 5));
    if (!hit) continue;
    if (!plan.faults.empty() && plan.faults.back().kind == FaultKind::kReorder && plan.faults.back().frame + 1 == f) continue;
    if (kind == FaultKind::kReorder && f + 1 >= frames) kind = FaultKind::kDrop;
    plan.faults.push_back({f, kind});
  }
  check_plan(plan, frames, "random plan");
  return plan;
}

FaultPlan cycle_fault_plan(std::uint32_t every, const std::vector<FaultKind>& kinds, std::uint32_t frames) {
  if (every < 2) throw app::Error("--faults cycle:N wants N >= 2 (a reorder swaps a frame with the next)");
  if (kinds.empty()) throw app::Error("--faults cycle:N:KINDS wants at least one kind");
  FaultPlan plan;
  std::size_t next = 0;
  for (std::uint64_t f = every; f + 1 < frames; f += every) plan.faults.push_back({static_cast<std::uint32_t>(f), kinds[next++ % kinds.size()]});
  check_plan(plan, frames, "cycle plan");
  return plan;
}

FaultPlan parse_fault_plan(const std::string& spec, std::uint32_t frames, std::uint64_t seed) {
  if (spec.rfind("cycle:", 0) == 0) {
    const std::string rest = spec.substr(6);
    const auto colon = rest.find(':');
    const std::string n = rest.substr(0, colon);
    char* end = nullptr;
    const unsigned long every = std::strtoul(n.c_str(), &end, 10);
    if (n.empty() || *end != '\0' || every > 0xFFFFFFFFul) throw app::Error("--faults '" + spec + "': want cycle:N:KIND,KIND,...");
    std::vector<FaultKind> kinds;
    if (colon == std::string::npos) {
      kinds.assign(std::begin(kAllFaultKinds), std::end(kAllFaultKinds));
    } else {
      std::stringstream list(rest.substr(colon + 1));
      for (std::string k; std::getline(list, k, ',');) kinds.push_back(parse_fault_kind(k, "--faults " + spec));
    }
    return cycle_fault_plan(static_cast<std::uint32_t>(every), kinds, frames);
  }
  if (spec.rfind("random:", 0) == 0) {
    const std::string p = spec.substr(7);
    char* end = nullptr;
    const double v = std::strtod(p.c_str(), &end);
    if (p.empty() || *end != '\0') throw app::Error("--faults '" + spec + "': want random:P with P a number");
    return random_fault_plan(v, frames, seed);
  }
  return read_fault_file(spec, frames);
}

std::string fault_file_text(const FaultPlan& plan) {
  std::string text = "# gabarit hil fault plan: FRAME KIND\n";
  for (const PlannedFault& f : plan.faults) text += std::to_string(f.frame) + " " + fault_name(f.kind) + "\n";
  return text;
}

}  // namespace gabarit::hil
