#include "gabarit/app/test_vectors.hpp"

#include <cstring>

#include "gabarit/byte_order.hpp"
#include "gabarit/crc32.hpp"
#include "gabarit/particle_measures.hpp"
#include "gabarit/particle_recovery.hpp"

namespace gabarit::vectors {
namespace {

template <class T>
std::uint32_t float_bits(T value) noexcept {
  std::uint32_t bits = 0;
  static_assert(sizeof(T) == sizeof(bits));
  std::memcpy(&bits, &value, sizeof(bits));
  return bits;
}

// Field offsets in a record (see encode_record).
struct Field {
  const char* name;
  std::size_t offset;
  std::size_t size;
};
constexpr Field kFields[] = {
    {"x", 0, 4},          {"y", 4, 4},           {"theta_deg", 8, 4},  {"depth", 12, 2},
    {"state", 14, 1},     {"best_cell", 16, 4},  {"best_votes", 20, 2}, {"runner_up_votes", 22, 2},
    {"runner_up_cell", 24, 4}, {"score", 28, 4}, {"roi_centre_x", 32, 4}, {"roi_centre_y", 36, 4},
    {"features", 40, 4},  {"features_dropped", 44, 4}, {"votes", 48, 8},
};

// The session's fields after the vote's record.
constexpr Field kSessionFields[] = {
    {"session_x", kRecordBytes + 0, 4},      {"session_y", kRecordBytes + 4, 4},
    {"session_theta_deg", kRecordBytes + 8, 4}, {"session_depth", kRecordBytes + 12, 2},
    {"confidence", kRecordBytes + 14, 1},    {"session_state", kRecordBytes + 15, 1},
    {"session_score", kRecordBytes + 16, 4}, {"reacquired", kRecordBytes + 20, 1},
    {"searched_coarse", kRecordBytes + 21, 1},
};

// A particle record's fields (see encode_particle_record).
constexpr Field kParticleFields[] = {
    {"x", 0, 4},      {"y", 4, 4},          {"theta_deg", 8, 4},       {"depth", 12, 2},
    {"state", 14, 1}, {"flags", 15, 1},     {"score", 16, 4},          {"modes", 20, 4},
    {"mode_particles", 24, 4},              {"proposed", 28, 4},
};

std::uint64_t load_field(const std::byte* record, const Field& f) noexcept {
  switch (f.size) {
    case 1: return std::to_integer<std::uint64_t>(record[f.offset]);
    case 2: return load_le<std::uint16_t>(record + f.offset);
    case 4: return load_le<std::uint32_t>(record + f.offset);
    default: return load_le<std::uint64_t>(record + f.offset);
  }
}

// The first 40 bytes both formats share: magic, frame count, width, height,
// detector kind, a byte of the format's own (21), detector threshold, the
// initial pose, and a u16 of the format's own (38).
void store_common(std::byte* p, const char (&magic)[8], std::uint32_t frames, std::uint32_t width, std::uint32_t height,
                  const Detector& detector, const Pose& init) noexcept {
  std::memcpy(p, magic, sizeof(magic));
  store_le<std::uint32_t>(p + 8, frames);
  store_le<std::uint32_t>(p + 12, width);
  store_le<std::uint32_t>(p + 16, height);
  p[20] = static_cast<std::byte>(detector.kind);
  store_le<std::uint16_t>(p + 22, detector.threshold);
  store_le<float>(p + 24, init.x);
  store_le<float>(p + 28, init.y);
  store_le<float>(p + 32, init.theta_deg);
  store_le<std::uint16_t>(p + 36, init.depth);
}

// Reads the shared fields; false if the counts, sizes or detector are out of range.
template <class Set>
bool load_common(const std::byte* p, Set& set) noexcept {
  set.frame_count = load_le<std::uint32_t>(p + 8);
  set.width = load_le<std::uint32_t>(p + 12);
  set.height = load_le<std::uint32_t>(p + 16);
  const std::uint8_t kind = std::to_integer<std::uint8_t>(p[20]);
  set.detector.kind = static_cast<table_format::DetectorKind>(kind);
  set.detector.threshold = load_le<std::uint16_t>(p + 22);
  set.init = {load_le<float>(p + 24), load_le<float>(p + 28), load_le<float>(p + 32), load_le<std::uint16_t>(p + 36)};
  return set.frame_count > 0 && set.frame_count <= 100000 && set.width > 0 && set.width <= 8192 && set.height > 0 &&
         set.height <= 8192 && kind <= static_cast<std::uint8_t>(table_format::DetectorKind::kCanny);
}

// The file is exactly `size` bytes and its trailer is the CRC of the rest.
Status check_size_and_crc(std::span<const std::byte> bytes, std::size_t size) noexcept {
  if (bytes.size() < size) return Status::kTruncated;
  if (bytes.size() != size) return Status::kSizeMismatch;
  const std::size_t body = size - kTrailerBytes;
  return crc32(bytes.first(body)) == load_le<std::uint32_t>(bytes.data() + body) ? Status::kOk : Status::kBadChecksum;
}

// Points `set`'s frames and expected records into `bytes` (already checked
// to be exactly the format's size): the frames from `at`, the records after.
template <class Set>
void place_frames(std::span<const std::byte> bytes, std::size_t at, std::size_t record_bytes, Set& set) noexcept {
  const std::size_t pixels = std::size_t{set.frame_count} * set.width * set.height;
  set.frames = bytes.subspan(at, pixels);
  set.expected = bytes.subspan(at + pixels, std::size_t{set.frame_count} * record_bytes);
}

// The first field where two records differ, or false.
template <std::size_t N>
bool first_difference(const std::byte* expected, const std::byte* actual, const Field (&fields)[N], std::uint32_t frame,
                      Report& report) noexcept {
  for (const Field& f : fields) {
    const std::uint64_t want = load_field(expected, f), got = load_field(actual, f);
    if (want != got) {
      report.match = false;
      report.frame = frame;
      report.field = f.name;
      report.expected = want;
      report.actual = got;
      return true;
    }
  }
  return false;
}

}  // namespace

Status open_vectors(std::span<const std::byte> bytes, VectorSet& out) noexcept {
  if (bytes.size() < kHeaderBytes + kTrailerBytes) return Status::kTruncated;
  if (std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0) return Status::kBadMagic;
  VectorSet set;
  if (!load_common(bytes.data(), set)) return Status::kBadHeaderField;
  GABARIT_TRY(check_size_and_crc(bytes, file_bytes(set.frame_count, set.width, set.height)));
  place_frames(bytes, kHeaderBytes, kRecordBytes, set);
  out = set;
  return Status::kOk;
}

void encode_header(const VectorSet& set, std::span<std::byte, kHeaderBytes> out) noexcept {
  std::memset(out.data(), 0, kHeaderBytes);
  store_common(out.data(), kMagic, set.frame_count, set.width, set.height, set.detector, set.init);
}

void encode_record(const StepResult& step, std::span<std::byte, kRecordBytes> out) noexcept {
  std::byte* p = out.data();
  std::memset(p, 0, kRecordBytes);
  store_le<std::uint32_t>(p + 0, float_bits(step.pose.x));
  store_le<std::uint32_t>(p + 4, float_bits(step.pose.y));
  store_le<std::uint32_t>(p + 8, float_bits(step.pose.theta_deg));
  store_le<std::uint16_t>(p + 12, step.pose.depth);
  p[14] = static_cast<std::byte>(step.state);
  store_le<std::uint32_t>(p + 16, step.best.cell);
  store_le<std::uint16_t>(p + 20, step.best.votes);
  store_le<std::uint16_t>(p + 22, step.runner_up.votes);
  store_le<std::uint32_t>(p + 24, step.runner_up.cell);
  store_le<std::uint32_t>(p + 28, float_bits(step.score));
  store_le<std::int32_t>(p + 32, step.roi_centre_x);
  store_le<std::int32_t>(p + 36, step.roi_centre_y);
  store_le<std::uint32_t>(p + 40, step.features);
  store_le<std::uint32_t>(p + 44, step.features_dropped);
  store_le<std::uint64_t>(p + 48, step.votes);
}

Status open_session_vectors(std::span<const std::byte> bytes, SessionVectorSet& out) noexcept {
  if (bytes.size() < kSessionHeaderBytes + kTrailerBytes) return Status::kTruncated;
  if (std::memcmp(bytes.data(), kSessionMagic, sizeof(kSessionMagic)) != 0) return Status::kBadMagic;
  const std::byte* p = bytes.data();
  SessionVectorSet set;
  const bool common_ok = load_common(p, set);
  const std::uint8_t flags = std::to_integer<std::uint8_t>(p[21]);
  set.stack_depths = load_le<std::uint16_t>(p + 38);
  set.stack_width = load_le<std::uint32_t>(p + 40);
  set.stack_height = load_le<std::uint32_t>(p + 44);
  set.stack_ref_x = load_le<float>(p + 48);
  set.stack_ref_y = load_le<float>(p + 52);
  set.stack_step = load_le<std::uint32_t>(p + 56);
  set.options = SessionOptions{};  // the defaults, then what the file records
  set.options.motion_filter = (flags & 1u) != 0;
  set.options.refine = (flags & 2u) != 0;
  set.options.recover = (flags & 4u) != 0;
  set.shared_search_features = (flags & 8u) != 0;
  set.options.recovery.turn_deg = load_le<float>(p + 60);
  set.options.recovery.budget = load_le<std::uint32_t>(p + 64);
  set.options.recovery.interval = load_le<std::uint32_t>(p + 68);
  set.options.recovery.screen_stride = load_le<std::uint32_t>(p + 72);
  const bool stack_ok = set.stack_depths == 0 ||
                        (set.stack_depths <= kMaxStackDepths && set.stack_width > 0 && set.stack_width <= 8192 &&
                         set.stack_height > 0 && set.stack_height <= 8192);
  if (!common_ok || (flags & ~15u) != 0 || !stack_ok || !valid(set.options.recovery) || load_le<std::uint32_t>(p + 76) != 0) {
    return Status::kBadHeaderField;
  }
  GABARIT_TRY(check_size_and_crc(
      bytes, session_file_bytes(set.frame_count, set.width, set.height, set.stack_depths, set.stack_width, set.stack_height)));
  const std::size_t stack = std::size_t{set.stack_depths} * set.stack_width * set.stack_height;
  set.stack = bytes.subspan(kSessionHeaderBytes, stack);
  place_frames(bytes, kSessionHeaderBytes + stack, kSessionRecordBytes, set);
  out = set;
  return Status::kOk;
}

void encode_session_header(const SessionVectorSet& set, std::span<std::byte, kSessionHeaderBytes> out) noexcept {
  std::byte* p = out.data();
  std::memset(p, 0, kSessionHeaderBytes);
  store_common(p, kSessionMagic, set.frame_count, set.width, set.height, set.detector, set.init);
  p[21] = static_cast<std::byte>((set.options.motion_filter ? 1u : 0u) | (set.options.refine ? 2u : 0u) |
                                 (set.options.recover ? 4u : 0u) | (set.shared_search_features ? 8u : 0u));
  store_le<std::uint16_t>(p + 38, set.stack_depths);
  store_le<std::uint32_t>(p + 40, set.stack_width);
  store_le<std::uint32_t>(p + 44, set.stack_height);
  store_le<float>(p + 48, set.stack_ref_x);
  store_le<float>(p + 52, set.stack_ref_y);
  store_le<std::uint32_t>(p + 56, set.stack_step);
  store_le<float>(p + 60, set.options.recovery.turn_deg);
  store_le<std::uint32_t>(p + 64, set.options.recovery.budget);
  store_le<std::uint32_t>(p + 68, set.options.recovery.interval);
  store_le<std::uint32_t>(p + 72, set.options.recovery.screen_stride);
}

void encode_session_record(const SessionResult& r, std::span<std::byte, kSessionRecordBytes> out) noexcept {
  std::byte* p = out.data();
  std::memset(p, 0, kSessionRecordBytes);
  encode_record(r.step, out.first<kRecordBytes>());
  p += kRecordBytes;
  store_le<std::uint32_t>(p + 0, float_bits(r.pose.x));
  store_le<std::uint32_t>(p + 4, float_bits(r.pose.y));
  store_le<std::uint32_t>(p + 8, float_bits(r.pose.theta_deg));
  store_le<std::uint16_t>(p + 12, r.pose.depth);
  p[14] = static_cast<std::byte>(r.confidence);
  p[15] = static_cast<std::byte>(r.state);
  store_le<std::uint32_t>(p + 16, float_bits(r.score));
  p[20] = static_cast<std::byte>(r.reacquired ? 1 : 0);
  p[21] = static_cast<std::byte>(r.searched_coarse ? 1 : 0);
}

Status check_session_vectors(const TableView& table, const SessionVectorSet& set, SessionScratch scratch,
                             std::span<ImageView> stack_views, Report& report) noexcept {
  report = Report{};
  if (stack_views.size() < set.stack_depths) return Status::kBufferTooSmall;
  if (!set.shared_search_features) {
    scratch.search_features = {};
  } else if (scratch.search_features.size() < search_feature_capacity(table)) {
    return Status::kBufferTooSmall;
  }
  TrackingSession session(table, nullptr, set.detector);
  GABARIT_TRY(session.start(set.options, set.init));
  FocusStack stack;
  if (set.stack_depths > 0) {
    for (std::uint16_t d = 0; d < set.stack_depths; ++d) stack_views[d] = set.stack_image(d);
    stack = FocusStack{stack_views.first(set.stack_depths), set.stack_ref_x, set.stack_ref_y, set.stack_step};
    session.use_focus_stack(&stack);
  }
  for (std::uint32_t i = 0; i < set.frame_count; ++i) {
    SessionResult result;
    GABARIT_TRY(session.step(set.frame(i), scratch, result));
    std::byte actual[kSessionRecordBytes];
    encode_session_record(result, std::span<std::byte, kSessionRecordBytes>(actual));
    const std::byte* expected = set.expected.data() + std::size_t{i} * kSessionRecordBytes;
    if (first_difference(expected, actual, kFields, i, report) || first_difference(expected, actual, kSessionFields, i, report)) {
      return Status::kOk;
    }
    report.frames_checked = i + 1;
  }
  return Status::kOk;
}

Status check_vectors(const TableView& table, const VectorSet& set, TrackerScratch scratch, Report& report) noexcept {
  report = Report{};
  Pose pose = set.init;
  for (std::uint32_t i = 0; i < set.frame_count; ++i) {
    StepResult step;
    GABARIT_TRY(track_step(table, set.detector, set.frame(i), pose, scratch, step));
    std::byte actual[kRecordBytes];
    encode_record(step, std::span<std::byte, kRecordBytes>(actual));
    const std::byte* expected = set.expected.data() + std::size_t{i} * kRecordBytes;
    if (first_difference(expected, actual, kFields, i, report)) return Status::kOk;
    report.frames_checked = i + 1;
    pose = step.pose;
  }
  return Status::kOk;
}

Status open_particle_vectors(std::span<const std::byte> bytes, ParticleVectorSet& out) noexcept {
  if (bytes.size() < kParticleHeaderBytes + kTrailerBytes) return Status::kTruncated;
  if (std::memcmp(bytes.data(), kParticleMagic, sizeof(kParticleMagic)) != 0) return Status::kBadMagic;
  const std::byte* p = bytes.data();
  ParticleVectorSet set;
  const bool common_ok = load_common(p, set);
  const std::uint8_t flags = std::to_integer<std::uint8_t>(p[21]);
  set.finer = (flags & 1u) != 0;
  set.intensity = (flags & 2u) != 0;
  set.intensity_samples = load_le<std::uint32_t>(p + 52);
  set.proposals = load_le<std::uint16_t>(p + 38);
  set.particles = load_le<std::uint32_t>(p + 40);
  set.edge_stride = load_le<std::uint32_t>(p + 44);
  set.edge_tolerance = load_le<std::uint32_t>(p + 48);
  set.seed = load_le<std::uint64_t>(p + 56);
  // The frame's sides are the edge map's window: at most 65535 (u16) each.
  const bool filter_ok = set.particles >= 1 && set.particles <= kMaxVectorParticles && set.proposals <= kMaxParticleProposals &&
                         set.edge_stride >= 1 && set.edge_stride <= 64 && set.edge_tolerance <= 3 &&
                         (set.intensity ? set.intensity_samples >= 16 && set.intensity_samples <= kMaxIntensityMeasureSamples
                                        : set.intensity_samples == 0);
  if (!common_ok || (flags & ~3u) != 0 || !filter_ok) return Status::kBadHeaderField;
  GABARIT_TRY(check_size_and_crc(bytes, particle_file_bytes(set.frame_count, set.width, set.height)));
  place_frames(bytes, kParticleHeaderBytes, kParticleRecordBytes, set);
  out = set;
  return Status::kOk;
}

void encode_particle_header(const ParticleVectorSet& set, std::span<std::byte, kParticleHeaderBytes> out) noexcept {
  std::byte* p = out.data();
  std::memset(p, 0, kParticleHeaderBytes);
  store_common(p, kParticleMagic, set.frame_count, set.width, set.height, set.detector, set.init);
  p[21] = static_cast<std::byte>((set.finer ? 1u : 0u) | (set.intensity ? 2u : 0u));
  store_le<std::uint16_t>(p + 38, static_cast<std::uint16_t>(set.proposals));
  store_le<std::uint32_t>(p + 40, set.particles);
  store_le<std::uint32_t>(p + 44, set.edge_stride);
  store_le<std::uint32_t>(p + 48, set.edge_tolerance);
  store_le<std::uint32_t>(p + 52, set.intensity ? set.intensity_samples : 0u);
  store_le<std::uint64_t>(p + 56, set.seed);
}

void encode_particle_record(const ParticleEstimate& e, std::span<std::byte, kParticleRecordBytes> out) noexcept {
  std::byte* p = out.data();
  std::memset(p, 0, kParticleRecordBytes);
  store_le<std::uint32_t>(p + 0, float_bits(e.pose.x));
  store_le<std::uint32_t>(p + 4, float_bits(e.pose.y));
  store_le<std::uint32_t>(p + 8, float_bits(e.pose.theta_deg));
  store_le<std::uint16_t>(p + 12, e.pose.depth);
  p[14] = static_cast<std::byte>(e.state);
  p[15] = static_cast<std::byte>((e.held ? 1u : 0u) | (e.reinitialised ? 2u : 0u));
  store_le<std::uint32_t>(p + 16, float_bits(e.score));
  store_le<std::uint32_t>(p + 20, e.modes);
  store_le<std::uint32_t>(p + 24, e.mode_particles);
  store_le<std::uint32_t>(p + 28, e.proposed);
}

namespace {

// Starts `filter` and steps it over every frame, comparing each estimate.
template <class Filter>
Status replay_particles(Filter& filter, StencilVoteProposer& proposer, const TableView& table, const ParticleVectorSet& set,
                        const ParticleScratch& ps, ParticleFilterOptions options, Report& report) noexcept {
  if (set.proposals > 0) filter.propose_with(&proposer);
  GABARIT_TRY(filter.start(options, set.init, table.depth_count(), set.seed,
                           {ps.cloud.first(set.particles), ps.next.first(set.particles), ps.order}));
  for (std::uint32_t i = 0; i < set.frame_count; ++i) {
    ParticleEstimate estimate;
    GABARIT_TRY(filter.step(set.frame(i), estimate));
    std::byte actual[kParticleRecordBytes];
    encode_particle_record(estimate, std::span<std::byte, kParticleRecordBytes>(actual));
    const std::byte* expected = set.expected.data() + std::size_t{i} * kParticleRecordBytes;
    if (first_difference(expected, actual, kParticleFields, i, report)) return Status::kOk;
    report.frames_checked = i + 1;
  }
  return Status::kOk;
}

// The compositions app::ParticleTracker builds on the heap, on the caller's memory.
Status replay_edges(const TableView& table, const ParticleVectorSet& set, const ParticleVectorScratch& scratch,
                    StencilVoteProposer& proposer, Report& report) noexcept {
  EdgeMapLoader loader(set.detector, scratch.edge_bits.first(edge_map_words(set.width, set.height)),
                       scratch.edge_features.first(edge_map_features(set.width)), static_cast<std::uint16_t>(set.width),
                       static_cast<std::uint16_t>(set.height));
  EdgeCorrelationMeasure edges(table, loader, set.edge_stride, set.edge_tolerance);
  EdgeCorrelationMeasure fine(table, loader, 1, set.edge_tolerance);
  EdgeParticleFilter filter(edges, set.finer ? &fine : nullptr, &loader);
  return replay_particles(filter, proposer, table, set, scratch.particles, ParticleFilterOptions{}, report);
}

Status replay_intensity(const TableView& table, const ParticleVectorSet& set, const ParticleVectorScratch& scratch,
                        StencilVoteProposer& proposer, Report& report) noexcept {
  const std::uint16_t depths = table.depth_count();
  for (std::uint16_t d = 0; d < depths; ++d) scratch.stack_views[d] = table.model_image(d);
  const FocusStack stack{scratch.stack_views.first(depths), table.model_ref_x(), table.model_ref_y(), 2};
  IntensityCorrelationMeasure& coarse = scratch.intensity[0];
  IntensityCorrelationMeasure& fine = scratch.intensity[1];
  coarse.reset(stack, set.intensity_samples);
  fine.reset(stack, 0);
  IntensityParticleFilter filter(coarse, set.finer ? &fine : nullptr);
  ParticleFilterOptions options;
  options.sharpness = kIntensitySharpness;
  return replay_particles(filter, proposer, table, set, scratch.particles, options, report);
}

}  // namespace

Status check_particle_vectors(const TableView& table, const ParticleVectorSet& set, ParticleVectorScratch scratch,
                              Report& report) noexcept {
  report = Report{};
  const ParticleScratch& ps = scratch.particles;
  if (ps.cloud.size() < particle_scratch_particles(set.particles) || ps.next.size() < particle_scratch_particles(set.particles) ||
      ps.order.size() < particle_scratch_order(set.particles) || set.width > 65535 || set.height > 65535) {
    return Status::kBufferTooSmall;
  }
  if (set.intensity && !table.has_model_images()) return Status::kInvalidArgument;
  if (set.intensity ? scratch.stack_views.size() < table.depth_count() || scratch.intensity.size() < 2
                    : scratch.edge_bits.size() < edge_map_words(set.width, set.height) ||
                          scratch.edge_features.size() < edge_map_features(set.width)) {
    return Status::kBufferTooSmall;
  }
  StencilVoteProposer proposer(table, set.detector, scratch.proposer, set.proposals > 0 ? set.proposals : 1);
  return set.intensity ? replay_intensity(table, set, scratch, proposer, report) : replay_edges(table, set, scratch, proposer, report);
}

}  // namespace gabarit::vectors
