// A hosted device under test: the kernel's TrackingSession behind the HIL
// link's endpoint (gabarit/link/dut_endpoint.hpp), with scratch allocated
// once per table. What the in-process DUT runs and what a Linux board's DUT
// application runs; the Cortex-M firmware does the same with static buffers.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "gabarit/app/scratch.hpp"
#include "gabarit/link/dut_endpoint.hpp"
#include "gabarit/table_view.hpp"
#include "gabarit/tracking_session.hpp"

namespace gabarit::app {

// An Application for link::deliver (dut_endpoint.hpp).
class SessionDut {
 public:
  // `plain`: the thesis's loop; else gabarit track's defaults (the session,
  // the recovery search detecting once per frame, the table's focus stack).
  // `clock` gives the DUT's timestamps in `clock_hz` ticks.
  SessionDut(const TableView& table, bool plain, std::uint64_t (*clock)());
  // The mode bits CAPS reports for it (link::kMode*).
  std::uint32_t mode() const;
  link::Refusal start(const link::Hello& hello) noexcept;
  std::uint64_t now() noexcept { return clock_(); }
  // Tracks the endpoint's next frame, if one is ready, and reports it (the
  // caller then flushes the endpoint's outbox).
  bool track_next(link::DutEndpoint& endpoint) noexcept;

 private:
  const TableView& table_;
  bool plain_;
  std::uint64_t (*clock_)();
  SessionOptions options_;
  SessionBuffers buffers_;
  TableFocusStack stack_;
  std::optional<TrackingSession> session_;
};

}  // namespace gabarit::app
