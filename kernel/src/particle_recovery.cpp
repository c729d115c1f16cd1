#include "gabarit/particle_recovery.hpp"

#include "gabarit/deterministic_math.hpp"
#include "gabarit/finder_search.hpp"
#include "gabarit/voter.hpp"

namespace gabarit {

bool valid(const ParticleRecoveryOptions& o) noexcept {
  const auto in = [](float v, float hi) { return is_finite(v) && v >= 0.0f && v <= hi; };
  return in(o.reach_px, 1.0e5f) && o.reach_px > 0.0f && in(o.growth_px, 1.0e5f) && in(o.turn_deg, 180.0f) &&
         in(o.growth_deg, 180.0f) && o.rescatter > 0.0f && o.rescatter <= 1.0f && o.candidates >= 1 &&
         o.candidates <= kMaxParticleModes;
}

Status ParticleRecovery::run(const ImageView& image, const LastSighting& last, TrackerScratch fine_scratch,
                             SearchResult& out) noexcept {
  out = SearchResult{};
  if (!valid(options_) || !image.valid() || !pose_in_range(last.pose)) return Status::kInvalidArgument;
  // The region: around the extrapolated pose, growing with the lost frames, clipped to the frame.
  const auto n_since = static_cast<float>(last.frames_since);
  const float cx = last.pose.x + last.motion.vx * n_since, cy = last.pose.y + last.motion.vy * n_since;
  const auto grown = static_cast<float>(frames_);
  const float reach = options_.reach_px + options_.growth_px * grown;
  float turn = options_.turn_deg + options_.growth_deg * grown;
  if (turn > 180.0f) turn = 180.0f;
  const auto clip = [](float v, float hi) { return v < 0.0f ? 0.0f : v > hi ? hi : v; };
  const float w = static_cast<float>(image.width), h = static_cast<float>(image.height);
  float x0 = clip(cx - reach, w), x1 = clip(cx + reach, w), y0 = clip(cy - reach, h), y1 = clip(cy + reach, h);
  if (!(x0 < x1)) x0 = 0.0f, x1 = w;  // extrapolated off the frame: all of it
  if (!(y0 < y1)) y0 = 0.0f, y1 = h;
  const float theta = last.pose.theta_deg + last.motion.vtheta * n_since;
  GABARIT_TRY(filter_.scatter(x0, x1, y0, y1, theta - turn, theta + turn, frames_ == 0 ? 1.0f : options_.rescatter));
  ++frames_;
  ParticleEstimate estimate;
  GABARIT_TRY(filter_.step(image, estimate));
  // The fine table's vote from each of the heaviest modes; the best again from its own estimate.
  const std::span<const ParticleMode> modes = filter_.modes();
  const std::uint32_t n = modes.size() < options_.candidates ? static_cast<std::uint32_t>(modes.size()) : options_.candidates;
  StepResult best;
  bool have = false;
  for (std::uint32_t m = 0; m < n; ++m) {
    StepResult r;
    GABARIT_TRY(track_step(fine_, detector_, image, modes[m].pose, fine_scratch, r));
    out.work += track_step_work(fine_, r);
    if (r.best.votes == 0) continue;
    if (!have || ranks_before(r.best, best.best)) best = r, have = true;
  }
  out.searched = true;
  if (!have) return Status::kOk;  // no candidate drew a vote: the vote stays empty (kLost)
  out.from = best.pose;
  GABARIT_TRY(track_step(fine_, detector_, image, out.from, fine_scratch, out.vote));
  out.work += track_step_work(fine_, out.vote);
  // A strong vote pulls half the next cloud to it.
  if (out.vote.best.votes > 0 && out.vote.state == TrackState::kTracking) filter_.reinitialise_around(out.vote.pose, 0.5f);
  return Status::kOk;
}

}  // namespace gabarit
