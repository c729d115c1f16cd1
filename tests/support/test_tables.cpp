#include "test_tables.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "gabarit/byte_order.hpp"
#include "gabarit/deterministic_math.hpp"
#include "gabarit/host/tables/state_space.hpp"

namespace gabarit::testing {

std::vector<host::Point> random_points(app::Rng& rng, std::size_t n, std::int32_t half, double min_distance) {
  std::vector<host::Point> out;
  for (int tries = 0; out.size() < n && tries < 200000; ++tries) {
    const host::Point p{rng.uniform_int(-half, half), rng.uniform_int(-half, half)};
    bool ok = true;
    for (const host::Point& q : out) {
      const double d = std::hypot(double(p.x - q.x), double(p.y - q.y));
      if (d == 0 || d <= min_distance) {
        ok = false;
        break;
      }
    }
    if (ok) out.push_back(p);
  }
  return out;
}

host::ModelStack point_model(std::vector<host::Point> points) {
  host::ModelStack m;
  m.depths.push_back(std::move(points));
  m.detector.kind = table_format::DetectorKind::kBinary;
  return m;
}

std::vector<std::byte> build(const host::ModelStack& model, const std::string& x, const std::string& y,
                             const std::string& theta, double keep, std::uint64_t seed) {
  host::BuildOptions o;
  o.space.x = host::parse_axis(x, "x");
  o.space.y = host::parse_axis(y, "y");
  o.space.theta = host::parse_axis(theta, "theta");
  o.keep = keep;
  o.seed = seed;
  return host::build_table(model, o);
}

TableView open_table(std::span<const std::byte> bytes) {
  TableView view;
  const Status s = TableView::open(bytes, view);
  EXPECT_EQ(s, Status::kOk) << status_name(s);
  return view;
}

void reseal(std::vector<std::byte>& table) {
  store_le<std::uint32_t>(table.data() + table_format::offset::kCrc32, table_checksum(table));
}

app::GrayImage draw_points(const std::vector<host::Point>& pts, float x, float y, float theta_deg, std::uint32_t size) {
  app::GrayImage img(size, size);
  const SinCos sc = sin_cos_deg(theta_deg);
  for (const host::Point& p : pts) {
    const auto px = round_to_int(x + sc.cos * static_cast<float>(p.x) - sc.sin * static_cast<float>(p.y));
    const auto py = round_to_int(y + sc.sin * static_cast<float>(p.x) + sc.cos * static_cast<float>(p.y));
    if (px >= 0 && py >= 0 && px < static_cast<std::int32_t>(size) && py < static_cast<std::int32_t>(size)) {
      img.at(static_cast<std::uint32_t>(px), static_cast<std::uint32_t>(py)) = 255;
    }
  }
  return img;
}

PointScene::PointScene(std::uint64_t seed, std::size_t n, std::int32_t half, const std::string& xy, const std::string& theta,
                       std::uint32_t frame_side, double flip_probability)
    : side(frame_side), flip(flip_probability) {
  app::Rng rng(seed);
  points = random_points(rng, n, half, 2.0);
  bytes = build(point_model(points), xy, xy, theta);
  table = open_table(bytes);
}

app::GrayImage PointScene::frame(float x, float y, float theta_deg, bool visible, app::Rng& noise) const {
  app::GrayImage g = visible ? draw_points(points, x, y, theta_deg, side) : app::GrayImage(side, side);
  for (auto& v : g.pixels)
    if (noise.bernoulli(flip)) v = static_cast<std::uint8_t>(255 - v);
  return g;
}

}  // namespace gabarit::testing
