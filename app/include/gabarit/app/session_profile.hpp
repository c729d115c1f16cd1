// The session profile: every choice that changes what a tracking session
// outputs, in one value that every program builds its session from (gabarit
// track, the board application, the HIL's in-process device and its
// reference, the Cortex-M firmware). It maps the choices to the kernel's
// SessionOptions, is validated once, travels on the HIL link as CAPS mode
// bits (so the harness's reference runs what the device runs), and is saved
// as a small text file (session_profile_io.hpp, docs/file-formats.md).
//
// Kernel-grade (no heap, no exceptions): the firmware holds its profile as a
// constant and sizes its static buffers for it.
#pragma once

#include <cstdint>

#include "gabarit/particle_filter.hpp"
#include "gabarit/status.hpp"
#include "gabarit/tracking_session.hpp"

namespace gabarit::app {

// How a lost target is re-acquired (with recovery on).
enum class RecoveryKind : std::uint8_t {
  kGrid = 0,       // the grid search around where it was last seen (recovery_search.hpp)
  kDetection = 1,  // detection where the target can be after detect_after lost frames (detection_recovery.hpp)
  kParticles = 2,  // a particle filter over the whole frame (particle_recovery.hpp)
  // The default: detection where the session verifies (a table with model
  // images and a grayscale detector, not the plain loop), else the grid.
  // A session resolves it once (resolve_recovery) before it runs.
  kAuto = 3,
};
// How refinement places the pose within the cell (SessionOptions::align_features).
enum class SubCellKind : std::uint8_t { kParabola = 0, kAlignment = 1 };
// Which of the thesis's two trackers runs.
enum class TrackerKind : std::uint8_t {
  kStencil = 0,   // the stencil session (tracking_session.hpp), or with `plain` the thesis's loop
  kParticle = 1,  // the particle filter (chapter 3; particle_filter.hpp) on the table's model
};
// The particle tracker's measure (app/particle_run.hpp runs it).
enum class ParticleMeasureKind : std::uint8_t {
  // The default: kIntensity for a table with model images, else kEdges (on
  // the pipette scenes the intensity measure held the tip within 6 px on
  // 57.9% of the held-out frames against 36.5%, in two thirds of the time;
  // docs/particle-filter.md, "The measures").
  kAuto = 0,
  kEdges = 1,    // edge correlation (thesis 3.4.3): every edge_stride-th model point, within edge_tolerance px of an edge
  kStencil = 2,  // the stencil vote of the particle's cell (the table voted once per frame at the prediction)
  // The session's verified score: the correlation of the table's model image
  // of the particle's depth with the frame, on about intensity_samples of
  // its samples; the finer measure the same on every sample of the stack's
  // step. Needs a table with model images.
  kIntensity = 3,
};
// The measure's name in profiles, options and reports ("auto", "edges", ...).
constexpr const char* name_of(ParticleMeasureKind kind) noexcept {
  switch (kind) {
    case ParticleMeasureKind::kAuto: return "auto";
    case ParticleMeasureKind::kEdges: return "edges";
    case ParticleMeasureKind::kStencil: return "stencil";
    case ParticleMeasureKind::kIntensity: return "intensity";
  }
  return "?";
}

// The particle filter's improvements a profile may switch off (bits of
// SessionProfile::particle_improvements_off); kAllImprovements: plain
// CONDENSATION (plain_condensation()).
inline constexpr std::uint32_t kImproveModes = 1u << 0;
inline constexpr std::uint32_t kImproveDisambiguation = 1u << 1;
inline constexpr std::uint32_t kImproveNarrowing = 1u << 2;
inline constexpr std::uint32_t kImproveKinematics = 1u << 3;
inline constexpr std::uint32_t kImproveReinit = 1u << 4;
inline constexpr std::uint32_t kImproveModeFilter = 1u << 5;
inline constexpr std::uint32_t kImproveVelocity = 1u << 6;
inline constexpr std::uint32_t kAllImprovements = 1u << 7;
inline constexpr std::uint32_t kImproveProposals = 1u << 8;  // vote-guided proposals (issue 31)
// Re-acquisition by detection while the filter is lost (ParticleRunOptions::
// detection; not a filter option). Runs only where the table verifies (model
// images, a grayscale detector); a device that cannot run it (the Cortex-M
// firmware) has it off in its profile, and CAPS says which (mode_bits).
inline constexpr std::uint32_t kImproveDetection = 1u << 9;
inline constexpr std::uint32_t kKnownImprovements = (1u << 10) - 1;
// The filter's options with the improvements in `off` switched off.
ParticleFilterOptions particle_filter_options(std::uint32_t off) noexcept;

// The stencil vote's best cells drawn around each frame by the particle
// tracker (ParticleRunOptions::proposals' default; the firmware's too).
inline constexpr std::uint32_t kDefaultParticleProposals = 4;
// The measure a table runs: kAuto resolved (the intensity measure on a table
// with model images, else the edge measure), the others as they are.
inline constexpr ParticleMeasureKind resolved_measure(ParticleMeasureKind kind, bool has_model_images) noexcept {
  if (kind != ParticleMeasureKind::kAuto) return kind;
  return has_model_images ? ParticleMeasureKind::kIntensity : ParticleMeasureKind::kEdges;
}
// What the particle tracker reports for a frame, as a session's result (the
// pose CSV, the HIL's POSE): its estimate, confidence from its state, and
// its ledger (the proposals' vote as the frame's features and votes).
SessionResult particle_session_result(const ParticleEstimate& estimate, const FrameLedger& ledger) noexcept;

struct SessionProfile {
  // The particle tracker instead of the stencil session: then only the
  // particle filter's numbers below and particle_measure apply, and `plain`
  // must be false.
  TrackerKind tracker = TrackerKind::kStencil;
  ParticleMeasureKind particle_measure = ParticleMeasureKind::kAuto;
  // The base: the tracking session's defaults (SessionOptions{}), or with
  // `plain` the thesis's loop (kPlainSession) with only the parts below added.
  bool plain = false;
  bool motion_filter = false;  // with plain: the motion filter, with its own defaults
  bool refine = false;         // with plain: sub-cell refinement
  bool recover = false;        // with plain: recovery once lost
  RecoveryKind recovery = RecoveryKind::kAuto;
  SubCellKind subcell = SubCellKind::kParabola;
  // The grid search detects features once per lost frame (SessionScratch::
  // search_features); false: a full track_step per placement.
  bool shared_search = true;
  // Without plain: depth and angle by intensity with the model images the
  // table carries (format 1.1), when it has them.
  bool focus_stack = true;
  // Without plain, with the table's model images: vote, then verify (the
  // best-correlated proposal, refined; docs/tracking.md).
  bool verify = true;
  // How verification refines the winner: Gauss-Newton on the correlation
  // (default) or the quadratic fitted to 19 correlations a round.
  RefineBy verify_refine = RefineBy::kGaussNewton;
  // The recovery search (RecoveryOptions): grid placements beyond the nearest
  // 9 per search (0: all), every n-th lost frame, every n-th feature screens a
  // placement; detection recovery after this many lost frames.
  std::uint32_t search_budget = 0;
  std::uint32_t search_interval = 1;
  std::uint32_t screen_stride = 2;
  std::uint32_t detect_after = 0;
  // Detection recovery's work per lost frame, and the look-alike survey's
  // per tracked frame, in tracked frames' work (SessionOptions::recovery_frames,
  // survey_frames); 0: the whole search in one frame.
  std::uint32_t recovery_frames = 0;
  std::uint32_t survey_frames = 2;
  // Particle recovery and the particle tracker: the filter's size, seed, edge
  // measure and improvements.
  std::uint32_t particles = 1000;
  std::uint64_t seed = 1;
  std::uint32_t edge_stride = 2;
  std::uint32_t edge_tolerance = 0;
  std::uint32_t particle_improvements_off = 0;
  ModeClustering particle_clustering = ModeClustering::kSeed;

