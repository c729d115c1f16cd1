#include "gabarit/particle_filter.hpp"

#include "gabarit/assert.hpp"
#include "gabarit/deterministic_math.hpp"

namespace gabarit {
namespace {

float clamp01(float v) noexcept { return v < 0.0f ? 0.0f : v > 1.0f ? 1.0f : v; }

// e^-x for x >= 0 from + and * only: (e^(-x/16))^16, the inner one by its
// Taylor series (|x/16| <= 1.25 below the cut-off; relative error < 1e-4).
float exp_neg(float x) noexcept {
  if (!(x < 20.0f)) return 0.0f;
  if (x <= 0.0f) return 1.0f;
  const float y = x * (1.0f / 16.0f);
  float e = 1.0f - y * (1.0f - y * (0.5f - y * (1.0f / 6 - y * (1.0f / 24 - y * (1.0f / 120 - y * (1.0f / 720))))));
  for (int i = 0; i < 4; ++i) e = e * e;
  return e;
}

// s^k for k >= 1 by squaring.
float power(float s, std::uint32_t k) noexcept {
  float result = 1.0f, base = s;
  while (k != 0) {
    if ((k & 1u) != 0) result *= base;
    base *= base;
    k >>= 1;
  }
  return result;
}

std::uint16_t jitter_depth(std::uint16_t depth, std::uint16_t depth_count, float change, ParticleRng& rng) noexcept {
  if (depth_count <= 1 || change <= 0.0f) return depth;
  const float u = rng.uniform();
  if (u >= change) return depth;
  const bool up = u < change * 0.5f;
  if (up) return depth + 1 < depth_count ? static_cast<std::uint16_t>(depth + 1) : static_cast<std::uint16_t>(depth - 1);
  return depth > 0 ? static_cast<std::uint16_t>(depth - 1) : static_cast<std::uint16_t>(depth + 1);
}

bool finite_pose(const Pose& p) noexcept { return pose_in_range(p); }

}  // namespace

bool valid(const ParticleFilterOptions& o) noexcept {
  const auto positive = [](float v) { return is_finite(v) && v > 0.0f && v < 1.0e6f; };
  const auto unit = [](float v) { return is_finite(v) && v >= 0.0f && v <= 1.0f; };
  return positive(o.sigma_px) && positive(o.sigma_deg) && unit(o.depth_change) && o.sharpness >= 1 && o.sharpness <= 64 &&
         positive(o.mode_radius_px) && positive(o.mode_radius_deg) && o.max_modes >= 1 && o.max_modes <= kMaxParticleModes &&
         o.disambiguate_modes >= 1 && o.disambiguate_modes <= kMaxParticleModes && unit(o.narrow_min) &&
         is_finite(o.kinematic_gain) && o.kinematic_gain >= 0.0f && o.kinematic_gain < 1.0e6f && positive(o.kinematic_px) &&
         positive(o.kinematic_deg) && unit(o.reinit_fraction) && positive(o.reinit_px) && positive(o.reinit_deg) &&
         positive(o.mode_filter_px) && is_finite(o.mode_filter_growth_px) && o.mode_filter_growth_px >= 0.0f &&
         o.mode_filter_growth_px < 1.0e6f && unit(o.high_ratio) && unit(o.lost_ratio) && o.lost_ratio <= o.high_ratio &&
         is_finite(o.lost_spread_growth) && o.lost_spread_growth >= 1.0f && o.lost_spread_growth < 100.0f &&
         is_finite(o.lost_spread_max) && o.lost_spread_max >= 1.0f && o.lost_spread_max < 1000.0f &&
         unit(o.proposal_fraction) && unit(o.proposal_floor) && unit(o.mode_seed_ratio) &&
         static_cast<std::uint8_t>(o.mode_clustering) <= static_cast<std::uint8_t>(ModeClustering::kRunningMean);
}

ParticleFilterOptions plain_condensation() noexcept {
  ParticleFilterOptions o;
  o.constant_velocity = false;
  o.modes = false;
  o.disambiguate = false;
  o.narrow_spread = false;
  o.kinematic_weighting = false;
  o.partial_reinit = false;
  o.mode_filter = false;
  o.lost_spread_growth = 1.0f;
  o.proposal_fraction = 0.0f;
  return o;
}

void DefaultPropagation::propagate(std::span<const Particle> cloud, std::span<Particle> next, const ParticleContext& context,
                                   ParticleRng& rng) noexcept {
  const ParticleFilterOptions& o = *context.options;
  const auto n = static_cast<std::uint32_t>(cloud.size());
  GABARIT_ASSERT(next.size() >= n && n > 0);
  auto reinit = static_cast<std::uint32_t>(context.reinit_fraction * static_cast<float>(n) + 0.5f);
  if (reinit > n) reinit = n;
  const std::uint32_t picked = n - reinit;
  float total = 0.0f;
  for (const Particle& p : cloud) total += p.weight;
  const bool uniform = !(total > 0.0f) || !is_finite(total);
  const float sx = o.sigma_px * context.spread, st = o.sigma_deg * context.spread;
  const float vx = o.constant_velocity ? context.vx : 0.0f, vy = o.constant_velocity ? context.vy : 0.0f;
  const float vt = o.constant_velocity ? context.vtheta : 0.0f;
  // Systematic resampling: one uniform offset, `picked` evenly spaced
  // pointers into the cumulative weights.
  const float step = picked > 0 ? (uniform ? static_cast<float>(n) : total) / static_cast<float>(picked) : 0.0f;
  float pointer = rng.uniform() * step;
  float cumulative = uniform ? 1.0f : cloud[0].weight;
  std::uint32_t j = 0;
  for (std::uint32_t i = 0; i < picked; ++i) {
    while (cumulative <= pointer && j + 1 < n) {
      ++j;
      cumulative += uniform ? 1.0f : cloud[j].weight;
    }
    const Pose& from = cloud[j].pose;
    Particle& p = next[i];
    p.pose.x = from.x + vx + sx * rng.normal();
    p.pose.y = from.y + vy + sx * rng.normal();
    p.pose.theta_deg = from.theta_deg + vt + st * rng.normal();
    p.pose.depth = jitter_depth(from.depth, context.depth_count, o.depth_change, rng);
    p.weight = 1.0f / static_cast<float>(n);
    pointer += step;
  }
  const Pose& c = context.reinit_centre;
  for (std::uint32_t i = picked; i < n; ++i) {
    Particle& p = next[i];
    p.pose.x = c.x + o.reinit_px * rng.normal();
    p.pose.y = c.y + o.reinit_px * rng.normal();
    p.pose.theta_deg = c.theta_deg + o.reinit_deg * rng.normal();
    p.pose.depth = jitter_depth(c.depth, context.depth_count, o.depth_change, rng);
    p.weight = 1.0f / static_cast<float>(n);
  }
}

void KinematicCompensation::compensate(std::span<Particle> particles, const ParticleContext& context) noexcept {
  const ParticleFilterOptions& o = *context.options;
  if (!o.kinematic_weighting || context.lost) return;
  const float gain = o.kinematic_gain * context.confidence;
  if (!(gain > 0.0f)) return;
  const float ix = 1.0f / o.kinematic_px, it = 1.0f / o.kinematic_deg;
  for (Particle& p : particles) {
    const float dx = (p.pose.x - context.predicted.x) * ix, dy = (p.pose.y - context.predicted.y) * ix;
    const float dt = (p.pose.theta_deg - context.predicted.theta_deg) * it;
    p.weight *= 1.0f + gain * exp_neg(0.5f * (dx * dx + dy * dy + dt * dt));
  }
}

void sort_by_weight(std::span<const Particle> particles, std::span<std::uint32_t> order) noexcept {
  const auto n = static_cast<std::uint32_t>(particles.size());
  GABARIT_ASSERT(order.size() >= 2 * std::size_t{n});
  std::uint32_t* a = order.data();
  std::uint32_t* b = order.data() + n;
  for (std::uint32_t i = 0; i < n; ++i) a[i] = i;
  // Descending weight = ascending complement of the (non-negative) float's bits.
  const auto key = [&](std::uint32_t i) {
    float w = particles[i].weight;
    if (!(w > 0.0f)) w = 0.0f;  // NaN and -0 sort as 0
    std::uint32_t bits = 0;
    __builtin_memcpy(&bits, &w, 4);
    return ~bits;
  };
  for (std::uint32_t shift = 0; shift < 32; shift += 8) {
    std::uint32_t count[257] = {};
    for (std::uint32_t i = 0; i < n; ++i) ++count[((key(a[i]) >> shift) & 0xFFu) + 1];
    for (std::uint32_t d = 1; d < 257; ++d) count[d] += count[d - 1];
    for (std::uint32_t i = 0; i < n; ++i) b[count[(key(a[i]) >> shift) & 0xFFu]++] = a[i];
    std::uint32_t* t = a;
    a = b;
    b = t;
  }
  // Four passes: the result is back in order[0, n).
}

std::uint32_t ModeAnalysis::cluster(std::span<const Particle> particles, std::span<std::uint32_t> order,
                                    const ParticleContext& context, std::span<ParticleMode> modes) noexcept {
  const ParticleFilterOptions& o = *context.options;
  const auto n = static_cast<std::uint32_t>(particles.size());
  if (n == 0 || modes.empty()) return 0;
  float total = 0.0f;
  for (const Particle& p : particles) total += p.weight;
  const float inv_total = total > 0.0f ? 1.0f / total : 0.0f;

  // A mode's sums; theta relative to its seed's, so that the mean of angles
  // near the seed does not depend on where the angle range is cut.
  struct Sum {
    Pose seed;
    float w = 0, x = 0, y = 0, t = 0;
    float mean_x = 0, mean_y = 0, mean_t = 0;  // kRunningMean: where the mode is now
    std::uint32_t count = 0;
    void add(const Particle& p) noexcept {
      w += p.weight, x += p.weight * p.pose.x, y += p.weight * p.pose.y;
      t += p.weight * (p.pose.theta_deg - seed.theta_deg);
      ++count;
    }
  };
  Sum sums[kMaxParticleModes];
  std::uint32_t mode_count = 0;
  if (!o.modes) {
    // The weighted mean of the whole cloud, at the heaviest particle's depth.
    std::uint32_t heaviest = 0;
    for (std::uint32_t i = 1; i < n; ++i)
      if (particles[i].weight > particles[heaviest].weight) heaviest = i;
    sums[0].seed = particles[heaviest].pose;
    for (const Particle& p : particles) sums[0].add(p);
    mode_count = 1;
  } else {
    sort_by_weight(particles, order);
    const std::uint32_t max_modes = o.max_modes < modes.size() ? o.max_modes : static_cast<std::uint32_t>(modes.size());
    const float irx = 1.0f / o.mode_radius_px, irt = 1.0f / o.mode_radius_deg;
    const bool running = o.mode_clustering == ModeClustering::kRunningMean;
    const float seed_weight = o.mode_seed_ratio * particles[order[0]].weight;
    for (std::uint32_t k = 0; k < n; ++k) {
      const Particle& p = particles[order[k]];
      std::uint32_t m = 0;
      for (; m < mode_count; ++m) {
        const Sum& s = sums[m];
        if (s.seed.depth != p.pose.depth) continue;
        const float cx = running ? s.mean_x : s.seed.x, cy = running ? s.mean_y : s.seed.y;
        const float ct = running ? s.mean_t : s.seed.theta_deg;
        const float dx = (p.pose.x - cx) * irx, dy = (p.pose.y - cy) * irx, dt = (p.pose.theta_deg - ct) * irt;
        if (dx * dx + dy * dy + dt * dt <= 1.0f) break;
      }
      if (m == mode_count) {
        // Beyond the modes kept, or (kRunningMean) too light to start one: counted in no mode.
        if (mode_count == max_modes || (running && p.weight < seed_weight)) continue;
        Sum& fresh = sums[mode_count++];
        fresh.seed = p.pose;
        fresh.mean_x = p.pose.x, fresh.mean_y = p.pose.y, fresh.mean_t = p.pose.theta_deg;
      }
      Sum& s = sums[m];
      s.add(p);
      if (running && s.w > 0.0f) {
        const float iw = 1.0f / s.w;
        s.mean_x = s.x * iw, s.mean_y = s.y * iw, s.mean_t = s.seed.theta_deg + s.t * iw;
      }
    }
  }
  for (std::uint32_t m = 0; m < mode_count; ++m) {
    const Sum& s = sums[m];
    ParticleMode& mode = modes[m];
    mode.particles = s.count;
    mode.weight = s.w * inv_total;
    mode.score = -1.0f;
    if (s.w > 0.0f) {
      const float iw = 1.0f / s.w;
      mode.pose = {s.x * iw, s.y * iw, s.seed.theta_deg + s.t * iw, s.seed.depth};
    } else {
      mode.pose = s.seed;
    }
  }
  // Heaviest mode first (insertion sort over at most kMaxParticleModes, stable).
  for (std::uint32_t i = 1; i < mode_count; ++i) {
    const ParticleMode m = modes[i];
    std::uint32_t j = i;
    for (; j > 0 && modes[j - 1].weight < m.weight; --j) modes[j] = modes[j - 1];
    modes[j] = m;
  }
  return mode_count;
}

void ModeAnalysis::choose(std::span<const ParticleMode> modes, std::uint32_t scored, const ParticleContext& context,
                          ParticleAnalysisResult& out) noexcept {
  const ParticleFilterOptions& o = *context.options;
  const auto mode_count = static_cast<std::uint32_t>(modes.size());
  out = {};
  out.modes = mode_count;
  if (mode_count == 0) return;
  if (scored > mode_count) scored = mode_count;
  // The first `scored` modes (the heaviest) carry the finer measure's score
  // and rank by it; the rest rank after them, by weight.
  const auto better = [&](std::uint32_t a, std::uint32_t b) {  // a ranks before b
    if (a < scored && b < scored && modes[a].score != modes[b].score) return modes[a].score > modes[b].score;
    if ((a < scored) != (b < scored)) return a < scored;
    return a < b;  // by weight
  };
  std::uint32_t best = 0;
  for (std::uint32_t m = 1; m < mode_count; ++m)
    if (better(m, best)) best = m;
  out.best = out.chosen = best;
  if (!o.mode_filter || context.lost) return;
  // Mode filtering: the best mode within the adaptive distance of the prediction.
  const auto magnitude = [](float v) { return v < 0.0f ? -v : v; };
  float reach = o.mode_filter_px + magnitude(context.vx) + magnitude(context.vy);  // the speed's L1 norm bounds |v|
  reach += o.mode_filter_growth_px * static_cast<float>(context.unconfident_frames);
  const float reach2 = reach * reach;
  std::uint32_t near = mode_count;
  for (std::uint32_t m = 0; m < mode_count; ++m) {
    const float dx = modes[m].pose.x - context.predicted.x, dy = modes[m].pose.y - context.predicted.y;
    if (dx * dx + dy * dy > reach2) continue;
    if (near == mode_count || better(m, near)) near = m;
  }
  if (near != mode_count) {
    out.chosen = near;
  } else if (context.held_frames < o.mode_filter_patience) {
    out.held = true;
  }
}

Status ParticleFilterCore::start(const ParticleFilterOptions& options, const Pose& initial, std::uint16_t depth_count,
                             std::uint64_t seed, ParticleScratch scratch) noexcept {
  started_ = false;
  if (!valid(options) || !finite_pose(initial) || depth_count == 0 ||
      initial.depth >= depth_count)
    return Status::kInvalidArgument;
  const std::size_t n = scratch.cloud.size();
  if (n == 0 || n > kMaxParticles) return Status::kInvalidArgument;
  const auto n32 = static_cast<std::uint32_t>(n);
  if (scratch.next.size() < particle_scratch_particles(n32) || scratch.order.size() < particle_scratch_order(n32))
    return Status::kBufferTooSmall;
  options_ = options;
  cloud_ = scratch.cloud;
  next_ = scratch.next.first(n);
  order_ = scratch.order;
  rng_ = ParticleRng(seed);
  context_ = {};
  context_.estimate = context_.predicted = context_.reinit_centre = initial;
  context_.depth_count = depth_count;
  context_.options = &options_;
  // No confidence yet: the velocity is unknown, so the first frames diffuse
  // at full spread and are not over-weighted towards a standing prediction.
  context_.confidence = 0.0f;
  // The first cloud: spread around the initial pose as partial
  // re-initialisation would draw.
  for (Particle& p : cloud_) {
    p.pose.x = initial.x + options_.sigma_px * rng_.normal();
    p.pose.y = initial.y + options_.sigma_px * rng_.normal();
    p.pose.theta_deg = initial.theta_deg + options_.sigma_deg * rng_.normal();
    p.pose.depth = initial.depth;
    p.weight = 1.0f / static_cast<float>(n);
  }
  scattered_ = true;  // the first step measures this cloud as it is
  mode_count_ = 0;
  reference_ = 0.0f;
  unconfident_ = held_ = 0;
  last_confident_ = initial;
  external_fraction_ = 0.0f;
  started_ = true;
  return Status::kOk;
}

void ParticleFilterCore::reinitialise_around(const Pose& pose, float fraction) noexcept {
  if (!finite_pose(pose) || !(fraction > 0.0f)) return;
  external_reinit_ = pose;
  if (external_reinit_.depth >= context_.depth_count) external_reinit_.depth = static_cast<std::uint16_t>(context_.depth_count - 1);
  external_fraction_ = fraction > 1.0f ? 1.0f : fraction;
}

void ParticleFilterCore::draw_uniform(Particle& p, const float* r) noexcept {
  p.pose.x = r[0] + (r[1] - r[0]) * rng_.uniform();
  p.pose.y = r[2] + (r[3] - r[2]) * rng_.uniform();
  p.pose.theta_deg = r[4] + (r[5] - r[4]) * rng_.uniform();
  p.pose.depth = static_cast<std::uint16_t>(rng_.uniform() * static_cast<float>(context_.depth_count));
  if (p.pose.depth >= context_.depth_count) p.pose.depth = static_cast<std::uint16_t>(context_.depth_count - 1);
  p.weight = 1.0f / static_cast<float>(cloud_.size());
}

Status ParticleFilterCore::scatter(float x0, float x1, float y0, float y1, float theta0_deg, float theta1_deg,
                               float fraction) noexcept {
  if (!started_) return Status::kInvalidArgument;
  const auto ordered = [](float a, float b) { return within_limit(a, kPoseLimit) && within_limit(b, kPoseLimit) && a <= b; };
  if (!ordered(x0, x1) || !ordered(y0, y1) || !ordered(theta0_deg, theta1_deg)) return Status::kInvalidArgument;
  if (!(fraction > 0.0f && fraction <= 1.0f)) return Status::kInvalidArgument;
  const float region[6] = {x0, x1, y0, y1, theta0_deg, theta1_deg};
  if (fraction < 1.0f) {
    for (int i = 0; i < 6; ++i) scatter_[i] = region[i];
    scatter_fraction_ = fraction;
    return Status::kOk;
  }
  for (Particle& p : cloud_) draw_uniform(p, region);
  scatter_fraction_ = 0.0f;
  scattered_ = true;
  context_.lost = true;
  return Status::kOk;
}

Status ParticleFilterCore::begin_step(const ImageView& image, ParticleEstimate& out) noexcept {
  if (!started_ || !image.valid()) return Status::kInvalidArgument;
  out = {};
  const ParticleFilterOptions& o = options_;
  ParticleContext& c = context_;
  // The prediction and this frame's spread.
  c.predicted = c.estimate;
  if (o.constant_velocity && !c.lost) {
    c.predicted.x += c.vx, c.predicted.y += c.vy, c.predicted.theta_deg += c.vtheta;
  }
  if (c.lost) {
    c.spread *= o.lost_spread_growth;
    if (c.spread > o.lost_spread_max) c.spread = o.lost_spread_max;
  } else {
    c.spread = o.narrow_spread ? 1.0f - (1.0f - o.narrow_min) * c.confidence : 1.0f;
  }
  c.reinit_fraction = 0.0f;
  if (external_fraction_ > 0.0f) {
    c.reinit_centre = external_reinit_;
    c.reinit_fraction = external_fraction_;
    external_fraction_ = 0.0f;
  } else if (o.partial_reinit && unconfident_ > 0) {
    c.reinit_centre = last_confident_;
    c.reinit_fraction = o.reinit_fraction;
  }
  c.unconfident_frames = unconfident_;
  c.held_frames = held_;
  return Status::kOk;
}

void ParticleFilterCore::after_propagation(ParticleEstimate& out) noexcept {
  if (!scattered_) {
    const std::span<Particle> t = cloud_;
    cloud_ = next_;
    next_ = t;
    out.reinitialised = context_.reinit_fraction > 0.0f;
    if (scatter_fraction_ > 0.0f) {
      // A partial scatter: every k-th particle re-drawn over the region
      // (spread over the cloud, which propagation leaves in picking order).
      const auto n = static_cast<std::uint32_t>(cloud_.size());
      auto count = static_cast<std::uint32_t>(scatter_fraction_ * static_cast<float>(n) + 0.5f);
      if (count > n) count = n;
      for (std::uint32_t k = 0; k < count; ++k) draw_uniform(cloud_[static_cast<std::size_t>(k) * n / count], scatter_);
      out.reinitialised = true;
    }
  }
  scatter_fraction_ = 0.0f;
  scattered_ = false;
}

ImageWindow ParticleFilterCore::loader_window(const ImageView& image, std::uint32_t reach) const noexcept {
  float x_lo = cloud_[0].pose.x, x_hi = x_lo, y_lo = cloud_[0].pose.y, y_hi = y_lo;
  for (const Particle& p : cloud_) {
    x_lo = p.pose.x < x_lo ? p.pose.x : x_lo, x_hi = p.pose.x > x_hi ? p.pose.x : x_hi;
    y_lo = p.pose.y < y_lo ? p.pose.y : y_lo, y_hi = p.pose.y > y_hi ? p.pose.y : y_hi;
  }
  const float r = static_cast<float>(reach) + 1.0f;
  const auto clip = [](float v, float hi) { return v < 0.0f ? 0.0f : v > hi ? hi : v; };
  const float w = static_cast<float>(image.width), h = static_cast<float>(image.height);
  const float wx0 = clip(x_lo - r, w), wx1 = clip(x_hi + r + 1.0f, w), wy0 = clip(y_lo - r, h), wy1 = clip(y_hi + r + 1.0f, h);
  ImageWindow window;
  window.x0 = static_cast<std::int32_t>(wx0);
  window.y0 = static_cast<std::int32_t>(wy0);
  const auto extent = [](float a, float b) {
    const float d = b - a;
    return static_cast<std::uint16_t>(d >= 65535.0f ? 65535.0f : d < 0.0f ? 0.0f : d);
  };
  window.width = extent(static_cast<float>(window.x0), wx1);
  window.height = extent(static_cast<float>(window.y0), wy1);
  return window;
}

// (2 pi)^(3/2): a three-dimensional Gaussian's normalisation.
constexpr float kTwoPiToThreeHalves = 15.749609945f;

std::size_t ParticleFilterCore::proposal_index(std::uint32_t k) const noexcept {
  // Midway between the particles a partial scatter re-draws (k n / count),
  // so that the two rarely take the same particle.
  return ((2 * std::size_t{k} + 1) * cloud_.size()) / (2 * std::size_t{proposed_});
}

void ParticleFilterCore::draw_proposals(ParticleEstimate& out) noexcept {
  proposed_ = 0;
  ParticleProposals& q = proposals_;
  const auto positive = [](float v) { return is_finite(v) && v > 0.0f && v < 1.0e6f; };
  // A proposer's output is checked like any caller's input: nothing is drawn
  // from a malformed one.
  if (q.count == 0 || q.count > kMaxParticleProposals || !positive(q.sigma_px) || !positive(q.sigma_deg) ||
      !(is_finite(q.region_volume) && q.region_volume > 0.0f))
    return;
  for (std::uint32_t k = 0; k < q.count; ++k)
    if (!finite_pose(q.poses[k]) || q.poses[k].depth >= context_.depth_count) return;
  const auto n = static_cast<std::uint32_t>(cloud_.size());
  auto count = static_cast<std::uint32_t>(options_.proposal_fraction * static_cast<float>(n) + 0.5f);
  if (count > n) count = n;
  proposed_ = count;
  for (std::uint32_t k = 0; k < count; ++k) {
    // Round robin: each place draws an equal share (the proposal density is
    // their equal mixture).
    const Pose& c = q.poses[k % q.count];
    Particle& p = cloud_[proposal_index(k)];
    p.pose.x = c.x + q.sigma_px * rng_.normal();
    p.pose.y = c.y + q.sigma_px * rng_.normal();
    p.pose.theta_deg = c.theta_deg + q.sigma_deg * rng_.normal();
    p.pose.depth = c.depth;
    p.weight = 1.0f / static_cast<float>(n);
  }
  out.proposed = count;
}

// The motion model's density at `pose` (per px^2 deg, per depth), as the
// options describe it: the last frame's modes (the estimate before there are
// any), each moved by the velocity and widened by the diffusion plus half its
// radius, mixed with the proposer's uniform in the share max(floor, 1 - c).
float ParticleFilterCore::prior_density(const Pose& pose) const noexcept {
  const ParticleFilterOptions& o = options_;
  const ParticleContext& c = context_;
  float share = c.lost ? 1.0f : 1.0f - c.confidence;
  if (share < o.proposal_floor) share = o.proposal_floor;
  const float uniform = share / proposals_.region_volume;
  if (!(share < 1.0f)) return uniform;
  const float sx = o.sigma_px * c.spread, st = o.sigma_deg * c.spread;
  // The widths add (rather than in quadrature, which needs a square root):
  // a little wider than the cloud, so a proposal near a mode is not undercounted.
  const float sd_px = sx + 0.5f * o.mode_radius_px, sd_deg = st + 0.5f * o.mode_radius_deg;
  const float var_px = sd_px * sd_px, var_deg = sd_deg * sd_deg;
  const float norm = 1.0f / (kTwoPiToThreeHalves * var_px * sd_deg);
  const bool moving = o.constant_velocity;
  const auto depth_factor = [&](std::uint16_t mode_depth) {
    if (c.depth_count <= 1) return 1.0f;
    const int d = static_cast<int>(pose.depth) - static_cast<int>(mode_depth);
    return d == 0 ? 1.0f - o.depth_change : (d == 1 || d == -1) ? 0.5f * o.depth_change : 0.0f;
  };
  const auto gaussian = [&](const Pose& m) {
    const float dx = pose.x - (m.x + (moving ? c.vx : 0.0f)), dy = pose.y - (m.y + (moving ? c.vy : 0.0f));
    const float dt = pose.theta_deg - (m.theta_deg + (moving ? c.vtheta : 0.0f));
    return exp_neg(0.5f * ((dx * dx + dy * dy) / var_px + dt * dt / var_deg)) * depth_factor(m.depth);
  };
  float sum = 0.0f, total = 0.0f;
  for (std::uint32_t m = 0; m < mode_count_; ++m) {
    sum += modes_[m].weight * gaussian(modes_[m].pose);
    total += modes_[m].weight;
  }
  const float motion = total > 0.0f ? sum / total : gaussian(c.estimate);
  return (1.0f - share) * norm * motion + uniform;
}

// The proposals' density at `pose`: their equal mixture.
float ParticleFilterCore::proposal_density(const Pose& pose) const noexcept {
  const ParticleProposals& q = proposals_;
  const float var_px = q.sigma_px * q.sigma_px, var_deg = q.sigma_deg * q.sigma_deg;
  float sum = 0.0f;
  for (std::uint32_t k = 0; k < q.count; ++k) {
    const Pose& c = q.poses[k];
    if (c.depth != pose.depth) continue;
    const float dx = pose.x - c.x, dy = pose.y - c.y, dt = pose.theta_deg - c.theta_deg;
    sum += exp_neg(0.5f * ((dx * dx + dy * dy) / var_px + dt * dt / var_deg));
  }
  return sum / (kTwoPiToThreeHalves * var_px * q.sigma_deg * static_cast<float>(q.count));
}

void ParticleFilterCore::correct_proposals() noexcept {
  if (proposed_ == 0 || !options_.proposal_correction) return;
  for (std::uint32_t k = 0; k < proposed_; ++k) {
    Particle& p = cloud_[proposal_index(k)];
    // A particle's own place gives a density > 0: the normal deviates are
    // bounded (a sum of four uniforms), so exp_neg's cut-off is never reached.
    const float g = proposal_density(p.pose);
    p.weight = g > 0.0f ? p.weight * (prior_density(p.pose) / g) : 0.0f;
  }
}

void ParticleFilterCore::sharpen() noexcept {
  for (Particle& p : cloud_) {
    const float s = p.weight > 0.0f ? (p.weight < 1.0f ? p.weight : 1.0f) : 0.0f;
    p.weight = power(s, options_.sharpness);
  }
}

void ParticleFilterCore::finish_step(const ParticleAnalysisResult& analysis, float score, ParticleEstimate& out) noexcept {
  const ParticleFilterOptions& o = options_;
  ParticleContext& c = context_;
  const ParticleMode& chosen = modes_[analysis.chosen];
  if (reference_ <= 0.0f && score > 0.0f) reference_ = score;
  const float ratio = reference_ > 0.0f ? score / reference_ : 0.0f;
  out.score = score;
  out.mode_particles = chosen.particles;
  out.mode_weight = chosen.weight;
  out.held = analysis.held;
  out.state = ratio >= o.high_ratio ? TrackState::kTracking : ratio >= o.lost_ratio ? TrackState::kUncertain : TrackState::kLost;
  if (analysis.held && out.state != TrackState::kLost) out.state = TrackState::kUncertain;
  const Pose previous = c.estimate;
  if (out.state == TrackState::kLost) {
    // Keep the last estimate; the cloud explores (growing spread, partial
    // re-initialisation around the last confident pose).
    c.lost = true;
    c.vx = c.vy = c.vtheta = 0.0f;
    c.confidence = 0.0f;
  } else {
    const Pose next = analysis.held ? c.predicted : chosen.pose;
    if (!c.lost) {
      c.vx = 0.5f * c.vx + 0.5f * (next.x - previous.x);
      c.vy = 0.5f * c.vy + 0.5f * (next.y - previous.y);
      c.vtheta = 0.5f * c.vtheta + 0.5f * (next.theta_deg - previous.theta_deg);
    }
    c.estimate = next;
    c.lost = false;
    c.confidence = analysis.held ? 0.0f : clamp01(ratio / o.high_ratio);
  }
  held_ = analysis.held ? held_ + 1 : 0;
  if (out.state == TrackState::kTracking) {
    unconfident_ = 0;
    last_confident_ = c.estimate;
    reference_ = 0.95f * reference_ + 0.05f * score;  // follows slow changes of contrast
  } else {
    ++unconfident_;
  }
  out.pose = c.estimate;
  out.confidence = c.confidence;
}

}  // namespace gabarit
