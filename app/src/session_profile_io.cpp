#include "gabarit/app/session_profile_io.hpp"

#include <algorithm>
#include <charconv>
#include <limits>
#include <set>

#include "gabarit/app/error.hpp"
#include "gabarit/app/files.hpp"

namespace gabarit::app {

namespace {

struct ImprovementName {
  const char* word;
  std::uint32_t bit;
};
constexpr ImprovementName kImprovementNames[] = {
    {"modes", kImproveModes},         {"disambiguation", kImproveDisambiguation}, {"narrowing", kImproveNarrowing},
    {"kinematics", kImproveKinematics}, {"reinit", kImproveReinit},               {"mode-filter", kImproveModeFilter},
    {"velocity", kImproveVelocity},   {"proposals", kImproveProposals},           {"detection", kImproveDetection},
    {"all", kAllImprovements}};

const char* recovery_name(RecoveryKind kind) {
  switch (kind) {
    case RecoveryKind::kGrid: return "grid";
    case RecoveryKind::kDetection: return "detect";
    case RecoveryKind::kParticles: return "particle";
    case RecoveryKind::kAuto: return "auto";
  }
  return "grid";
}

RecoveryKind parse_recovery(const std::string& text, const std::string& what) {
  if (text == "grid") return RecoveryKind::kGrid;
  if (text == "detect") return RecoveryKind::kDetection;
  if (text == "particle") return RecoveryKind::kParticles;
  if (text == "auto") return RecoveryKind::kAuto;
  throw UsageError(what + " '" + text + "': want auto, grid, detect or particle");
}

TrackerKind parse_tracker(const std::string& text, const std::string& what) {
  if (text == "stencil") return TrackerKind::kStencil;
  if (text == "particle") return TrackerKind::kParticle;
  throw UsageError(what + " '" + text + "': want stencil or particle");
}

ParticleMeasureKind parse_measure(const std::string& text, const std::string& what) {
  if (text == "auto") return ParticleMeasureKind::kAuto;
  if (text == "edges") return ParticleMeasureKind::kEdges;
  if (text == "stencil") return ParticleMeasureKind::kStencil;
  if (text == "intensity") return ParticleMeasureKind::kIntensity;
  throw UsageError(what + " '" + text + "': want auto, intensity, edges or stencil");
}

SubCellKind parse_subcell(const std::string& text, const std::string& what) {
  if (text == "parabola") return SubCellKind::kParabola;
  if (text == "alignment") return SubCellKind::kAlignment;
  throw UsageError(what + " '" + text + "': want parabola or alignment");
}

RefineBy parse_verify_refine(const std::string& text, const std::string& what) {
  if (text == "gauss-newton") return RefineBy::kGaussNewton;
  if (text == "quadratic") return RefineBy::kQuadraticDesign;
  throw UsageError(what + " '" + text + "': want gauss-newton or quadratic");
}

ModeClustering parse_mode_clustering(const std::string& text, const std::string& what) {
  if (text == "seed") return ModeClustering::kSeed;
  if (text == "running-mean") return ModeClustering::kRunningMean;
  throw UsageError(what + " '" + text + "': want seed or running-mean");
}

bool parse_bool(const std::string& text, const std::string& what) {
  if (text == "true") return true;
  if (text == "false") return false;
  throw UsageError(what + " '" + text + "': want true or false");
}

std::uint64_t parse_count(const std::string& text, const std::string& what, std::uint64_t lo, std::uint64_t hi) {
  std::uint64_t v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size() || text.empty() || v < lo || v > hi) {
    throw UsageError(what + " '" + text + "': want an integer in " + std::to_string(lo) + ".." + std::to_string(hi));
  }
  return v;
}

// One key of the profile: its name (the option's, without the dashes), how
// it is written and how it is read. The text file and the command line read
// values through the same `set`, so their ranges cannot drift apart.
struct Key {
  const char* name;
  std::string (*get)(const SessionProfile&);
  void (*set)(SessionProfile&, const std::string& value, const std::string& what);
};

std::string yes(bool b) { return b ? "true" : "false"; }

const Key kKeys[] = {
    {"tracker", [](const SessionProfile& p) { return std::string(p.tracker == TrackerKind::kParticle ? "particle" : "stencil"); },
     [](SessionProfile& p, const std::string& v, const std::string& w) { p.tracker = parse_tracker(v, w); }},
    {"measure", [](const SessionProfile& p) { return std::string(name_of(p.particle_measure)); },
     [](SessionProfile& p, const std::string& v, const std::string& w) { p.particle_measure = parse_measure(v, w); }},
    {"plain", [](const SessionProfile& p) { return yes(p.plain); },
     [](SessionProfile& p, const std::string& v, const std::string& w) { p.plain = parse_bool(v, w); }},
    {"motion-filter", [](const SessionProfile& p) { return yes(p.motion_filter); },
     [](SessionProfile& p, const std::string& v, const std::string& w) { p.motion_filter = parse_bool(v, w); }},
    {"refine", [](const SessionProfile& p) { return yes(p.refine); },
     [](SessionProfile& p, const std::string& v, const std::string& w) { p.refine = parse_bool(v, w); }},
    {"recover", [](const SessionProfile& p) { return yes(p.recover); },
     [](SessionProfile& p, const std::string& v, const std::string& w) { p.recover = parse_bool(v, w); }},
    {"recovery", [](const SessionProfile& p) { return std::string(recovery_name(p.recovery)); },
     [](SessionProfile& p, const std::string& v, const std::string& w) { p.recovery = parse_recovery(v, w); }},
    {"subcell", [](const SessionProfile& p) { return std::string(p.subcell == SubCellKind::kAlignment ? "alignment" : "parabola"); },
     [](SessionProfile& p, const std::string& v, const std::string& w) { p.subcell = parse_subcell(v, w); }},
    {"shared-search", [](const SessionProfile& p) { return yes(p.shared_search); },
     [](SessionProfile& p, const std::string& v, const std::string& w) { p.shared_search = parse_bool(v, w); }},
    {"focus-stack", [](const SessionProfile& p) { return yes(p.focus_stack); },
     [](SessionProfile& p, const std::string& v, const std::string& w) { p.focus_stack = parse_bool(v, w); }},
    {"verify", [](const SessionProfile& p) { return yes(p.verify); },
     [](SessionProfile& p, const std::string& v, const std::string& w) { p.verify = parse_bool(v, w); }},
    {"verify-refine",
     [](const SessionProfile& p) { return std::string(p.verify_refine == RefineBy::kQuadraticDesign ? "quadratic" : "gauss-newton"); },
     [](SessionProfile& p, const std::string& v, const std::string& w) { p.verify_refine = parse_verify_refine(v, w); }},
    {"search-budget", [](const SessionProfile& p) { return std::to_string(p.search_budget); },
     [](SessionProfile& p, const std::string& v, const std::string& w) {
       p.search_budget = static_cast<std::uint32_t>(parse_count(v, w, 0, kSearchPlacementCount - kSearchNear));
     }},
    {"search-interval", [](const SessionProfile& p) { return std::to_string(p.search_interval); },
     [](SessionProfile& p, const std::string& v, const std::string& w) {
       p.search_interval = static_cast<std::uint32_t>(parse_count(v, w, 1, 100));
     }},
    {"screen-stride", [](const SessionProfile& p) { return std::to_string(p.screen_stride); },
     [](SessionProfile& p, const std::string& v, const std::string& w) {
       p.screen_stride = static_cast<std::uint32_t>(parse_count(v, w, 1, 16));
     }},
    {"detect-after", [](const SessionProfile& p) { return std::to_string(p.detect_after); },
     [](SessionProfile& p, const std::string& v, const std::string& w) {
       p.detect_after = static_cast<std::uint32_t>(parse_count(v, w, 0, 1000));
     }},
    {"recovery-frames", [](const SessionProfile& p) { return std::to_string(p.recovery_frames); },
     [](SessionProfile& p, const std::string& v, const std::string& w) {
       p.recovery_frames = static_cast<std::uint32_t>(parse_count(v, w, 0, 1000));
     }},
    {"survey-frames", [](const SessionProfile& p) { return std::to_string(p.survey_frames); },
     [](SessionProfile& p, const std::string& v, const std::string& w) {
       p.survey_frames = static_cast<std::uint32_t>(parse_count(v, w, 0, 1000));
     }},
    {"particles", [](const SessionProfile& p) { return std::to_string(p.particles); },
     [](SessionProfile& p, const std::string& v, const std::string& w) {
       p.particles = static_cast<std::uint32_t>(parse_count(v, w, 1, 1000000));
     }},
    {"seed", [](const SessionProfile& p) { return std::to_string(p.seed); },
     [](SessionProfile& p, const std::string& v, const std::string& w) {
       p.seed = parse_count(v, w, 0, static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()));
     }},
    {"edge-stride", [](const SessionProfile& p) { return std::to_string(p.edge_stride); },
     [](SessionProfile& p, const std::string& v, const std::string& w) {
       p.edge_stride = static_cast<std::uint32_t>(parse_count(v, w, 1, 64));
     }},
    {"edge-tolerance", [](const SessionProfile& p) { return std::to_string(p.edge_tolerance); },
     [](SessionProfile& p, const std::string& v, const std::string& w) {
       p.edge_tolerance = static_cast<std::uint32_t>(parse_count(v, w, 0, 3));
     }},
    {"without", [](const SessionProfile& p) { return improvements_off_list(p.particle_improvements_off); },
     [](SessionProfile& p, const std::string& v, const std::string& w) {
       p.particle_improvements_off = v.empty() ? 0u : parse_improvements_off(v, w);
     }},
    {"mode-clustering",
     [](const SessionProfile& p) {
       return std::string(p.particle_clustering == ModeClustering::kRunningMean ? "running-mean" : "seed");
     },
     [](SessionProfile& p, const std::string& v, const std::string& w) { p.particle_clustering = parse_mode_clustering(v, w); }},
};

