// Helpers shared by the tests: random shapes and tables built with the real
// host builder, so every test exercises the production code paths.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "gabarit/app/image_io.hpp"
#include "gabarit/host/tables/model.hpp"
#include "gabarit/app/rng.hpp"
#include "gabarit/host/tables/table_builder.hpp"
#include "gabarit/table_view.hpp"
#include "gabarit/tracker.hpp"

namespace gabarit::testing {

// n distinct points in [-half, half]^2 whose pairwise Euclidean distance is
// > min_distance (best effort: gives up on a point after many tries).
std::vector<host::Point> random_points(app::Rng& rng, std::size_t n, std::int32_t half, double min_distance = 0);

host::ModelStack point_model(std::vector<host::Point> points);

std::vector<std::byte> build(const host::ModelStack& model, const std::string& x, const std::string& y,
                             const std::string& theta = "0:0:1", double keep = 1.0, std::uint64_t seed = 1);

// Opens a table and fails the current test if it does not validate.
TableView open_table(std::span<const std::byte> bytes);

// A binary frame of size x size with `pts` (relative to the reference point)
// rotated by theta_deg and placed at (x, y), the tracker's geometry.
app::GrayImage draw_points(const std::vector<host::Point>& pts, float x, float y, float theta_deg, std::uint32_t size);

// track_step's scratch for one table, sized by the kernel's formulas (CSR voter).
struct TrackerTestScratch {
  explicit TrackerTestScratch(const TableView& t)
      : features(tracker_feature_capacity(t)), counters(voter_counter_count(t.cell_count())), mask(tracker_mask_bytes(t)) {}
  TrackerScratch view() { return {features, counters, mask}; }
  std::vector<RoiPoint> features;
  std::vector<VoteCounter> counters;
  std::vector<std::uint8_t> mask;
};

// A random point model (n points in [-half, half]^2, at least 2 px apart),
// its table over x and y `xy` and `theta`, and binary side x side frames of
// it with each pixel flipped with probability `flip`. Not copyable: the
// table views its own bytes.
struct PointScene {
  PointScene(std::uint64_t seed, std::size_t n, std::int32_t half, const std::string& xy, const std::string& theta,
             std::uint32_t side, double flip);
  PointScene(const PointScene&) = delete;
  PointScene& operator=(const PointScene&) = delete;
  // The model at (x, y, theta_deg), or an empty frame when not visible.
  app::GrayImage frame(float x, float y, float theta_deg, bool visible, app::Rng& noise) const;

  std::vector<host::Point> points;
  std::vector<std::byte> bytes;
  TableView table;
  std::uint32_t side = 0;
  double flip = 0.0;
};

// Re-seals a deliberately edited table with a correct CRC, so structural
// checks (not the CRC) are what rejects it.
void reseal(std::vector<std::byte>& table);

}  // namespace gabarit::testing