  bool operator==(const SessionProfile&) const = default;
};

// The thesis's loop: track_step frame after frame, nothing added.
inline constexpr SessionProfile plain_profile() noexcept {
  SessionProfile p;
  p.plain = true;
  return p;
}

// kInvalidArgument for a profile no session can run: numbers out of the
// documented ranges (search_budget <= kSearchPlacementCount - kSearchNear, search_interval
// 1..100, screen_stride 1..16, detect_after, recovery_frames and
// survey_frames <= 1000, particles 1..10^6,
// edge_stride 1..64, edge_tolerance 0..3, known improvement bits), a
// recovery kind other than the grid without recovery, an alignment subcell
// without refinement, the particle tracker with `plain`, or a particle
// measure other than auto for the stencil session.
[[nodiscard]] Status validate(const SessionProfile& profile) noexcept;

// The kernel's options for the profile (its recovery numbers included).
SessionOptions session_options(const SessionProfile& profile) noexcept;
// Whether a session runs the recovery, refinement, the table's focus stack.
inline bool recovers(const SessionProfile& p) noexcept { return !p.plain || p.recover; }
inline bool refines(const SessionProfile& p) noexcept { return !p.plain || p.refine; }
inline bool uses_table_focus_stack(const SessionProfile& p) noexcept { return !p.plain && p.focus_stack; }
// Recovery kinds that need the session's recovery on (auto and the grid do not:
// without recovery they are nothing).
inline bool needs_recovery(RecoveryKind k) noexcept { return k == RecoveryKind::kDetection || k == RecoveryKind::kParticles; }
// Whether the particle tracker re-acquires by detection (neither
// kImproveDetection nor kAllImprovements off).
inline bool particle_detection(const SessionProfile& p) noexcept {
  return (p.particle_improvements_off & (kImproveDetection | kAllImprovements)) == 0;
}
// Whether a session on `table` with `detector` can verify (and so detect):
// the table carries model images and the detector is a grayscale one.
inline bool table_verifies(const TableView& table, const Detector& detector) noexcept {
  return table.has_model_images() && detector.kind != table_format::DetectorKind::kBinary;
}
// The profile with RecoveryKind::kAuto made concrete for a table: detection
// where the session verifies (`verifying_table`, table_verifies: model images and a
// grayscale detector) and recovers, else the grid.
SessionProfile resolve_recovery(const SessionProfile& profile, bool verifying_table) noexcept;

// The HIL link's form (CAPS.mode, link/protocol.hpp's kMode* bits): a device
// reports the profile it runs, as the choices take effect on its table
// (`shares_search`: its scratch shares the search's features; `has_stack`:
// it uses the table's focus stack), and the harness's reference runs
// profile_from_mode_bits of it. The numbers (budget, interval, stride,
// detect_after, the detection budgets, the particle filter's) do not travel: a profile whose numbers
// differ from the defaults sets kModeTuned, and the harness refuses it. The
// particle tracker travels as kModeParticleTracker with its measure, which
// the device reports resolved for its table (never auto).
std::uint32_t mode_bits(const SessionProfile& profile, bool shares_search, bool has_stack) noexcept;
SessionProfile profile_from_mode_bits(std::uint32_t bits) noexcept;

}  // namespace gabarit::app
