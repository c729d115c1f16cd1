// The register interface (hdl/rtl/gbt_voter_axil.sv, 2 lanes): a table is
// loaded, features fed and results read back through AXI4-Lite transactions
// only, and compared with the kernel.
#include <gtest/gtest.h>
#include <verilated.h>

#include <memory>

#include "Vvoter_axil.h"
#include "test_tables.hpp"
#include "voter_harness.hpp"

namespace gabarit::hdl {
namespace {

class AxiMaster {
 public:
  AxiMaster() : context_(std::make_unique<VerilatedContext>()), m_(std::make_unique<Vvoter_axil>(context_.get())) {
    m_->rst_ni = 0;
    tick();
    m_->rst_ni = 1;
    tick();
  }
  void tick() {
    m_->clk_i = 0;
    m_->eval();
    m_->clk_i = 1;
    m_->eval();
  }
  void write(std::uint8_t addr, std::uint32_t data) {
    m_->s_axil_awvalid = 1;
    m_->s_axil_awaddr = addr;
    m_->s_axil_wvalid = 1;
    m_->s_axil_wdata = data;
    m_->s_axil_wstrb = 0xF;
    m_->s_axil_bready = 1;
    bool aw = false, w = false;
    for (int guard = 0; guard < 100000; ++guard) {
      m_->eval();
      const bool aw_now = m_->s_axil_awvalid && m_->s_axil_awready;
      const bool w_now = m_->s_axil_wvalid && m_->s_axil_wready;
      const bool b_now = m_->s_axil_bvalid && m_->s_axil_bready;
      tick();
      if (aw_now) aw = true, m_->s_axil_awvalid = 0;
      if (w_now) w = true, m_->s_axil_wvalid = 0;
      if (b_now && aw && w) return;
    }
    throw std::runtime_error("AXI write timed out");
  }
  std::uint32_t read(std::uint8_t addr) {
    m_->s_axil_arvalid = 1;
    m_->s_axil_araddr = addr;
    m_->s_axil_rready = 1;
    for (int guard = 0; guard < 1000; ++guard) {
      m_->eval();
      const bool ar_now = m_->s_axil_arvalid && m_->s_axil_arready;
      const bool r_now = m_->s_axil_rvalid && m_->s_axil_rready;
      const std::uint32_t data = m_->s_axil_rdata;
      tick();
      if (ar_now) m_->s_axil_arvalid = 0;
      if (r_now) return data;
    }
    throw std::runtime_error("AXI read timed out");
  }

 private:
  std::unique_ptr<VerilatedContext> context_;
  std::unique_ptr<Vvoter_axil> m_;
};

TEST(VoterAxiLite, LoadsTablesVotesAndReportsThroughRegistersOnly) {
  constexpr std::uint32_t kLanes = 2, kCells = 64, kPixels = 1024, kRefs = 4096;
  AxiMaster bus;
  EXPECT_EQ(bus.read(0x54), 0x47425431u);
  EXPECT_EQ(bus.read(0x58) >> 24, kLanes);
  app::Rng rng(5);
  for (int table = 0; table < 3; ++table) {
    const auto bytes = testing::build(testing::point_model(testing::random_points(rng, 12, 6)), "-3:3:7", "-2:2:5", "0:0:1",
                                      table == 0 ? 1.0 : 0.6, table + 1u);
    const TableView t = testing::open_table(bytes);
    ASSERT_LE(t.cell_count(), kCells);
    ASSERT_LE(t.roi_pixels(), kPixels);
    const app::HdlLayout l = app::hdl_layout(t, kLanes);
    const app::HdlWidths w = app::hdl_widths(kLanes, kCells, kRefs);
    bus.write(0x0C, t.cell_count());
    bus.write(0x10, (std::uint32_t{t.roi_height()} << 16) | t.roi_width());
    const auto load = [&](std::uint32_t sel, std::uint32_t lane, std::uint32_t addr, const std::vector<std::uint32_t>& data) {
      bus.write(0x38, (lane << 8) | sel);
      bus.write(0x3C, addr);
      for (std::size_t i = 0; i < data.size(); ++i) bus.write(static_cast<std::uint8_t>(0x40 + 4 * i), data[i]);
      bus.write(0x50, 1);
    };
    for (std::uint32_t p = 0; p < t.roi_pixels(); ++p) load(0, 0, p, app::hdl_offsets_word(l, p, w));
    for (std::uint32_t k = 0; k < kLanes; ++k) {
      for (std::uint32_t i = 0; i < l.refs[k].size(); ++i) load(1, k, i, {l.refs[k][i]});
      for (std::uint32_t i = 0; i < l.sizes[k].size(); ++i) load(2, k, i, {l.sizes[k][i]});
    }
    for (int frame = 0; frame < 3; ++frame) {
      std::vector<RoiPoint> f(200 + 100 * frame);
      for (auto& p : f) p = {static_cast<std::uint16_t>(rng.next_u32() % t.roi_width()), static_cast<std::uint16_t>(rng.next_u32() % t.roi_height())};
      bus.write(0x00, 1);  // frame start
      for (const RoiPoint& p : f) bus.write(0x08, (std::uint32_t{p.row} << 16) | p.col);
      bus.write(0x00, 2);  // frame end
      int polls = 0;
      while (!(bus.read(0x04) & 2u)) ASSERT_LT(++polls, 10000);
      const Outcome sw = kernel_outcome(t, f);
      Outcome hw;
      hw.best_cell = bus.read(0x14);
      hw.best_votes = bus.read(0x18);
      hw.runner_cell = bus.read(0x1C);
      hw.runner_votes = hw.runner_cell == kNoCell ? 0 : bus.read(0x20);
      hw.votes = bus.read(0x24);
      hw.features = bus.read(0x28);
      for (std::uint32_t c = 0; c < t.cell_count(); ++c) {
        bus.write(0x30, c);
        hw.counters.push_back(static_cast<VoteCounter>(bus.read(0x34)));
      }
      EXPECT_EQ(compare(hw, sw), "") << "table " << table << " frame " << frame;
      EXPECT_EQ(bus.read(0x04) & 0xCu, 0u);  // no overflow, no ROI error
    }
  }
}

}  // namespace
}  // namespace gabarit::hdl