const Key* find_key(std::string_view name) {
  for (const Key& k : kKeys)
    if (name == k.name) return &k;
  return nullptr;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

// The session's parts that only the thesis's loop can leave out.
void check(const SessionProfile& p, const std::string& origin) {
  if (validate(p) == Status::kOk) return;
  if (p.tracker == TrackerKind::kParticle && p.plain) throw UsageError(origin + "tracker particle is not the thesis's loop: drop plain");
  if (p.tracker == TrackerKind::kStencil && p.particle_measure != ParticleMeasureKind::kAuto)
    throw UsageError(origin + "measure applies to tracker particle");
  if (needs_recovery(p.recovery) && !recovers(p))
    throw UsageError(origin + "recovery " + recovery_name(p.recovery) + " needs recovery: drop plain or add recover");
  if (p.subcell != SubCellKind::kParabola && !refines(p))
    throw UsageError(origin + "subcell alignment needs refinement: drop plain or add refine");
  throw UsageError(origin + "the profile is not valid");
}

}  // namespace

std::uint32_t parse_improvements_off(const std::string& list, const std::string& what) {
  std::uint32_t off = 0;
  for (std::size_t start = 0; start <= list.size();) {
    const std::size_t comma = std::min(list.find(',', start), list.size());
    const std::string word = list.substr(start, comma - start);
    const auto* it = std::find_if(std::begin(kImprovementNames), std::end(kImprovementNames),
                                  [&](const ImprovementName& n) { return word == n.word; });
    if (it == std::end(kImprovementNames))
      throw UsageError(what + ": '" + word + "' is none of modes, disambiguation, narrowing, kinematics, reinit, mode-filter, velocity, proposals, all");
    off |= it->bit;
    start = comma + 1;
  }
  return off;
}

