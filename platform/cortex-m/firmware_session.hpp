// The firmware's tracking session: the static twin of app::HostedSession
// (app/hosted_session.hpp). Same profile, same kernel calls, but every buffer
// is the caller's (static arrays in the firmware, sized by the kernel's
// constexpr formulas) and only the recovery the firmware's memory holds: the
// grid search, without shared features (they would need about 4 bytes per
// pixel of the search window). Header-only and free of anything MCU-specific,
// so the host's tests build it and compare it with HostedSession frame by
// frame (tests/app/session_profile_test.cpp).
#pragma once

#include <cstdint>
#include <span>

#include "gabarit/app/session_profile.hpp"
#include "gabarit/depth_by_intensity.hpp"
#include "gabarit/table_view.hpp"
#include "gabarit/tracking_session.hpp"

namespace gabarit::mcu {

// What the firmware runs: gabarit track's defaults, less what its memory lacks.
inline constexpr app::SessionProfile kFirmwareProfile = [] {
  app::SessionProfile p;
  p.shared_search = false;
  p.recovery = app::RecoveryKind::kGrid;  // no room for a finder
  return p;
}();
static_assert(kFirmwareProfile.recovery == app::RecoveryKind::kGrid, "the firmware holds the grid search only");

class FirmwareSession {
 public:
  // `table` must outlive the session; `stack_views` holds at least the
  // table's depth count to use its focus stack (else it goes without one).
  FirmwareSession(const TableView& table, std::span<ImageView> stack_views) noexcept
      : table_(table), session_(table, nullptr, detector_of(table)) {
    if (uses_table_focus_stack(kFirmwareProfile) && table.has_model_images() && table.depth_count() <= stack_views.size()) {
      for (std::uint16_t d = 0; d < table.depth_count(); ++d) stack_views[d] = table.model_image(d);
      stack_ = FocusStack{stack_views.first(table.depth_count()), table.model_ref_x(), table.model_ref_y(), 2};
      has_stack_ = true;
    }
  }
  // The CAPS mode bits (app::mode_bits of the profile as it runs here).
  std::uint32_t mode() const noexcept { return app::mode_bits(kFirmwareProfile, false, has_stack_); }
  [[nodiscard]] bool start(const Pose& initial) noexcept {
    started_ = session_.start(app::session_options(kFirmwareProfile), initial) == Status::kOk;
    if (started_) session_.use_focus_stack(has_stack_ ? &stack_ : nullptr);
    return started_;
  }
  bool started() const noexcept { return started_; }
  // `fine`: the table's tracker scratch (tracker_feature_capacity,
  // voter_counter_count, tracker_mask_bytes).
  [[nodiscard]] Status step(const ImageView& image, TrackerScratch fine, SessionResult& out) noexcept {
    if (!started_) return Status::kInvalidArgument;
    return session_.step(image, {fine, {}, {}}, out);
  }

 private:
  const TableView& table_;
  TrackingSession session_;
  FocusStack stack_;
  bool has_stack_ = false, started_ = false;
};

}  // namespace gabarit::mcu
