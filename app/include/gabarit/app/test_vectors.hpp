// Cross-target test vectors: files produced on the host by `gabarit vectors`,
// that every target (x86-64, aarch64 and armhf under qemu-user, Cortex-M
// under qemu-system-arm) replays and must reproduce bit for bit:
//   vectors.gbv  track_step frame after frame: poses, vote counts, best and
//                runner-up cells;
//   session.gbs  a TrackingSession (motion filter, refinement, recovery,
//                depth and angle by intensity) over a sequence with an
//                occlusion: the session's pose, confidence, state and score,
//                and the vote it searched (the format below);
//   particle.gbp the particle tracker (gabarit track --tracker particle's
//                defaults on that table: the edge measure, its finer
//                measure, vote-guided proposals, 1,000 particles, seed 1)
//                over the session's sequence: every frame's estimate;
//   particle-intensity.gbp  the same on particle-table.gbt, the model's table
//                with its images: the intensity measure.
//
// Like the kernel this reader never allocates, so the same code runs in the
// firmware on a const array in flash and on the host on a file read into memory.
//
// Format (little-endian; docs/file-formats.md):
//   header   40 bytes  magic "GBVECT01", u32 frame_count, u32 width, u32 height,
//                      u8 detector kind, u8 0, u16 detector threshold,
//                      f32 init x, f32 init y, f32 init theta_deg, u16 init depth, u16 0
//   frames   frame_count * width * height bytes, 8-bit luma, row-major
//   expected frame_count records of kRecordBytes (encode_record's layout)
//   trailer  u32 CRC-32 of every byte before it
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "gabarit/image_view.hpp"
#include "gabarit/particle_filter.hpp"
#include "gabarit/particle_measures.hpp"
#include "gabarit/status.hpp"
#include "gabarit/table_view.hpp"
#include "gabarit/tracker.hpp"
#include "gabarit/tracking_session.hpp"

namespace gabarit::vectors {

inline constexpr char kMagic[8] = {'G', 'B', 'V', 'E', 'C', 'T', '0', '1'};
inline constexpr std::size_t kHeaderBytes = 40;
inline constexpr std::size_t kRecordBytes = 56;
inline constexpr std::size_t kTrailerBytes = 4;

constexpr std::size_t file_bytes(std::uint32_t frames, std::uint32_t width, std::uint32_t height) noexcept {
  return kHeaderBytes + std::size_t{frames} * width * height + std::size_t{frames} * kRecordBytes + kTrailerBytes;
}

struct VectorSet {
  std::uint32_t frame_count = 0;
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  Detector detector;
  Pose init;
  std::span<const std::byte> frames;    // frame_count * width * height
  std::span<const std::byte> expected;  // frame_count * kRecordBytes

