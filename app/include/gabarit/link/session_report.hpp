// A tracking session's frame as the link's POSE: the fields every DUT that
// runs the kernel reports, so each builds it the same way.
#pragma once

#include "gabarit/link/protocol.hpp"
#include "gabarit/tracking_session.hpp"

namespace gabarit::link {

// The session's pose, state, score and confidence with the raw vote's counts
// (what app::fill_row puts in a `gabarit track` row). frame_id, frame_crc
// and the DUT timestamps are the endpoint's to fill.
inline PoseReport session_report(const SessionResult& r, std::uint64_t cycles = 0) noexcept {
  PoseReport p;
  p.pose = r.pose;
  p.state = static_cast<std::uint8_t>(r.state);
  p.confidence = static_cast<std::uint8_t>(r.confidence);
  p.flags = r.reacquired ? kPoseReacquired : 0;
  p.best_votes = r.step.best.votes;
  p.score = r.score;
  p.features = r.step.features;
  p.features_dropped = r.step.features_dropped;
  p.votes = r.step.votes;
  p.cycles = cycles;
  return p;
}

}  // namespace gabarit::link
