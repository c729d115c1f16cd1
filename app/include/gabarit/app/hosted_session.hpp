// The one place a hosted program builds a tracking session: from a table and
// a session profile (session_profile.hpp), with its scratch, focus stack,
// and recovery stages (the grid, detection over the whole frame, a particle
// filter) allocated here; or, with the profile's particle tracker, the
// particle filter (particle_run.hpp) in the session's place, its results as
// SessionResults. gabarit track, the board application, the HIL's
// in-process device and the harness's reference all run this class; the
// Cortex-M firmware runs its static twin (platform/cortex-m/hil_dut.cpp),
// checked against it by tests/app/session_profile_test.cpp and the HIL.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "gabarit/app/image_io.hpp"
#include "gabarit/app/scratch.hpp"
#include "gabarit/app/session_profile.hpp"
#include "gabarit/detection_recovery.hpp"
#include "gabarit/model_finder.hpp"
#include "gabarit/particle_recovery.hpp"
#include "gabarit/table_view.hpp"
#include "gabarit/tracking_session.hpp"

namespace gabarit::app {

class ParticleTracker;

// What a host program may give beyond the profile: they are files or
// per-program choices, not part of what a device runs.
struct SessionExtras {
  VoterChoice voter = VoterChoice::kAuto;  // same results, other speed
  std::optional<Detector> detector;        // overrides the table's (gabarit track --binary)
  const TableView* coarse = nullptr;       // the recovery search's table (must outlive the session)
  std::vector<GrayImage> focus_stack;      // images, one per depth, instead of the table's
  FinderOptions finder;                    // detection: re-acquisition and finding the start
  // A bench's experiment only: these kernel options instead of the profile's
  // (the profile still chooses the recovery stage, sharing and focus stack).
  std::optional<SessionOptions> research_options;
};

class HostedSession {
 public:
  // Throws app::Error for a profile that does not validate, a focus stack
  // that does not match the table, or detection options that are not valid.
  HostedSession(const TableView& table, const SessionProfile& profile, SessionExtras extras = {});
  HostedSession(const HostedSession&) = delete;
  HostedSession& operator=(const HostedSession&) = delete;
  ~HostedSession();

  // Starts (or restarts) at `initial`; false if the session rejects it
  // (a pose outside pose_in_range or a depth the table does not have).
  [[nodiscard]] bool start(const Pose& initial);
  // No starting pose: searches `frame` for the model (the finder's best
  // detection) and starts there if found; false if nothing was found.
  // Throws app::Error on a kernel error.
  bool start_by_detection(const ImageView& frame);
  bool started() const { return session_.has_value() || particle_started_; }
  // Tracks one frame of a started session. The particle tracker is built at
  // its first frame, for that frame's size: a later frame of another size
  // is kInvalidArgument. Throws app::Error when a recovery stage or the
  // particle tracker cannot be built for the frame (as the constructors of
  // ParticleTracker and the finder's buffers do).
  [[nodiscard]] Status step(const ImageView& frame, SessionResult& out);

  const SessionProfile& profile() const { return profile_; }
  const SessionOptions& options() const { return options_; }
  // The CAPS mode bits of what runs (session_profile.hpp, mode_bits).
  std::uint32_t mode() const;

 private:
  void fit_frame(std::uint32_t width, std::uint32_t height);
  Status particle_step(const ImageView& frame, SessionResult& out);

  const TableView& table_;
  SessionProfile profile_;
  SessionExtras extras_;
  SessionOptions options_;
  Detector detector_;
  SessionBuffers buffers_;
  TableFocusStack table_stack_;
  std::vector<ImageView> stack_views_;
  FocusStack stack_;
  const FocusStack* stack_in_use_ = nullptr;
  ModelFinder finder_;
  std::optional<FinderBuffers> finder_buffers_;
  std::optional<DetectionRecovery> detection_;
  std::unique_ptr<IntensityScan> scan_;  // with detection and a focus stack (intensity_scan.hpp)
  std::unique_ptr<ParticleTracker> particles_;
  std::optional<ParticleRecovery> particle_recovery_;
  bool particle_started_ = false;  // the particle tracker: started, built at the first frame
  std::uint32_t particle_width_ = 0, particle_height_ = 0;
  Pose start_pose_;
  std::optional<TrackingSession> session_;
};

}  // namespace gabarit::app