  ImageView frame(std::uint32_t i) const noexcept {
    return {reinterpret_cast<const std::uint8_t*>(frames.data()) + std::size_t{i} * width * height, width, height, width};
  }
};

// Validates size, magic, dimensions and CRC. Errors: kTruncated, kBadMagic,
// kSizeMismatch, kBadHeaderField, kBadChecksum.
Status open_vectors(std::span<const std::byte> bytes, VectorSet& out) noexcept;

// One frame's expected result in the record layout:
//   f32 x, f32 y, f32 theta_deg, u16 depth, u8 state, u8 0,
//   u32 best cell, u16 best votes, u16 runner-up votes, u32 runner-up cell,
//   f32 score, i32 roi centre x, i32 roi centre y, u32 features,
//   u32 features dropped, u64 votes
void encode_record(const StepResult& step, std::span<std::byte, kRecordBytes> out) noexcept;

// Writes the header into `out` (kHeaderBytes).
void encode_header(const VectorSet& set, std::span<std::byte, kHeaderBytes> out) noexcept;

struct Report {
  std::uint32_t frames_checked = 0;  // frames replayed before the first mismatch (all when none)
  bool match = true;
  std::uint32_t frame = 0;           // first mismatching frame
  const char* field = "";            // its first mismatching field
  std::uint64_t expected = 0;        // raw field values (float fields as their bits)
  std::uint64_t actual = 0;
};

// Replays the frames closed-loop from the initial pose (each step starts from
// the pose this target computed) and compares every field of every record.
// Status errors are the tracker's (e.g. short scratch); a mismatch is not an
// error but is described in `report`.
Status check_vectors(const TableView& table, const VectorSet& set, TrackerScratch scratch, Report& report) noexcept;

// ---------------------------------------------------------------------------
// Session vectors (docs/file-formats.md), little-endian:
//   header   80 bytes  magic "GBSESS01", u32 frame_count, u32 width, u32 height,
//                      u8 detector kind, u8 flags (1 motion filter, 2 refine,
//                      4 recover, 8 recovery screened from shared search
//                      features), u16 detector threshold, f32 init x, y,
//                      theta_deg, u16 init depth, u16 stack depth count (0:
//                      no focus stack), u32 stack width, u32 stack height,
//                      f32 stack ref x, f32 stack ref y, u32 stack step,
//                      f32 recovery turn_deg, u32 budget, u32 interval,
//                      u32 screen_stride, 4 zero bytes
//   stack    depth count * stack width * stack height bytes, 8-bit
//   frames   frame_count * width * height bytes
//   expected frame_count records of kSessionRecordBytes: the vote's record
//            (encode_record), then f32 pose x, y, theta_deg, u16 depth,
//            u8 confidence, u8 state, f32 score, u8 reacquired,
//            u8 searched_coarse, u16 0
//   trailer  u32 CRC-32 of every byte before it
// The session runs with the default MotionFilterParams. Recovery either
// votes each placement with a full track_step (the mode a part short of RAM
// runs: session.gbs, replayed everywhere, firmware included) or screens them
// from features detected once (flag 8: session-screened.gbs, the hosted
// default, replayed on the Linux targets).
inline constexpr char kSessionMagic[8] = {'G', 'B', 'S', 'E', 'S', 'S', '0', '1'};
inline constexpr std::size_t kSessionHeaderBytes = 80;
inline constexpr std::size_t kSessionRecordBytes = kRecordBytes + 24;
inline constexpr std::uint16_t kMaxStackDepths = 16;

constexpr std::size_t session_file_bytes(std::uint32_t frames, std::uint32_t width, std::uint32_t height,
                                         std::uint16_t stack_depths, std::uint32_t stack_width,
                                         std::uint32_t stack_height) noexcept {
  return kSessionHeaderBytes + std::size_t{stack_depths} * stack_width * stack_height + std::size_t{frames} * width * height +
         std::size_t{frames} * kSessionRecordBytes + kTrailerBytes;
}

struct SessionVectorSet {
  std::uint32_t frame_count = 0;
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  Detector detector;
  Pose init;
  SessionOptions options;             // motion_filter, refine, recover and recovery from the file
  bool shared_search_features = false;  // recovery screened from features detected once (flag 8)
  std::uint16_t stack_depths = 0;
  std::uint32_t stack_width = 0, stack_height = 0;
  float stack_ref_x = 0.0f, stack_ref_y = 0.0f;
  std::uint32_t stack_step = 2;
  std::span<const std::byte> stack;     // stack_depths * stack_width * stack_height
  std::span<const std::byte> frames;    // frame_count * width * height
  std::span<const std::byte> expected;  // frame_count * kSessionRecordBytes