std::string improvements_off_list(std::uint32_t off) {
  std::string list;
  for (const ImprovementName& n : kImprovementNames) {
    if ((off & n.bit) == 0) continue;
    if (!list.empty()) list += ',';
    list += n.word;
  }
  return list;
}

std::string format_profile(const SessionProfile& profile) {
  std::string text = std::string(kProfileMagic) + '\n';
  for (const Key& k : kKeys) text += std::string(k.name) + " = " + k.get(profile) + '\n';
  return text;
}

SessionProfile parse_profile(std::string_view text, const std::string& origin) {
  SessionProfile p;
  std::set<std::string> seen;
  std::size_t line_no = 0;
  bool magic = false;
  for (std::size_t start = 0; start < text.size();) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = trim(text.substr(start, end - start));
    start = end + 1;
    ++line_no;
    const std::string where = origin + ":" + std::to_string(line_no) + ": ";
    if (!magic) {
      if (line != kProfileMagic) throw Error(where + "not a session profile (the first line must be '" + std::string(kProfileMagic) + "')");
      magic = true;
      continue;
    }
    if (line.empty() || line.front() == '#') continue;
    const std::size_t eq = line.find('=');
    if (eq == std::string_view::npos) throw Error(where + "want 'key = value'");
    const std::string key(trim(line.substr(0, eq)));
    const Key* k = find_key(key);
    if (k == nullptr) throw Error(where + "unknown key '" + key + "'");
    if (!seen.insert(key).second) throw Error(where + "'" + key + "' given twice");
    try {
      k->set(p, std::string(trim(line.substr(eq + 1))), key);
    } catch (const UsageError& e) {
      throw Error(where + e.what());
    }
  }
  if (!magic) throw Error(origin + ": empty, not a session profile");
  try {
    check(p, "");
  } catch (const UsageError& e) {
    throw Error(origin + ": " + e.what());
  }
  return p;
}

