// The firmware's application: validate the table linked into flash once,
// then replay the embedded test vectors through the kernel's tracker (or the
// session vectors through a TrackingSession: motion filter, refinement,
// recovery, depth and angle by intensity; or the particle vectors through
// the particle tracker gabarit track --tracker particle runs) and report
// whether every pose and vote count is bit-identical to the host's.
// All buffers are static and sized by the kernel's constexpr functions for
// the largest table this firmware accepts; a bigger table is refused at
// start-up, never overrun.
#include <cstddef>
#include <cstdint>
#include <span>

#include "board.hpp"
#include "console.hpp"
#include "gabarit/app/test_vectors.hpp"
#include "gabarit/table_view.hpp"
#include "gabarit/tracker.hpp"
#include "tracker_capacity.hpp"

extern "C" {
extern const std::byte gabarit_table[], gabarit_table_end[];
extern const std::byte gabarit_vectors[], gabarit_vectors_end[];
extern const std::byte gabarit_session[], gabarit_session_end[];
extern const std::byte gabarit_particle[], gabarit_particle_end[];
}

namespace {

using gabarit::mcu::Line;
using gabarit::mcu::console_write;

using gabarit::mcu::kFeatureCapacity;
using gabarit::mcu::kMaskBytes;
using gabarit::mcu::kMaxCells;

gabarit::RoiPoint g_features[kFeatureCapacity];
gabarit::VoteCounter g_counters[gabarit::mcu::kCounterCount];
std::uint8_t g_roi_mask[kMaskBytes];
std::uint16_t g_magnitudes[gabarit::mcu::kMagnitudeEntries];
// The session vectors' focus stack: views of images in flash.
gabarit::ImageView g_stack_views[gabarit::vectors::kMaxStackDepths];
#if GABARIT_REPLAY_PARTICLES  // only the images that replay the particle vectors hold their buffers
// The particle tracker's cloud, its radix sort's indices and the frame's edge map.
gabarit::Particle g_cloud[gabarit::particle_scratch_particles(gabarit::mcu::kMaxParticles)];
gabarit::Particle g_next[gabarit::particle_scratch_particles(gabarit::mcu::kMaxParticles)];
std::uint32_t g_order[gabarit::particle_scratch_order(gabarit::mcu::kMaxParticles)];
std::uint64_t g_edge_bits[gabarit::mcu::kEdgeMapWords];
gabarit::RoiPoint g_edge_features[gabarit::mcu::kEdgeMapFeatures];
// With the intensity measure: the coarse and the finer measure, reset once the
// table is known (constant-initialised: no static constructor).
gabarit::IntensityCorrelationMeasure g_intensity[2];
#endif

std::span<const std::byte> between(const std::byte* begin, const std::byte* end) {
  return {begin, static_cast<std::size_t>(end - begin)};
}

int fail(const char* what, gabarit::Status status) {
  Line line;
  console_write(line.text("FAIL: ").text(what).text(": ").text(gabarit::status_name(status)));
  return 1;
}

int mismatch(const char* what, const gabarit::vectors::Report& report) {
  Line line;
  console_write(line.text("FAIL: ").text(what).text(" frame ").dec(std::uint64_t{report.frame}).text(" field ")
                    .text(report.field).text(": expected ").hex(report.expected).text(", got ").hex(report.actual));
  return 1;
}

#if GABARIT_REPLAY_PARTICLES
// The particle vectors: the table's tracker scratch serves the proposals' vote.
int replay_particles(const gabarit::TableView& table, gabarit::TrackerScratch scratch) {
  gabarit::vectors::ParticleVectorSet set;
  if (const auto s = gabarit::vectors::open_particle_vectors(between(gabarit_particle, gabarit_particle_end), set);
      s != gabarit::Status::kOk)
    return fail("particle vectors", s);
  if (set.particles > gabarit::mcu::kMaxParticles || set.width > gabarit::mcu::kMaxParticleFrameSide ||
      set.height > gabarit::mcu::kMaxParticleFrameSide) {
    Line line;
    console_write(line.text("FAIL: the particle vectors need ").dec(std::uint64_t{set.particles}).text(" particles on ")
                      .dec(std::uint64_t{set.width}).text("x").dec(std::uint64_t{set.height}).text(" frames; this firmware has ")
                      .dec(std::uint64_t{gabarit::mcu::kMaxParticles}).text(" and ")
                      .dec(std::uint64_t{gabarit::mcu::kMaxParticleFrameSide}).text(" a side"));
    return 1;
  }
  gabarit::vectors::Report report;
  const gabarit::vectors::ParticleVectorScratch particle_scratch{{g_cloud, g_next, g_order}, g_edge_bits, g_edge_features, scratch,
                                                                 g_stack_views, g_intensity};
  if (const auto s = gabarit::vectors::check_particle_vectors(table, set, particle_scratch, report); s != gabarit::Status::kOk)
    return fail("particle filter", s);
  if (!report.match) return mismatch("particle", report);
  Line result;
  console_write(result.text("PASS: particle tracker (").text(set.intensity ? "intensity" : "edge").text(" measure), ")
                    .dec(std::uint64_t{report.frames_checked}).text(" frames ")
                    .dec(std::uint64_t{set.width}).text("x").dec(std::uint64_t{set.height}).text(", ")
                    .dec(std::uint64_t{set.particles}).text(" particles, seed ").dec(set.seed)
                    .text(": estimates bit-identical to the host"));
  return 0;
}
#endif

}  // namespace

