// The table loader must reject every damaged table with a distinct error and
// never read outside the buffer it is given (this suite runs under
// AddressSanitizer in CI; each candidate sits in an exact-size heap buffer so
// one byte past the end is caught).
#include "gabarit/table_view.hpp"

#include <gtest/gtest.h>

#include <bit>

#include <set>
#include <vector>

#include "gabarit/byte_order.hpp"
#include "gabarit/voter.hpp"
#include "test_tables.hpp"

namespace gabarit {
namespace {

namespace off = table_format::offset;
using testing::build;
using testing::point_model;
using testing::reseal;

// A small table with one u32 offset per pixel (format 1.0), which the
// crafted-payload tests below edit in place.
std::vector<std::byte> small_table(bool compact = false) {
  app::Rng rng(11);
  host::BuildOptions o;
  o.space.x = host::parse_axis("-2:2:5", "x");
  o.space.y = host::parse_axis("-1:1:3", "y");
  o.compact_offsets = compact;
  return host::build_table(point_model(testing::random_points(rng, 12, 6)), o);
}

// Writes a header field of `width` bytes (1, 2 or 4) at `at`, little-endian.
void store_field(std::vector<std::byte>& t, std::size_t at, std::uint32_t value, int width) {
  std::byte* p = t.data() + at;
  if (width == 1) store_le<std::uint8_t>(p, static_cast<std::uint8_t>(value));
  if (width == 2) store_le<std::uint16_t>(p, static_cast<std::uint16_t>(value));
  if (width == 4) store_le<std::uint32_t>(p, value);
}

Status open_copy(const std::vector<std::byte>& bytes) {
  const std::vector<std::byte> exact(bytes.begin(), bytes.end());  // exact-size allocation for ASan
  TableView v;
  return TableView::open(exact, v);
}

TEST(TableView, OpensAWellFormedTableAndReadsItBack) {
  app::Rng rng(3);
  const auto pts = testing::random_points(rng, 20, 8);
  const auto bytes = build(point_model(pts), "-3:3:7", "-2:2:5");
  const TableView t = testing::open_table(bytes);
  EXPECT_EQ(t.cell_count(), 35u);
  EXPECT_EQ(t.reference_bytes(), 1);
  EXPECT_EQ(t.model_point_count(), 20u);
  EXPECT_EQ(t.axis_x().cells, 7u);
  EXPECT_EQ(t.cell(0).x_lo, -3.5f);
  EXPECT_EQ(t.cell(34).y_hi, 2.5f);
  EXPECT_EQ(t.stencil_size(0), 20u);
  EXPECT_EQ(t.references_begin(t.roi_pixels()), t.reference_count());
  for (std::uint32_t i = 0; i < t.model_point_count(); ++i) {
    EXPECT_EQ(t.model_point(i).x, pts[i].x);
    EXPECT_EQ(t.model_point(i).y, pts[i].y);
  }
}

// Documented preconditions are checked where GABARIT_ASSERTS is on (the dev
// preset): a cell index past the end stops the program instead of reading
// past the descriptors.
TEST(TableViewDeathTest, APreconditionBrokenInADevBuildStopsTheProgram) {
#if defined(GABARIT_ASSERTS_ENABLED) && GABARIT_ASSERTS_ENABLED
  const auto bytes = small_table();
  const TableView t = testing::open_table(bytes);
  EXPECT_EQ(t.cell(t.cell_count() - 1).depth, 0);
  EXPECT_DEATH(static_cast<void>(t.cell(t.cell_count())), "");
  EXPECT_DEATH(static_cast<void>(t.reference(t.reference_count())), "");
#else
  GTEST_SKIP() << "GABARIT_ASSERTS is off in this build";
#endif
}

TEST(TableView, ReadsAtAnyAlignment) {
  const auto bytes = small_table();
  for (std::size_t shift = 1; shift < 8; ++shift) {
    std::vector<std::byte> buffer(bytes.size() + shift);
    std::copy(bytes.begin(), bytes.end(), buffer.begin() + static_cast<std::ptrdiff_t>(shift));
    TableView t;
    ASSERT_EQ(TableView::open(std::span(buffer).subspan(shift), t), Status::kOk) << "shift " << shift;
    EXPECT_EQ(t.cell(3).x_lo, testing::open_table(bytes).cell(3).x_lo);
  }
}

TEST(TableView, RejectsEveryTruncation) {
  const auto bytes = small_table();
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    EXPECT_EQ(open_copy({bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(n)}), Status::kTruncated) << "length " << n;
  }
}

TEST(TableView, RejectsTrailingBytes) {
  auto bytes = small_table();
  bytes.push_back(std::byte{0});
  EXPECT_EQ(open_copy(bytes), Status::kSizeMismatch);
}

TEST(TableView, RejectsEveryBitFlipWithTheErrorOfTheFieldHit) {
  const auto bytes = small_table();
  for (std::size_t byte = 0; byte < bytes.size(); ++byte) {
    for (int bit = 0; bit < 8; ++bit) {
      auto bad = bytes;
      bad[byte] ^= std::byte(1u << bit);
      const Status s = open_copy(bad);
      if (byte < off::kVersionMajor) {
        EXPECT_EQ(s, Status::kBadMagic) << byte;
      } else if (byte < off::kVersionMinor) {
        EXPECT_EQ(s, Status::kUnsupportedVersion) << byte;
      } else if (byte >= off::kHeaderBytes && byte < off::kFileBytes) {
        EXPECT_EQ(s, Status::kBadHeaderField) << byte;
      } else if (byte >= off::kFileBytes && byte < off::kCrc32) {
        EXPECT_TRUE(s == Status::kTruncated || s == Status::kSizeMismatch) << byte << " " << status_name(s);
      } else {
        EXPECT_EQ(s, Status::kBadChecksum) << "byte " << byte << " bit " << bit << ": " << status_name(s);
      }
    }
  }
}

TEST(TableView, RejectsOtherVersionsButAcceptsANewerMinor) {
  auto bytes = small_table();
  store_le<std::uint16_t>(bytes.data() + off::kVersionMajor, 2);
  EXPECT_EQ(open_copy(bytes), Status::kUnsupportedVersion);
  store_le<std::uint16_t>(bytes.data() + off::kVersionMajor, 0);
  EXPECT_EQ(open_copy(bytes), Status::kUnsupportedVersion);
  bytes = small_table();
  store_le<std::uint16_t>(bytes.data() + off::kVersionMinor, 7);  // minor versions only add meaning to reserved fields
  reseal(bytes);
  EXPECT_EQ(open_copy(bytes), Status::kOk);
}

// Format 1.1: a table built from images carries them, one per depth, after
// the model points; a crafted size or offset is refused.
TEST(TableView, CarriesTheModelImagesOfATableBuiltFromImages) {
  app::Rng rng(5);
  host::ModelStack model = point_model(testing::random_points(rng, 12, 6));
  model.depths.push_back(model.depths[0]);
  model.image_width = 7;
  model.image_height = 5;
  for (int d = 0; d < 2; ++d) {
    std::vector<std::uint8_t> image(35);
    for (std::size_t i = 0; i < image.size(); ++i) image[i] = static_cast<std::uint8_t>(10 * d + i);
    model.images.push_back(image);
  }
  host::BuildOptions o;
  o.space.x = host::parse_axis("-2:2:5", "x");
  o.space.y = host::parse_axis("-1:1:3", "y");
  const std::vector<std::byte> bytes = host::build_table(model, o);
  const TableView t = testing::open_table(bytes);
  ASSERT_TRUE(t.has_model_images());
  EXPECT_EQ(load_le<std::uint16_t>(bytes.data() + off::kVersionMinor), 2);  // compact offsets too
  const ImageView second = t.model_image(1);
  EXPECT_EQ(second.width, 7u);
  EXPECT_EQ(second.height, 5u);
  EXPECT_EQ(second.at(3, 2), 10 + 2 * 7 + 3);
  EXPECT_EQ(bytes.size() % 8, 0u);
  const auto edited = [&](std::size_t at, std::uint32_t value, int width) {
    auto bad = bytes;
    store_field(bad, at, value, width);
    reseal(bad);
    return open_copy(bad);
  };
  EXPECT_EQ(edited(off::kModelImagesOffset, load_le<std::uint32_t>(bytes.data() + off::kModelImagesOffset) + 8, 4),
            Status::kSectionOutOfBounds);
  EXPECT_EQ(edited(off::kModelWidth, 8, 2), Status::kSizeMismatch);  // the images no longer fill the file
  EXPECT_EQ(edited(off::kModelWidth, 0, 2), Status::kBadHeaderField);
  EXPECT_EQ(edited(off::kModelWidth, 0xFFFFFFFFu /* 65535 x 65535 */, 4), Status::kCountTooLarge);
  EXPECT_EQ(edited(off::kVersionMinor, 0, 2), Status::kBadHeaderField);
  o.compact_offsets = false;
  const std::vector<std::byte> wide = host::build_table(model, o);
  EXPECT_EQ(load_le<std::uint16_t>(wide.data() + off::kVersionMinor), 1);
  // Without them (--no-model-images) and with u32 offsets the table is format 1.0, as before.
  o.store_model_images = false;
  const std::vector<std::byte> plain = host::build_table(model, o);
  EXPECT_FALSE(testing::open_table(plain).has_model_images());
  EXPECT_EQ(load_le<std::uint16_t>(plain.data() + off::kVersionMinor), 0);
  EXPECT_EQ(plain.size() + 2 * 35 + 2, wide.size());  // 70 bytes of images, aligned to 8
}

// Compact offsets (format 1.2) hold the same lists as u32 offsets, in fewer
// bytes, and a crafted encoding is refused.
TEST(TableView, CompactOffsetsHoldTheSameListsAndRefuseACraftedEncoding) {
  const auto wide = small_table(false);
  const auto compact = small_table(true);
  const TableView w = testing::open_table(wide);
  const TableView c = testing::open_table(compact);
  ASSERT_EQ(w.offset_delta_bytes(), 0);
  ASSERT_NE(c.offset_delta_bytes(), 0);
  EXPECT_LT(compact.size(), wide.size());
  EXPECT_EQ(load_le<std::uint16_t>(compact.data() + off::kVersionMinor), 2);
  ASSERT_EQ(c.roi_pixels(), w.roi_pixels());
  for (std::uint32_t p = 0; p <= w.roi_pixels(); ++p) ASSERT_EQ(c.references_begin(p), w.references_begin(p)) << p;
  for (std::uint32_t i = 0; i < w.reference_count(); ++i) ASSERT_EQ(c.reference(i), w.reference(i));

  const auto edited = [&](std::size_t at, std::uint32_t value, int width) {
    auto bad = compact;
    store_field(bad, at, value, width);
    reseal(bad);
    return open_copy(bad);
  };
  EXPECT_EQ(edited(off::kOffsetDeltaBytes, 3, 1), Status::kBadHeaderField);
  EXPECT_EQ(edited(off::kOffsetBlockLog2, 6, 1), Status::kBadHeaderField);
  EXPECT_EQ(edited(off::kVersionMinor, 1, 2), Status::kBadHeaderField);
  EXPECT_EQ(edited(off::kOffsetDeltaCount, c.roi_pixels() + 1, 4), Status::kBadHeaderField);
  // Another delta count moves the references: the layout no longer matches.
  EXPECT_NE(edited(off::kOffsetDeltaCount, load_le<std::uint32_t>(compact.data() + off::kOffsetDeltaCount) - 1, 4), Status::kOk);
  // The block headers: a wrong rank, a pixel past the ROI marked, a base
  // that does not follow from the block before, and deltas out of order.
  const std::uint32_t blocks_at = load_le<std::uint32_t>(compact.data() + off::kPixelOffsetsOffset);
  const std::uint32_t blocks = table_format::offset_block_count(c.roi_pixels());
  const std::uint32_t deltas_at = blocks_at + blocks * table_format::kOffsetBlockHeaderBytes;
  ASSERT_GE(blocks, 2u);
  constexpr std::uint32_t H = table_format::kOffsetBlockHeaderBytes;
  EXPECT_EQ(edited(blocks_at + H + 4, load_le<std::uint32_t>(compact.data() + blocks_at + H + 4) + 1, 4), Status::kOffsetsNotMonotonic);
  {
    auto bad = compact;
    const std::size_t last_mask = blocks_at + (blocks - 1) * H + 16;
    store_le<std::uint64_t>(bad.data() + last_mask, load_le<std::uint64_t>(bad.data() + last_mask) | (std::uint64_t{1} << 63));
    reseal(bad);
    EXPECT_EQ(open_copy(bad), Status::kOffsetsNotMonotonic);  // position 128 (blocks - 1) + 127 is past the ROI
  }
  EXPECT_EQ(edited(blocks_at + H, load_le<std::uint32_t>(compact.data() + blocks_at + H) + 1, 4), Status::kOffsetsNotMonotonic);
  ASSERT_EQ(c.offset_delta_bytes(), 1);
  EXPECT_EQ(edited(deltas_at + 1, load_le<std::uint8_t>(compact.data() + deltas_at), 1), Status::kOffsetsNotMonotonic);
  EXPECT_EQ(edited(deltas_at, 0, 1), Status::kOffsetsNotMonotonic);  // a marked pixel that lists nothing
}

struct Edit {
  const char* what;
  std::size_t at;
  std::uint32_t value;
  int width;  // bytes
  Status expected;
};

TEST(TableView, RejectsCraftedHeadersWithAValidChecksum) {
  const auto good = small_table();
  const TableView t = testing::open_table(good);
  const Edit edits[] = {
      {"cell count over the limit", off::kCellCount, table_format::kMaxCells + 1, 4, Status::kCountTooLarge},
      {"reference count over the limit", off::kReferenceCount, table_format::kMaxReferences + 1, 4, Status::kCountTooLarge},
      {"ROI over the limit", off::kRoiWidth, 0xFFFFFFFFu /* 65535 x 65535 */, 4, Status::kCountTooLarge},
      {"model points over the limit", off::kModelPointCount, table_format::kMaxModelPoints + 1, 4, Status::kCountTooLarge},
      {"cell count disagreeing with the space", off::kCellCount, t.cell_count() + 1, 4, Status::kSizeMismatch},
      {"reference count beyond the file", off::kReferenceCount, t.reference_count() + 100000, 4, Status::kSectionOutOfBounds},
      {"zero cells", off::kCellCount, 0, 4, Status::kBadHeaderField},
      {"the model-images flag in a 1.0 table", off::kFlags, 1, 4, Status::kBadHeaderField},
      {"reference width not the narrowest", off::kReferenceBytes, 2, 1, Status::kBadHeaderField},
      {"unknown detector", off::kDetectorKind, 9, 1, Status::kBadHeaderField},
      {"zero x cells", off::kAxisX + 8, 0, 4, Status::kBadHeaderField},
      {"keep ratio above 1", off::kKeepRatio, 0x40000000u /* 2.0f */, 4, Status::kBadHeaderField},
      {"section moved", off::kReferencesOffset, 8, 4, Status::kSectionOutOfBounds},
      {"max stencil size wrong", off::kMaxStencilSize, 3, 4, Status::kStencilSizeMismatch},
      {"reserved byte set", off::kReserved147 + 4, 1, 1, Status::kBadHeaderField},
      {"reserved byte 147 set", off::kReserved147, 1, 1, Status::kBadHeaderField},
      {"channels without the flag", off::kOrientationChannels, 16, 1, Status::kBadHeaderField},
      {"the channels flag in a 1.0 table", off::kFlags, 4, 4, Status::kBadHeaderField},
      {"an unknown flag", off::kFlags, 8, 4, Status::kBadHeaderField},
      {"the compact-offsets flag in a 1.0 table", off::kFlags, 2, 4, Status::kBadHeaderField},
      {"an offset delta width without compact offsets", off::kOffsetDeltaBytes, 1, 1, Status::kBadHeaderField},
      {"a model-images offset without the flag", off::kModelImagesOffset, 8, 4, Status::kBadHeaderField},
  };
  for (const Edit& e : edits) {
    auto bad = good;
    store_field(bad, e.at, e.value, e.width);
    reseal(bad);
    EXPECT_EQ(open_copy(bad), e.expected) << e.what << ": got " << status_name(open_copy(bad));
  }
}

// Finite values that the kernel would later compute with past what it can
// serve (table_format.hpp, "Limits"): each refused with a valid checksum.
TEST(TableView, RejectsFieldsBeyondTheLimitsWithAValidChecksum) {
  const auto good = small_table();  // binary, x -2..2, y -1..1
  const std::uint32_t cells_at = load_le<std::uint32_t>(good.data() + off::kCellsOffset);
  namespace co = table_format::cell_offset;
  const auto f32 = [](float v) { return std::bit_cast<std::uint32_t>(v); };
  const Edit edits[] = {
      {"x axis beyond +-1024 px (the search grid's float-to-int overflow)", off::kAxisX + 4, f32(3.0e38f), 4, Status::kBadHeaderField},
      {"theta axis beyond +-360 deg", off::kAxisTheta, f32(-400.0f), 4, Status::kBadHeaderField},
      {"reference point beyond +-16384 px (depth by intensity's fixed point)", off::kModelRefX, f32(1.0e9f), 4, Status::kBadHeaderField},
      {"a cell bound of 3e38 (poses of infinity)", cells_at + co::kXHi, f32(3.0e38f), 4, Status::kBadHeaderField},
      {"a rotated-ROI window wider than 2048 px (gigabytes of scratch)", off::kRoiOriginX, static_cast<std::uint16_t>(-30000), 2,
       Status::kCountTooLarge},
      {"a gradient detector with threshold 0 (every frame would fail)", off::kDetectorKind, 1, 1, Status::kBadHeaderField},
      {"a Canny detector with threshold 1 (its low threshold would be 0)", off::kDetectorKind, 2, 1, Status::kBadHeaderField},
  };
  for (const Edit& e : edits) {
    auto bad = good;
    store_field(bad, e.at, e.value, e.width);
    if (e.at == off::kDetectorKind) store_le<std::uint16_t>(bad.data() + off::kDetectorThreshold, e.value == 2 ? 1 : 0);
    reseal(bad);
    EXPECT_EQ(open_copy(bad), e.expected) << e.what << ": got " << status_name(open_copy(bad));
  }
  // A gradient threshold in range opens.
  auto gradient = good;
  store_le<std::uint8_t>(gradient.data() + off::kDetectorKind, 1);
  store_le<std::uint16_t>(gradient.data() + off::kDetectorThreshold, 2040);
  reseal(gradient);
  EXPECT_EQ(open_copy(gradient), Status::kOk);
}

// The spec says each cell appears exactly stencil_size times. Moving one
// unit of stencil size from one cell to another keeps the total (and the
// maximum) right; the per-cell count still catches it. Accepted, the first
// cell's score could pass 1 and a clutter frame report "tracking".
TEST(TableView, RejectsACellReferencedOtherThanItsStencilSize) {
  app::Rng rng(11);
  host::BuildOptions o;  // decimated in one global pass, so stencil sizes differ
  o.space.x = host::parse_axis("-2:2:5", "x");
  o.space.y = host::parse_axis("-1:1:3", "y");
  o.keep = 0.5;
  o.seed = 3;
  o.decimation.method = host::Decimation::kGlobal;
  const auto good = host::build_table(point_model(testing::random_points(rng, 12, 6)), o);
  const std::uint32_t cells_at = load_le<std::uint32_t>(good.data() + off::kCellsOffset);
  const TableView t = testing::open_table(good);
  const auto below_max = [&](std::uint32_t c) { return t.stencil_size(c) > 0 && t.stencil_size(c) < t.max_stencil_size(); };
  std::uint32_t a = 0;  // two cells strictly below the maximum stencil size
  while (a < t.cell_count() && !below_max(a)) ++a;
  std::uint32_t b = a + 1;
  while (b < t.cell_count() && !below_max(b)) ++b;
  ASSERT_LT(b, t.cell_count());
  auto bad = good;
  const std::size_t sa = cells_at + std::size_t{a} * table_format::kCellDescriptorBytes + table_format::cell_offset::kStencilSize;
  const std::size_t sb = cells_at + std::size_t{b} * table_format::kCellDescriptorBytes + table_format::cell_offset::kStencilSize;
  store_le<std::uint32_t>(bad.data() + sa, load_le<std::uint32_t>(bad.data() + sa) + 1);
  store_le<std::uint32_t>(bad.data() + sb, load_le<std::uint32_t>(bad.data() + sb) - 1);
  reseal(bad);
  EXPECT_EQ(open_copy(bad), Status::kStencilSizeMismatch);
}

TEST(TableView, RefusesABufferLargerThanAnyValidTableBeforeItsChecksum) {
  // A header declaring 1 GiB + 8 bytes over a buffer of that size: refused
  // as too large, without reading (or checksumming) the rest.
  const std::size_t n = std::size_t{table_format::kMaxTableBytes} + 8;
  std::vector<std::byte> big(n);
  const auto good = small_table();
  std::copy(good.begin(), good.begin() + table_format::kHeaderBytes, big.begin());
  store_le<std::uint32_t>(big.data() + off::kFileBytes, static_cast<std::uint32_t>(n));
  TableView v;
  EXPECT_EQ(TableView::open(big, v), Status::kCountTooLarge);
}

TEST(TableView, RejectsCraftedPayloadsWithAValidChecksum) {
  const auto good = small_table();
  const std::uint32_t offsets_at = load_le<std::uint32_t>(good.data() + off::kPixelOffsetsOffset);
  const std::uint32_t refs_at = load_le<std::uint32_t>(good.data() + off::kReferencesOffset);
  const std::uint32_t cells_at = load_le<std::uint32_t>(good.data() + off::kCellsOffset);
  const TableView t = testing::open_table(good);
  // Find a pixel with at least two references.
  std::uint32_t pixel = 0;
  while (t.references_begin(pixel + 1) - t.references_begin(pixel) < 2) ++pixel;
  const std::uint32_t first = t.references_begin(pixel);

  auto bad = good;
  store_le<std::uint8_t>(bad.data() + refs_at + first, static_cast<std::uint8_t>(t.cell_count()));
  reseal(bad);
  EXPECT_EQ(open_copy(bad), Status::kReferenceOutOfRange);

  bad = good;
  store_le<std::uint8_t>(bad.data() + refs_at + first + 1, static_cast<std::uint8_t>(t.reference(first)));
  reseal(bad);
  EXPECT_EQ(open_copy(bad), Status::kReferencesNotSorted);

  bad = good;
  store_le<std::uint32_t>(bad.data() + offsets_at + 4 * (pixel + 1), t.reference_count() + 5);
  reseal(bad);
  EXPECT_EQ(open_copy(bad), Status::kOffsetsNotMonotonic);

  bad = good;
  store_le<std::uint32_t>(bad.data() + offsets_at, 1);
  reseal(bad);
  EXPECT_EQ(open_copy(bad), Status::kOffsetsNotMonotonic);

  bad = good;
  store_le<std::uint32_t>(bad.data() + cells_at + table_format::cell_offset::kStencilSize, t.stencil_size(0) + 1);
  reseal(bad);
  EXPECT_EQ(open_copy(bad), Status::kStencilSizeMismatch);

  bad = good;
  store_le<std::uint16_t>(bad.data() + cells_at + table_format::cell_offset::kDepth, 1);
  reseal(bad);
  EXPECT_EQ(open_copy(bad), Status::kBadHeaderField);

  bad = good;
  store_le<std::uint32_t>(bad.data() + cells_at + table_format::cell_offset::kXLo, 0x7FC00000u);  // NaN
  reseal(bad);
  EXPECT_EQ(open_copy(bad), Status::kBadHeaderField);
}

TEST(TableView, RandomResealedCorruptionNeverCrashesAndWhatOpensIsUsable) {
  const auto good = small_table();
  app::Rng rng(2024);
  std::set<Status> seen;
  for (int round = 0; round < 3000; ++round) {
    auto bad = good;
    const int edits = 1 + static_cast<int>(rng.next_u32() % 4);
    for (int e = 0; e < edits; ++e) {
      bad[rng.next_u32() % bad.size()] = static_cast<std::byte>(rng.next_u32());
    }
    reseal(bad);
    const std::vector<std::byte> exact(bad.begin(), bad.end());
    TableView v;
    const Status s = TableView::open(exact, v);
    seen.insert(s);
    if (s == Status::kOk) {
      // Whatever validated must be safe to vote with, every pixel a feature.
      std::vector<RoiPoint> all;
      for (std::uint16_t r = 0; r < v.roi_height(); ++r)
        for (std::uint16_t c = 0; c < v.roi_width(); ++c) all.push_back({c, r});
      std::vector<VoteCounter> counters(v.cell_count());
      VoteTally tally;
      ASSERT_EQ(accumulate_votes(v, all, counters, tally), Status::kOk);
      ASSERT_EQ(tally.votes, v.reference_count());
    }
  }
  EXPECT_GE(seen.size(), 4u);  // the corruption reached several distinct checks
}

}  // namespace
}  // namespace gabarit
