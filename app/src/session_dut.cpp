#include "gabarit/app/session_dut.hpp"

#include "gabarit/link/session_report.hpp"

namespace gabarit::app {

SessionDut::SessionDut(const TableView& table, bool plain, std::uint64_t (*clock)())
    : table_(table), plain_(plain), clock_(clock), options_(session_options(plain, false, false, false)),
      buffers_(table, nullptr, VoterChoice::kAuto, options_.recover), stack_(table) {}

std::uint32_t SessionDut::mode() const {
  if (plain_) return 0;
  return link::kModeSession | (buffers_.shares_search_features() ? link::kModeSharedSearch : 0u) |
         (stack_.get() != nullptr ? link::kModeFocusStack : 0u);
}

link::Refusal SessionDut::start(const link::Hello& hello) noexcept {
  session_.emplace(table_, nullptr, detector_of(table_));
  if (session_->start(options_, hello.initial) != Status::kOk) {
    session_.reset();
    return link::Refusal::kBadPose;
  }
  if (!plain_) session_->use_focus_stack(stack_.get());
  return link::Refusal::kNone;
}

bool SessionDut::track_next(link::DutEndpoint& endpoint) noexcept {
  link::ReadyFrame frame;
  if (!endpoint.next_frame(frame)) return false;
  if (!session_) {
    endpoint.report_failure(link::EventKind::kSkipped, link::EventReason::kNotStarted, 0, now());
    return true;
  }
  const ImageView image{frame.pixels.data(), frame.width, frame.height, frame.width};
  SessionResult result;
  if (const Status s = session_->step(image, buffers_.scratch(), result); s != Status::kOk) {
    endpoint.report_failure(link::EventKind::kError, link::EventReason::kTracking, static_cast<std::uint32_t>(s), now());
    return true;
  }
  endpoint.report_pose(link::session_report(result), now());
  return true;
}

}  // namespace gabarit::app