extern "C" int app_main() {
  Line hello;
  console_write(hello.text("gabarit firmware on ").text(gabarit::mcu::board::kName));

  gabarit::TableView table;
  if (const auto s = gabarit::TableView::open(between(gabarit_table, gabarit_table_end), table); s != gabarit::Status::kOk)
    return fail("table", s);
  // The table's needs against this firmware's static buffers: checked once here.
  const std::size_t features_needed = gabarit::tracker_feature_capacity(table);
  if (!gabarit::mcu::table_fits(table)) {
    Line line;
    console_write(line.text("FAIL: table needs ").dec(std::uint64_t{features_needed}).text(" feature slots and ")
                      .dec(std::uint64_t{table.cell_count()}).text(" cells; this firmware has ")
                      .dec(std::uint64_t{kFeatureCapacity}).text(" and ").dec(std::uint64_t{kMaxCells}));
    return 1;
  }
  Line info;
  console_write(info.text("table: ").dec(std::uint64_t{table.cell_count()}).text(" cells, ")
                    .dec(std::uint64_t{table.reference_count()}).text(" references, ")
                    .dec(static_cast<std::uint64_t>(gabarit_table_end - gabarit_table)).text(" bytes in flash"));

  gabarit::TrackerScratch scratch;
  scratch.features = g_features;
  scratch.counters = std::span<gabarit::VoteCounter>(g_counters, gabarit::voter_counter_count(table.cell_count()));
  scratch.roi_mask = g_roi_mask;
  scratch.magnitudes = g_magnitudes;
  gabarit::vectors::Report report;

  if (!between(gabarit_vectors, gabarit_vectors_end).empty()) {
    gabarit::vectors::VectorSet set;
    if (const auto s = gabarit::vectors::open_vectors(between(gabarit_vectors, gabarit_vectors_end), set); s != gabarit::Status::kOk)
      return fail("vectors", s);
    if (const auto s = gabarit::vectors::check_vectors(table, set, scratch, report); s != gabarit::Status::kOk)
      return fail("track_step", s);
    if (!report.match) return mismatch("vectors", report);
    Line result;
    console_write(result.text("PASS: ").dec(std::uint64_t{report.frames_checked}).text(" frames ")
                      .dec(std::uint64_t{set.width}).text("x").dec(std::uint64_t{set.height})
                      .text(", poses and votes bit-identical to the host"));
  }
  if (!between(gabarit_session, gabarit_session_end).empty()) {
    gabarit::vectors::SessionVectorSet set;
    if (const auto s = gabarit::vectors::open_session_vectors(between(gabarit_session, gabarit_session_end), set);
        s != gabarit::Status::kOk)
      return fail("session vectors", s);
    // Each recovery placement a full track_step: no shared search features
    // (the mode the session vectors were recorded in, and the one a part
    // short of RAM runs).
    if (const auto s = gabarit::vectors::check_session_vectors(table, set, {scratch, {}, {}}, g_stack_views, report);
        s != gabarit::Status::kOk)
      return fail("session", s);
    if (!report.match) return mismatch("session", report);
    Line result;
    console_write(result.text("PASS: session, ").dec(std::uint64_t{report.frames_checked}).text(" frames ")
                      .dec(std::uint64_t{set.width}).text("x").dec(std::uint64_t{set.height}).text(" with ")
                      .dec(std::uint64_t{set.stack_depths})
                      .text(" focus-stack images: poses, confidence and votes bit-identical to the host"));
  }
#if GABARIT_REPLAY_PARTICLES
  if (!between(gabarit_particle, gabarit_particle_end).empty()) return replay_particles(table, scratch);
#endif
  return 0;
}