SessionProfile read_profile(const std::string& path) {
  const std::vector<std::byte> bytes = read_file(path);
  if (bytes.size() > 65536) throw Error(path + ": too large for a session profile (" + std::to_string(bytes.size()) + " bytes)");
  return parse_profile(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()), path);
}

std::vector<Option> session_option_group() {
  const std::string indent = "\n                          ";
  return {
      {"--profile", "FILE", "a session profile (docs/file-formats.md) to start from; the options below change it"},
      {"--tracker", "stencil|particle", "stencil (default): the stencil session; particle: the thesis's" + indent +
                                            "particle filter (chapter 3, docs/particle-filter.md) with the table's model"},
      {"--measure", "auto|intensity|edges|stencil", "--tracker particle: the session's verified score (the model image's" + indent +
                                                   "correlation with the frame on at most 256 of its samples; the default" + indent +
                                                   "for a table with model images), edge correlation over the table's" + indent +
                                                   "model points (the default without), or the stencil vote of each" + indent +
                                                   "particle's cell"},
      {"--plain", "", "the thesis's loop: the best cell of each frame, no filter, refinement, recovery or" + indent +
                          "focus stack (add --motion-filter, --refine or --recover to it one by one)"},
      {"--motion-filter", "", "with --plain: predict the ROI, gate candidates, grade confidence (default on)"},
      {"--refine", "", "with --plain: sub-cell x, y, theta from the neighbouring cells' scores (default on)"},
      {"--recover", "", "with --plain: once lost, search around the last confident pose (default on)"},
      {"--recovery", "auto|grid|detect|particle", "how the session re-acquires a lost target: the grid search around where" + indent +
                                                 "it was last seen, detection over the whole frame (with a focus stack, also poses" + indent +
                                                 "near the last sighting scored by intensity; docs/detection.md), or a" + indent +
                                                 "particle filter over the whole frame (docs/particle-filter.md); auto (default):" + indent +
                                                 "detection with a grayscale table that carries model images, else the grid"},
      {"--detect-after", "N", "--recovery detect (and auto): the first N lost frames search with the grid, the later ones" + indent +
                                  "by detection (default 0: detection from the first)"},
      {"--recovery-frames", "N", "--recovery detect (and auto): a lost frame's detection work, in tracked frames'" + indent +
                                     "work; a search that needs more goes on over the next frames, on the frame it" + indent +
                                     "began on, and what it finds is caught up with (docs/detection.md); 0..1000" + indent +
                                     "(default 0: each search in one frame)"},
      {"--survey-frames", "N", "--recovery detect (and auto), verifying: the look-alike survey's work after each" + indent +
                                   "tracked frame, in tracked frames' work (at least 10 units a pixel of the frame)," + indent +
                                   "until it has covered the frame; 0..1000 (default 2; 0: the whole survey after" + indent +
                                   "the first frame)"},
      {"--subcell", "parabola|alignment", "how refinement places the pose within the cell: a parabola through the" + indent +
                                              "neighbouring cells' scores (default), or a least-squares alignment of the" + indent +
                                              "matched features (docs/tracking.md compares them)"},
      {"--search-budget", "N", "recovery grid placements per search beyond the nearest 9, 1..558 (default: all" + indent +
                                   "558; fewer cost less and cover the grid over several searches)"},
      {"--screen-stride", "N", "recovery placements are screened with every N-th feature, 1..16 (default 2)"},
      {"--search-interval", "N", "search every N-th lost frame, 1..100 (default 1; the frames between only" + indent +
                                     "predict, so a lost period costs about 1/N)"},
      {"--no-focus-stack", "", "ignore the table's model images: depth from the winning stencils only"},
      {"--no-verify", "", "the vote's choice as it is: no correlation of the model images to decide between" + indent +
                              "proposals and refine the pose (docs/tracking.md, \"Vote, then verify\")"},
      {"--verify-refine", "gauss-newton|quadratic", "how verification refines the winner on the correlation: Gauss-Newton" + indent +
                                                      "steps (default), or a quadratic fitted to 19 correlations a round" + indent +
                                                      "(several times the cost; docs/tracking.md compares them)"},
      {"--particles", "N", "--recovery particle (and --tracker particle): particles, 1..1000000 (default 1000)"},
      {"--seed", "S", "--recovery particle (and --tracker particle): the generator's seed (default 1); same" + indent +
                          "seed, same output"},
      {"--edge-stride", "N", "the particle filter's edge measure: every N-th model point, 1..64 (default 2)"},
      {"--edge-tolerance", "PX", "the particle filter's edge measure: a point within PX pixels of an edge" + indent +
                                     "counts, 0..3 (default 0)"},
      {"--without", "LIST", "the particle filter's improvements to switch off, comma-separated: modes," + indent +
                                "disambiguation, narrowing, kinematics, reinit, mode-filter, velocity," + indent +
                                "proposals (--tracker particle: half the cloud drawn around the stencil" + indent +
                                "vote's best cells), detection (--tracker particle: while lost, the" + indent +
                                "model searched for where the target can be, on tables that verify);" + indent +
                                "all: plain CONDENSATION"},
      {"--mode-clustering", "seed|running-mean", "how the particle filter groups particles into modes: within the mode" + indent +
                                                   "radius of a mode's heaviest particle (default), or of its running" + indent +
                                                   "mean, a new mode only from a particle >= 5% of the heaviest's weight" + indent +
                                                   "(docs/particle-filter.md compares them)"},
      {"--save-profile", "FILE", "write the profile these options describe (the run goes on)"},
  };
}

