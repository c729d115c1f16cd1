#include "gabarit/intensity_scan.hpp"

#include "gabarit/deterministic_math.hpp"

namespace gabarit {

namespace {

bool positive_bound(float v) noexcept { return is_finite(v) && v > 0.0f && v <= 1000.0f; }

float larger_magnitude(const Axis& a) noexcept {
  const float lo = a.min < 0.0f ? -a.min : a.min, hi = a.max < 0.0f ? -a.max : a.max;
  return lo > hi ? lo : hi;
}

}  // namespace

bool valid(const IntensityScanOptions& o) noexcept {
  return positive_bound(o.step_px) && positive_bound(o.step_deg) && positive_bound(o.max_radius_px) &&
         positive_bound(o.max_turn_deg) && o.samples >= 16 && o.samples <= kMaxIntensityMeasureSamples &&
         o.screen_samples >= 16 && o.screen_samples <= kMaxIntensityMeasureSamples && o.kept >= 1 && o.kept <= kMaxScanKept;
}

void IntensityScan::reset(const TableView& table, const FocusStack& stack, const IntensityScanOptions& options) noexcept {
  ready_ = false;
  if (!valid(options) || !valid_focus_stack(stack)) return;
  options_ = options;
  screen_.reset(stack, options.screen_samples);
  measure_.reset(stack, options.samples);
  // A bound of 0 (an axis of one cell at 0) still lets the grid's centre be scored.
  per_frame_px_ = larger_magnitude(table.axis_x()) > larger_magnitude(table.axis_y()) ? larger_magnitude(table.axis_x())
                                                                                       : larger_magnitude(table.axis_y());
  per_frame_deg_ = larger_magnitude(table.axis_theta());
  ready_ = screen_.samples() > 0 && measure_.samples() > 0;
}

Status IntensityScan::run(const ImageView& frame, const LastSighting& last, IntensityScanResult& out) noexcept {
  out = {};
  if (!ready_ || !frame.valid() || !pose_in_range(last.pose)) return Status::kInvalidArgument;
  GABARIT_TRY(screen_.prepare(frame, last.pose));
  GABARIT_TRY(measure_.prepare(frame, last.pose));
  // The frames the target has had to move: those since the sighting, and this one.
  const float frames = static_cast<float>(last.frames_since > 1000u ? 1000u : last.frames_since) + 1.0f;
  float radius = per_frame_px_ * frames, turn = per_frame_deg_ * frames;
  if (radius > options_.max_radius_px) radius = options_.max_radius_px;
  if (turn > options_.max_turn_deg) turn = options_.max_turn_deg;
  const auto steps = [](float reach, float step) { return static_cast<std::int32_t>(reach / step); };
  const std::int32_t rings = steps(radius, options_.step_px), turns = steps(turn, options_.step_deg);
  // The screen's best `kept`, best first; of equal scores the earlier in
  // this fixed order first.
  struct Screened {
    Pose pose;
    float score;
  };
  Screened kept[kMaxScanKept];
  std::uint32_t held = 0;
  for (std::int32_t j = -turns; j <= turns; ++j) {
    const float theta = last.pose.theta_deg + static_cast<float>(j) * options_.step_deg;
    for (std::int32_t iy = -rings; iy <= rings; ++iy) {
      for (std::int32_t ix = -rings; ix <= rings; ++ix) {
        const Pose p{last.pose.x + static_cast<float>(ix) * options_.step_px, last.pose.y + static_cast<float>(iy) * options_.step_px,
                     theta, last.pose.depth};
        const float s = screen_.score(p);
        ++out.poses;
        if (!(s > 0.0f) || (held == options_.kept && !(s > kept[held - 1].score))) continue;
        std::uint32_t at = held < options_.kept ? held++ : held - 1;
        for (; at > 0 && s > kept[at - 1].score; --at) kept[at] = kept[at - 1];
        kept[at] = {p, s};
      }
    }
  }
  out.work = std::uint64_t{out.poses} * screen_.samples() + std::uint64_t{held} * measure_.samples();
  for (std::uint32_t k = 0; k < held; ++k) {
    // Strictly better: of equal scores the screen's earlier choice stays.
    const float s = measure_.score(kept[k].pose);
    if (s > out.score) {
      out.scored = true;
      out.best = kept[k].pose;
      out.score = s;
    }
  }
  return Status::kOk;
}

}  // namespace gabarit
