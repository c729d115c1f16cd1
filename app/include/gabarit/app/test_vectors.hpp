// Cross-target test vectors: one file, produced on the host by
// `gabarit vectors`, that every target (x86-64, aarch64 and armhf under
// qemu-user, Cortex-M under qemu-system-arm) replays through track_step and
// must reproduce bit for bit: poses, vote counts, best and runner-up cells.
//
// Like the kernel this reader never allocates, so the same code runs in the
// firmware on a const array in flash and on the host on a mapped file.
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
#include "gabarit/status.hpp"
#include "gabarit/table_view.hpp"
#include "gabarit/tracker.hpp"

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

}  // namespace gabarit::vectors