SessionProfile read_session_profile(const Args& args) {
  SessionProfile p = args.has("--profile") ? read_profile(args.get("--profile")) : SessionProfile{};
  // Numbers keep the command line's historical messages: "--search-budget '0': ...".
  const auto number = [&](const char* option, const char* key) {
    if (args.has(option)) find_key(key)->set(p, args.get(option), option);
  };
  if (args.has("--tracker")) p.tracker = parse_tracker(args.get("--tracker"), "--tracker");
  if (args.has("--measure")) {
    if (p.tracker != TrackerKind::kParticle) throw UsageError("--measure applies to --tracker particle");
    p.particle_measure = parse_measure(args.get("--measure"), "--measure");
  }
  if (p.tracker == TrackerKind::kParticle) {
    // The stencil session's choices name nothing the particle tracker runs.
    for (const char* option : {"--plain", "--motion-filter", "--refine", "--recover", "--recovery", "--subcell", "--search-budget",
                               "--screen-stride", "--search-interval", "--no-focus-stack", "--no-verify", "--detect-after",
                               "--recovery-frames", "--survey-frames", "--verify-refine"})
      if (args.has(option)) throw UsageError(std::string(option) + " applies to the stencil tracker, not --tracker particle");
  }
  if (args.has("--plain")) p.plain = true;
  if (p.plain) {  // without --plain these name parts that are on anyway
    if (args.has("--motion-filter")) p.motion_filter = true;
    if (args.has("--refine")) p.refine = true;
    if (args.has("--recover")) p.recover = true;
  }
  if (args.has("--recovery")) p.recovery = parse_recovery(args.get("--recovery"), "--recovery");
  if (args.has("--subcell")) p.subcell = parse_subcell(args.get("--subcell"), "--subcell");
  if (args.has("--no-focus-stack")) p.focus_stack = false;
  if (args.has("--no-verify")) p.verify = false;
  if (args.has("--verify-refine")) p.verify_refine = parse_verify_refine(args.get("--verify-refine"), "--verify-refine");
  number("--search-budget", "search-budget");
  if (args.has("--search-budget") && p.search_budget == 0) throw UsageError("--search-budget '0': want an integer in 1..558");
  number("--search-interval", "search-interval");
  number("--screen-stride", "screen-stride");
  number("--detect-after", "detect-after");
  number("--recovery-frames", "recovery-frames");
  number("--survey-frames", "survey-frames");
  number("--particles", "particles");
  number("--seed", "seed");
  number("--edge-stride", "edge-stride");
  number("--edge-tolerance", "edge-tolerance");
  if (args.has("--without")) p.particle_improvements_off = parse_improvements_off(args.get("--without"), "--without");
  if (args.has("--mode-clustering")) p.particle_clustering = parse_mode_clustering(args.get("--mode-clustering"), "--mode-clustering");
  for (const char* option : {"--detect-after", "--recovery-frames", "--survey-frames"})
    if (p.recovery != RecoveryKind::kDetection && p.recovery != RecoveryKind::kAuto && args.has(option))
      throw UsageError(std::string(option) + " applies to --recovery detect (and auto)");
  for (const char* option : {"--particles", "--seed", "--without", "--edge-stride", "--edge-tolerance",
                             "--mode-clustering"}) {
    if (p.recovery != RecoveryKind::kParticles && args.has(option) && p.tracker != TrackerKind::kParticle)
      throw UsageError(std::string(option) + " applies to --tracker particle and --recovery particle");
  }
  if (needs_recovery(p.recovery) && !recovers(p))
    throw UsageError(std::string("--recovery ") + recovery_name(p.recovery) + " needs recovery: drop --plain or add --recover");
  if (p.subcell != SubCellKind::kParabola && !refines(p))
    throw UsageError("--subcell needs refinement: drop --plain or add --refine");
  check(p, "");
  return p;
}

}  // namespace gabarit::app
