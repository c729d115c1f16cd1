#include "gabarit/app/session_dut.hpp"

#include <exception>

#include "gabarit/link/session_report.hpp"

namespace gabarit::app {

SessionDut::SessionDut(const TableView& table, const SessionProfile& profile, std::uint64_t (*clock)())
    : clock_(clock), session_(table, profile) {}

link::Refusal SessionDut::start(const link::Hello& hello) noexcept {
  return session_.start(hello.initial) ? link::Refusal::kNone : link::Refusal::kBadPose;
}

bool SessionDut::track_next(link::DutEndpoint& endpoint) noexcept {
  link::ReadyFrame frame;
  if (!endpoint.next_frame(frame)) return false;
  if (!session_.started()) {
    endpoint.report_failure(link::EventKind::kSkipped, link::EventReason::kNotStarted, 0, now());
    return true;
  }
  const ImageView image{frame.pixels.data(), frame.width, frame.height, frame.width};
  SessionResult result;
  Status s = Status::kOk;
  try {  // a recovery stage is sized at the first frame (hosted_session.hpp), which may fail
    s = session_.step(image, result);
  } catch (const std::exception&) {
    s = Status::kBufferTooSmall;
  }
  if (s != Status::kOk) {
    endpoint.report_failure(link::EventKind::kError, link::EventReason::kTracking, static_cast<std::uint32_t>(s), now());
    return true;
  }
  endpoint.report_pose(link::session_report(result), now());
  return true;
}

}  // namespace gabarit::app
