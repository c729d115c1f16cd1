#include "gabarit/host/tables/table_builder.hpp"

#include <gtest/gtest.h>

#include <filesystem>

#include "gabarit/app/error.hpp"
#include "gabarit/app/image_io.hpp"
#include "gabarit/host/scenes/synth.hpp"
#include "gabarit/table_format.hpp"
#include "test_tables.hpp"

namespace gabarit {
namespace {

using testing::build;
using testing::point_model;

TEST(TableBuilder, SameInputsAndSeedGiveIdenticalBytes) {
  app::Rng rng(1);
  const auto model = point_model(testing::random_points(rng, 150, 25));
  for (double keep : {1.0, 0.5, 0.1}) {
    EXPECT_EQ(build(model, "-5:5:11", "-5:5:11", "-2:2:3", keep, 42), build(model, "-5:5:11", "-5:5:11", "-2:2:3", keep, 42));
  }
  const auto a = build(model, "-5:5:11", "-5:5:11", "0:0:1", 0.5, 42);
  const auto b = build(model, "-5:5:11", "-5:5:11", "0:0:1", 0.5, 43);
  EXPECT_NE(a, b);
  EXPECT_NE(testing::open_table(a).reference_count(), 0u);
}

TEST(TableBuilder, DecimationShrinksStencilsAndTheTable) {
  app::Rng rng(2);
  const auto model = point_model(testing::random_points(rng, 194, 30));
  const auto full = build(model, "-5:5:11", "-5:5:11");
  const auto tenth = build(model, "-5:5:11", "-5:5:11", "0:0:1", 0.1, 7);
  const TableView f = testing::open_table(full), t = testing::open_table(tenth);
  EXPECT_NEAR(static_cast<double>(t.reference_count()) / f.reference_count(), 0.1, 0.01);
  EXPECT_LT(tenth.size(), full.size());
  EXPECT_LT(t.max_stencil_size(), f.max_stencil_size());
  EXPECT_FLOAT_EQ(t.keep_ratio(), 0.1f);
  EXPECT_EQ(t.seed(), 7u);
}

TEST(TableBuilder, UsesTheNarrowestReferenceWidth) {
  const auto m = point_model({{0, 0}});
  EXPECT_EQ(testing::open_table(build(m, "0:255:256", "0:0:1")).reference_bytes(), 1);
  EXPECT_EQ(testing::open_table(build(m, "0:256:257", "0:0:1")).reference_bytes(), 2);
  static_assert(table_format::narrowest_reference_bytes(65536) == 2);
  static_assert(table_format::narrowest_reference_bytes(65537) == 4);
}

TEST(TableBuilder, ModelImageAndPointCsvGiveTheSameStencils) {
  const auto dir = std::filesystem::temp_directory_path() / "gabarit_builder_test";
  host::SynthOptions o;
  o.shape = host::random_closed_curve(120, 5);
  o.frames = 1;
  host::write_synthetic_sequence(o, dir.string());
  host::ImageModelOptions mo;
  mo.binary = true;
  const auto from_image = host::model_from_images({(dir / "model.pgm").string()}, mo);
  const auto from_csv = point_model(host::read_points_csv((dir / "model.csv").string()));
  const auto bytes_a = build(from_image, "-3:3:7", "-3:3:7");
  const TableView a = testing::open_table(bytes_a);
  const auto bytes_b = build(from_csv, "-3:3:7", "-3:3:7");
  const TableView b = testing::open_table(bytes_b);
  ASSERT_EQ(a.reference_count(), b.reference_count());
  ASSERT_EQ(a.roi_pixels(), b.roi_pixels());
  EXPECT_EQ(a.roi_origin_x(), b.roi_origin_x());
  for (std::uint32_t i = 0; i < a.reference_count(); ++i) ASSERT_EQ(a.reference(i), b.reference(i));
  std::filesystem::remove_all(dir);
}

TEST(TableBuilder, FocusStackCellsCarryTheirDepth) {
  host::ModelStack m;
  m.depths = {{{0, 0}, {5, 0}}, {{0, 0}, {0, 5}, {3, 3}}};
  const auto bytes = build(m, "-1:1:3", "-1:1:3");
  const TableView t = testing::open_table(bytes);
  EXPECT_EQ(t.cell_count(), 18u);
  EXPECT_EQ(t.depth_count(), 2);
  EXPECT_EQ(t.cell(8).depth, 0);
  EXPECT_EQ(t.cell(9).depth, 1);
  EXPECT_EQ(t.stencil_size(0), 2u);
  EXPECT_EQ(t.stencil_size(9), 3u);
  EXPECT_EQ(t.model_point_count(1), 3u);
}

TEST(TableBuilder, RejectsSpacesTooLargeForTheFormat) {
  const auto m = point_model({{0, 0}});
  EXPECT_THROW(build(m, "0:4095:4096", "0:4096:4097"), app::Error);  // more than 2^24 cells
  EXPECT_THROW(build(m, "0:1:1", "0:0:1"), app::Error);              // parse: one cell needs MIN == MAX
  EXPECT_THROW(build(m, "1:0:2", "0:0:1"), app::Error);
  EXPECT_THROW(build(m, "0:1", "0:0:1"), app::Error);
}

}  // namespace
}  // namespace gabarit
