// make_table_seeds OUTDIR: the table fuzz target's seed corpus. Valid tables
// of every kind the builder makes (binary and gradient detectors, rotation,
// several depths, decimated, one-, two- and four-byte references), and for every
// error TableView::open can report one table that reports it. Exits non-zero
// if an error code is not reached, so the corpus provably reaches them all.
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "gabarit/app/files.hpp"
#include "gabarit/byte_order.hpp"
#include "gabarit/host/tables/model.hpp"
#include "gabarit/app/rng.hpp"
#include "gabarit/host/tables/state_space.hpp"
#include "gabarit/host/scenes/synth.hpp"
#include "gabarit/host/tables/table_builder.hpp"
#include "gabarit/table_view.hpp"

namespace {

using namespace gabarit;
namespace tf = table_format;
namespace off = tf::offset;

std::vector<std::byte> build(const std::vector<host::Point>& points, int depths, const char* x, const char* theta,
                             table_format::DetectorKind kind, std::uint16_t threshold, double keep, bool images = false,
                             bool compact = true, std::uint32_t channels = 0) {
  host::ModelStack model;
  for (int d = 0; d < depths; ++d) {
    std::vector<host::Point> scaled;
    for (const host::Point& p : points) scaled.push_back({p.x + d * (p.x > 0 ? 1 : -1), p.y});
    model.depths.push_back(scaled);
    if (images) {  // format 1.1: a focus stack of small images, the points drawn in
      model.image_width = model.image_height = 33;
      model.ref_x = model.ref_y = 16;
      std::vector<std::uint8_t> image(33 * 33, static_cast<std::uint8_t>(60 + 20 * d));
      for (const host::Point& p : scaled)
        if (p.x >= -16 && p.x <= 16 && p.y >= -16 && p.y <= 16) image[static_cast<std::size_t>((p.y + 16) * 33 + p.x + 16)] = 220;
      model.images.push_back(image);
    }
  }
  model.detector.kind = kind;
  model.detector.threshold = threshold;
  host::BuildOptions o;
  o.space.x = host::parse_axis(x, "x");
  o.space.y = host::parse_axis(x, "y");
  o.space.theta = host::parse_axis(theta, "theta");
  o.keep = keep;
  o.compact_offsets = compact;
  o.orientation_channels = channels;
  return host::build_table(model, o);
}

void reseal(std::vector<std::byte>& t) { store_le<std::uint32_t>(t.data() + off::kCrc32, table_checksum(t)); }

Status status_of(const std::vector<std::byte>& t) {
  std::vector<std::uint64_t> words((t.size() + 7) / 8);
  if (!t.empty()) std::memcpy(words.data(), t.data(), t.size());
  TableView v;
  return TableView::open({reinterpret_cast<const std::byte*>(words.data()), t.size()}, v);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_table_seeds OUTDIR\n");
    return 2;
  }
  const std::filesystem::path dir = argv[1];
  std::filesystem::create_directories(dir);
  app::Rng rng(7);
  std::vector<host::Point> curve = host::random_closed_curve(40, 3);
  const auto binary = table_format::DetectorKind::kBinary, gradient = table_format::DetectorKind::kGradientRows,
             canny = table_format::DetectorKind::kCanny;
  const std::vector<std::pair<std::string, std::vector<std::byte>>> valid = {
      // u32 offsets (format 1.0): the variants below edit them in place.
      {"binary", build(curve, 1, "-2:2:5", "0:0:1", binary, 0, 1.0, false, false)},
      {"binary-compact", build(curve, 1, "-2:2:5", "0:0:1", binary, 0, 1.0)},
      {"rotation", build(curve, 1, "-1:1:3", "-2:2:3", gradient, 20, 1.0)},
      {"depths", build(curve, 3, "-1:1:3", "0:0:1", canny, 30, 1.0)},
      {"model-images", build(curve, 2, "-1:1:3", "-1:1:3", canny, 30, 1.0, true)},
      {"orientation-channels", build(curve, 1, "-1:1:3", "-1:1:3", canny, 30, 1.0, true, true, 16)},  // format 1.3
      {"orientation-channels-wide", build(curve, 2, "-1:1:3", "0:0:1", canny, 30, 1.0, true, false, 4)},
      {"decimated", build(curve, 1, "-3:3:7", "0:0:1", binary, 0, 0.3)},
      {"decimated-wide", build(curve, 1, "-3:3:7", "0:0:1", binary, 0, 0.3, false, false)},
      {"two-byte-refs", build(curve, 1, "-8:8:17", "0:0:1", binary, 0, 1.0)},
      {"four-byte-refs", build({{0, 0}}, 1, "-128:128:257", "0:0:1", binary, 0, 1.0)},  // 66,049 cells
  };
  std::map<Status, std::vector<std::byte>> errors;
  const std::vector<std::byte>& base = valid[0].second;
  const auto variant = [&](Status want, std::vector<std::byte> t) {
    const Status got = status_of(t);
    if (got == want) errors.emplace(want, std::move(t));
    else std::fprintf(stderr, "make_table_seeds: a %s variant gave %s\n", status_name(want), status_name(got));
  };
  const auto with_u32 = [&](std::size_t at, std::uint32_t v) {
    auto t = base;
    store_le<std::uint32_t>(t.data() + at, v);
    reseal(t);
    return t;
  };
  variant(Status::kTruncated, {base.begin(), base.begin() + 100});
  {
    auto t = base;
    t[0] = std::byte{'X'};
    variant(Status::kBadMagic, t);
  }
  {
    auto t = base;
    store_le<std::uint16_t>(t.data() + off::kVersionMajor, 2);
    variant(Status::kUnsupportedVersion, t);
  }
  {
    auto t = base;
    t.push_back(std::byte{0});
    variant(Status::kSizeMismatch, t);
  }
  {
    auto t = base;
    t[t.size() - 1] ^= std::byte{1};
    variant(Status::kBadChecksum, t);
  }
  variant(Status::kBadHeaderField, with_u32(off::kFlags, 1));
  variant(Status::kCountTooLarge, with_u32(off::kCellCount, tf::kMaxCells + 1));
  {
    const TableView v = [&] {
      TableView out;
      static_cast<void>(TableView::open(base, out));
      return out;
    }();
    const std::uint32_t offsets_at = load_le<std::uint32_t>(base.data() + off::kPixelOffsetsOffset);
    const std::uint32_t refs_at = load_le<std::uint32_t>(base.data() + off::kReferencesOffset);
    variant(Status::kSectionOutOfBounds, with_u32(off::kReferencesOffset, refs_at + 8));
    // Pixel 0's end offset above pixel 1's: decreasing offsets.
    auto t = base;
    store_le<std::uint32_t>(t.data() + offsets_at + 4, v.reference_count());
    reseal(t);
    variant(Status::kOffsetsNotMonotonic, t);
    // A reference to a cell that does not exist, and two out of order.
    std::uint32_t p = 0;
    while (v.references_begin(p + 1) - v.references_begin(p) < 2) ++p;
    auto range = base;
    range[refs_at + v.references_begin(p)] = std::byte{0xFF};
    reseal(range);
    variant(Status::kReferenceOutOfRange, range);
    auto order = base;
    std::swap(order[refs_at + v.references_begin(p)], order[refs_at + v.references_begin(p) + 1]);
    reseal(order);
    variant(Status::kReferencesNotSorted, order);
    // Two cells swap a reference's worth of stencil size: the total agrees,
    // each cell's count does not.
    const std::uint32_t cells_at = load_le<std::uint32_t>(base.data() + off::kCellsOffset);
    auto sizes = base;
    const std::size_t s0 = cells_at + tf::cell_offset::kStencilSize, s1 = s0 + tf::kCellDescriptorBytes;
    store_le<std::uint32_t>(sizes.data() + s0, load_le<std::uint32_t>(sizes.data() + s0) - 1);
    store_le<std::uint32_t>(sizes.data() + s1, load_le<std::uint32_t>(sizes.data() + s1) + 1);
    reseal(sizes);
    variant(Status::kStencilSizeMismatch, sizes);
  }
  for (const auto& [name, bytes] : valid) {
    if (status_of(bytes) != Status::kOk) {
      std::fprintf(stderr, "make_table_seeds: the %s table does not open\n", name.c_str());
      return 1;
    }
    app::write_file((dir / ("valid-" + name + ".gbt")).string(), bytes);
  }
  for (const auto& [status, bytes] : errors) app::write_file((dir / (std::string("error-") + status_name(status) + ".gbt")).string(), bytes);
  const Status loader_errors[] = {Status::kTruncated,          Status::kBadMagic,          Status::kUnsupportedVersion,
                                  Status::kSizeMismatch,       Status::kBadChecksum,       Status::kBadHeaderField,
                                  Status::kCountTooLarge,      Status::kSectionOutOfBounds, Status::kOffsetsNotMonotonic,
                                  Status::kReferenceOutOfRange, Status::kReferencesNotSorted, Status::kStencilSizeMismatch};
  int missing = 0;
  for (const Status s : loader_errors) {
    if (errors.count(s) == 0) {
      std::fprintf(stderr, "make_table_seeds: no seed reaches %s\n", status_name(s));
      ++missing;
    }
  }
  std::printf("make_table_seeds: %zu valid tables, %zu of %zu loader errors reached, in %s\n", valid.size(), errors.size(),
              std::size(loader_errors), dir.c_str());
  return missing == 0 ? 0 : 1;
}