  ImageView frame(std::uint32_t i) const noexcept {
    return {reinterpret_cast<const std::uint8_t*>(frames.data()) + std::size_t{i} * width * height, width, height, width};
  }
  ImageView stack_image(std::uint16_t d) const noexcept {
    return {reinterpret_cast<const std::uint8_t*>(stack.data()) + std::size_t{d} * stack_width * stack_height, stack_width,
            stack_height, stack_width};
  }
};

// Validates size, magic, dimensions, options and CRC. Errors as open_vectors.
Status open_session_vectors(std::span<const std::byte> bytes, SessionVectorSet& out) noexcept;
void encode_session_header(const SessionVectorSet& set, std::span<std::byte, kSessionHeaderBytes> out) noexcept;
void encode_session_record(const SessionResult& result, std::span<std::byte, kSessionRecordBytes> out) noexcept;

// Replays the session from the initial pose and compares every field of
// every record. `stack_views` holds at least set.stack_depths entries (the
// caller's storage for the focus stack's views); with flag 8,
// scratch.search_features must hold search_feature_capacity(table) entries
// (else kBufferTooSmall), and without it they are not used. Status errors are
// the session's; a mismatch is described in `report`.
Status check_session_vectors(const TableView& table, const SessionVectorSet& set, SessionScratch scratch,
                             std::span<ImageView> stack_views, Report& report) noexcept;

// ---------------------------------------------------------------------------
// Particle vectors (docs/file-formats.md), little-endian:
//   header   64 bytes  magic "GBPART01", u32 frame_count, u32 width, u32 height,
//                      u8 detector kind, u8 flags (1: the finer measure,
//                      2: the intensity measure, else the edge measure),
//                      u16 detector threshold, f32 init x, y, theta_deg,
//                      u16 init depth, u16 vote proposals (0..8), u32 particles,
//                      u32 edge stride, u32 edge tolerance, u32 intensity
//                      samples (16..1024 with flag 2, else 0), u64 seed
//   frames   frame_count * width * height bytes
//   expected frame_count records of kParticleRecordBytes: f32 x, y,
//            theta_deg, u16 depth, u8 state, u8 flags (1 held, 2 part of the
//            cloud re-drawn), f32 score, u32 modes, u32 particles in the
//            chosen mode, u32 particles drawn around the proposals
//   trailer  u32 CRC-32 of every byte before it
// The filter runs with the default ParticleFilterOptions (every improvement
// of chapter 3 on) and the measure gabarit track --tracker particle runs:
// the edge measure on a table without model images (particle.gbp), the
// intensity measure with kIntensitySharpness on one with them
// (particle-intensity.gbp, with its own table particle-table.gbt).
inline constexpr char kParticleMagic[8] = {'G', 'B', 'P', 'A', 'R', 'T', '0', '1'};
inline constexpr std::size_t kParticleHeaderBytes = 64;
inline constexpr std::size_t kParticleRecordBytes = 32;
// The most particles a file may ask for (the firmware sizes for fewer).
inline constexpr std::uint32_t kMaxVectorParticles = 100000;

constexpr std::size_t particle_file_bytes(std::uint32_t frames, std::uint32_t width, std::uint32_t height) noexcept {
  return kParticleHeaderBytes + std::size_t{frames} * width * height + std::size_t{frames} * kParticleRecordBytes + kTrailerBytes;
}

struct ParticleVectorSet {
  std::uint32_t frame_count = 0;
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  Detector detector;
  Pose init;
  std::uint32_t particles = 1000;
  std::uint64_t seed = 1;
  std::uint32_t proposals = 4;
  std::uint32_t edge_stride = 2;
  std::uint32_t edge_tolerance = 0;
  bool finer = true;
  bool intensity = false;                // the intensity measure (needs a table with model images)
  std::uint32_t intensity_samples = 0;   // its sparse subset
  std::span<const std::byte> frames;    // frame_count * width * height
  std::span<const std::byte> expected;  // frame_count * kParticleRecordBytes

  ImageView frame(std::uint32_t i) const noexcept {
    return {reinterpret_cast<const std::uint8_t*>(frames.data()) + std::size_t{i} * width * height, width, height, width};
  }
};

// Validates size, magic, dimensions, the filter's numbers and CRC. Errors as open_vectors.
Status open_particle_vectors(std::span<const std::byte> bytes, ParticleVectorSet& out) noexcept;
void encode_particle_header(const ParticleVectorSet& set, std::span<std::byte, kParticleHeaderBytes> out) noexcept;
void encode_particle_record(const ParticleEstimate& estimate, std::span<std::byte, kParticleRecordBytes> out) noexcept;

// The replay's memory, sized for set.particles and set.width x set.height.
struct ParticleVectorScratch {
  ParticleScratch particles;              // particle_scratch_particles and particle_scratch_order of set.particles
  std::span<std::uint64_t> edge_bits;     // edge_map_words(width, height)
  std::span<RoiPoint> edge_features;      // edge_map_features(width)
  TrackerScratch proposer;                // track_step's for the table (the proposals' vote)
  // The intensity measure's (set.intensity): a view per depth of the
  // table's, and the coarse and the finer measure, reset here.
  std::span<ImageView> stack_views;
  std::span<IntensityCorrelationMeasure> intensity;  // 2
};

// Replays the particle tracker from the initial pose and compares every
// field of every record. Errors: kBufferTooSmall for scratch short of the
// sizes above; kInvalidArgument for the intensity measure on a table
// without model images; otherwise the filter's. A mismatch is described in
// `report`.
Status check_particle_vectors(const TableView& table, const ParticleVectorSet& set, ParticleVectorScratch scratch,
                              Report& report) noexcept;

}  // namespace gabarit::vectors
