// A hosted device under test: the session a profile describes
// (hosted_session.hpp) behind the HIL link's endpoint
// (gabarit/link/dut_endpoint.hpp). What the in-process DUT runs; the Cortex-M
// firmware runs the static twin of it (platform/cortex-m/hil_dut.cpp).
#pragma once

#include <cstdint>

#include "gabarit/app/hosted_session.hpp"
#include "gabarit/app/session_profile.hpp"
#include "gabarit/link/dut_endpoint.hpp"
#include "gabarit/table_view.hpp"

namespace gabarit::app {

// An Application for link::deliver (dut_endpoint.hpp).
class SessionDut {
 public:
  // `clock` gives the DUT's timestamps in `clock_hz` ticks. Throws app::Error
  // for a profile the table cannot run.
  SessionDut(const TableView& table, const SessionProfile& profile, std::uint64_t (*clock)());
  // The mode bits CAPS reports for it (session_profile.hpp, mode_bits).
  std::uint32_t mode() const { return session_.mode(); }
  link::Refusal start(const link::Hello& hello) noexcept;
  std::uint64_t now() noexcept { return clock_(); }
  // Tracks the endpoint's next frame, if one is ready, and reports it (the
  // caller then flushes the endpoint's outbox).
  bool track_next(link::DutEndpoint& endpoint) noexcept;

 private:
  std::uint64_t (*clock_)();
  HostedSession session_;
};

}  // namespace gabarit::app
