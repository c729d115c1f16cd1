#include "gabarit/verification.hpp"

// Eigen as in motion_filter.cpp: fixed-size floats, no heap, scalar code.
#include <Eigen/Cholesky>
#include <Eigen/Core>

namespace gabarit {

void Proposals::add(const Pose& p) noexcept {
  if (count >= kMaxProposals) return;
  for (std::uint32_t i = 0; i < count; ++i) {
    const Pose& q = poses[i];
    if (q.x == p.x && q.y == p.y && q.theta_deg == p.theta_deg && q.depth == p.depth) return;
  }
  poses[count++] = p;
}

float correlation_from_signed_square(float signed_r2) noexcept {
  const float s = signed_r2 < 0.0f ? -signed_r2 : signed_r2;
  if (!(s > 0.0f)) return 0.0f;
  float x = s < 1.0f ? 0.5f * (1.0f + s) : s;  // above the root: Newton then descends to it
  // At most 12 steps; a step that changes nothing has reached a fixed point,
  // which every later step would keep: stopping there gives the same bits.
  for (int i = 0; i < 12; ++i) {
    const float next = 0.5f * (x + s / x);
    if (next == x) break;
    x = next;
  }
  return signed_r2 < 0.0f ? -x : x;
}

namespace {

// The refinement's design, in units of the spacing: the centre, six points
// along the axes and twelve on the diagonals of each pair of axes (x, y, angle).
struct Offset {
  std::int8_t x, y, t;
};
constexpr Offset kDesign[19] = {{0, 0, 0},  {1, 0, 0},  {-1, 0, 0}, {0, 1, 0},   {0, -1, 0}, {0, 0, 1},  {0, 0, -1},
                                {1, 1, 0},  {1, -1, 0}, {-1, 1, 0}, {-1, -1, 0}, {1, 0, 1},  {1, 0, -1}, {-1, 0, 1},
                                {-1, 0, -1}, {0, 1, 1}, {0, 1, -1}, {0, -1, 1},  {0, -1, -1}};
constexpr int kSamples = 19;
constexpr int kRefineRounds = 3;

using Vector3 = Eigen::Matrix<float, 3, 1>;
using Matrix3 = Eigen::Matrix<float, 3, 3>;

Pose moved(const Pose& p, float dx, float dy, float dt) noexcept {
  Pose q = p;
  q.x += dx;
  q.y += dy;
  q.theta_deg += dt;
  return q;
}

// The design's samples in the plane of the angle kept (t = 0): the centre,
// four along x and y, four on the diagonals.
bool in_plane(int k) noexcept { return kDesign[k].t == 0; }

// The peak u* = -H^-1 g of a quadratic c + g.u + u'Hu/2 when H is negative
// definite, each coordinate clamped to one spacing; false otherwise.
bool newton_peak(const Matrix3& negative_h, const Vector3& g, int dims, Vector3& peak) noexcept {
  if (dims == 3) {
    const Eigen::LDLT<Matrix3> curvature(negative_h);
    if (curvature.info() != Eigen::Success || !(curvature.vectorD().minCoeff() > 0.0f)) return false;
    peak = curvature.solve(g);  // -H u = g
  } else {
    const Eigen::Matrix<float, 2, 2> h2 = negative_h.topLeftCorner<2, 2>();
    const Eigen::LDLT<Eigen::Matrix<float, 2, 2>> curvature(h2);
    if (curvature.info() != Eigen::Success || !(curvature.vectorD().minCoeff() > 0.0f)) return false;
    const Eigen::Matrix<float, 2, 1> uv = curvature.solve(g.head<2>());
    peak = Vector3(uv(0), uv(1), 0.0f);
  }
  for (int i = 0; i < 3; ++i) {
    if (!is_finite(peak(i))) return false;
    peak(i) = peak(i) > 1.0f ? 1.0f : (peak(i) < -1.0f ? -1.0f : peak(i));
  }
  return true;
}

// A quadratic c + g.u + u'Hu/2 fitted by least squares to the design's
// samples: all 19 (`with_angle`) or the nine in the plane. The design is
// fixed and symmetric, so the normal equations have a closed form (no
// matrix to factor): each gradient term is sum(u f) / sum(u^2), each cross
// term sum(u v f) / 4 (the four diagonal samples), and the constant and the
// three curvatures solve a 4 x 4 (3 x 3 in the plane) system solved by hand
// below. Its peak as newton_peak; where there is none in all three (a
// near-circular outline has none along the angle), the peak in x and y.
bool quadratic_peak(const float (&f)[kSamples], bool with_angle, Vector3& peak) noexcept {
  float s0 = 0.0f, sx = 0.0f, sy = 0.0f, sz = 0.0f;  // sum f, sum u^2 f, sum v^2 f, sum w^2 f
  Vector3 g = Vector3::Zero();
  float xy = 0.0f, xz = 0.0f, yz = 0.0f;  // sum u v f, ...
  for (int k = 0; k < kSamples; ++k) {
    if (!with_angle && !in_plane(k)) continue;
    const float u = kDesign[k].x, v = kDesign[k].y, w = kDesign[k].t;
    s0 += f[k];
    sx += u * u * f[k], sy += v * v * f[k], sz += w * w * f[k];
    g(0) += u * f[k], g(1) += v * f[k], g(2) += w * f[k];
    xy += u * v * f[k], xz += u * w * f[k], yz += v * w * f[k];
  }
  float qx = 0.0f, qy = 0.0f, qz = 0.0f;  // half the curvatures
  if (with_angle) {
    // Normal equations [19 10 10 10; 10 10 4 4; 10 4 10 4; 10 4 4 10] (c, qx, qy, qz) = (s0, sx, sy, sz).
    g /= 10.0f;
    const float t = sx + sy + sz, c = (9.0f * s0 - 5.0f * t) / 21.0f, q = (s0 - 19.0f * c) / 10.0f;
    qx = q / 3.0f + (2.0f * sx - sy - sz) / 18.0f;
    qy = q / 3.0f + (2.0f * sy - sx - sz) / 18.0f;
    qz = q / 3.0f + (2.0f * sz - sx - sy) / 18.0f;
  } else {
    // Normal equations [9 6 6; 6 6 4; 6 4 6] (c, qx, qy) = (s0, sx, sy).
    g /= 6.0f;
    const float q = (sx + sy - (4.0f / 3.0f) * s0) / 2.0f;
    qx = 0.5f * (q + 0.5f * (sx - sy));
    qy = 0.5f * (q - 0.5f * (sx - sy));
  }
  Matrix3 negative_h;
  negative_h << -2.0f * qx, -xy / 4.0f, -xz / 4.0f, -xy / 4.0f, -2.0f * qy, -yz / 4.0f, -xz / 4.0f, -yz / 4.0f, -2.0f * qz;
  if (with_angle && newton_peak(negative_h, g, 3, peak)) return true;
  return newton_peak(negative_h, g, 2, peak);
}

// One round of refinement at spacing (step_px, step_deg) around `centre`,
// whose score is `score`: the fitted peak if it scores better than every
// sample, else the best sample. False (centre unchanged) when a sample falls
// outside the frame.
bool refine_round(const ImageView& frame, const FocusStack& stack, OutlineRing ring, float step_px, float step_deg, bool with_angle,
                  Pose& centre, float& score, std::uint32_t& correlations) noexcept {
  bool ring_compared = false;
  float f[kSamples] = {};
  f[0] = score;
  int best = 0;
  for (int k = 1; k < kSamples; ++k) {
    if (!with_angle && !in_plane(k)) continue;
    const Pose p = moved(centre, kDesign[k].x * step_px, kDesign[k].y * step_px, kDesign[k].t * step_deg);
    ++correlations;
    if (!correlation_at(frame, p, stack, centre.depth, ring, f[k], ring_compared)) return false;
    if (f[k] > f[best]) best = k;
  }
  Vector3 peak;
  if (quadratic_peak(f, with_angle, peak)) {
    const Pose p = moved(centre, peak(0) * step_px, peak(1) * step_px, peak(2) * step_deg);
    float at_peak = 0.0f;
    ++correlations;
    if (correlation_at(frame, p, stack, centre.depth, ring, at_peak, ring_compared) && at_peak >= f[best]) {
      centre = p;
      score = at_peak;
      return true;
    }
  }
  centre = moved(centre, kDesign[best].x * step_px, kDesign[best].y * step_px, kDesign[best].t * step_deg);
  score = f[best];
  return true;
}

// Keeps x and y within `bound` of `anchor`; true if it moved them.
bool clamp_near(const Pose& anchor, float bound, Pose& pose) noexcept {
  const auto clamp = [](float v, float lo, float hi) { return v < lo ? lo : (v > hi ? hi : v); };
  const float x = clamp(pose.x, anchor.x - bound, anchor.x + bound), y = clamp(pose.y, anchor.y - bound, anchor.y + bound);
  const bool moved = x != pose.x || y != pose.y;
  pose.x = x;
  pose.y = y;
  return moved;
}

float clamp_to(float v, float bound) noexcept { return v > bound ? bound : (v < -bound ? -bound : v); }

// Gauss-Newton ascent from `pose` (scored `score` at the coarse step): each
// pass scores the pose it is at and gives a step from it. A step that
// scores no better than the pose it left is halved, twice at most; a step
// below a hundredth of a pixel ends the ascent. Each step is clamped to one
// pixel (the angle: one pixel at the outline's reach); x and y stay within
// `bound_px` of `anchor` and the angle within `bound_deg`. `pose` and
// `score` end at the best pose scored (at the fine step).
void ascend(const ImageView& frame, const FocusStack& fine, OutlineRing ring, bool with_angle, float reach_px, const Pose& anchor,
            float bound_px, float bound_deg, Pose& pose, float& score, std::uint32_t& correlations) noexcept {
  constexpr float kDegrees = 57.2957795f;
  const float max_deg = kDegrees / reach_px;
  Pose at = pose;
  float dx = 0.0f, dy = 0.0f, dt = 0.0f;
  bool scored = false;
  int halvings = 0;
  const auto step_to = [&](float scale) {
    at = moved(pose, scale * dx, scale * dy, scale * dt);
    clamp_near(anchor, bound_px, at);
    at.theta_deg = anchor.theta_deg + clamp_to(at.theta_deg - anchor.theta_deg, bound_deg);
    const float tx = at.x - pose.x, ty = at.y - pose.y, tt = (at.theta_deg - pose.theta_deg) * reach_px / kDegrees;
    return tx * tx + ty * ty + tt * tt >= 1.0e-4f;
  };
  for (int pass = 0; pass < kAscentPasses; ++pass) {
    CorrelationAscent a;
    correlations += kAscentPassCost;
    const bool ok = correlation_ascent_at(frame, at, fine, at.depth, with_angle, a, ring);
    if (!ok && !scored) return;
    if (!ok || (scored && !(a.signed_r2 > score))) {
      if (++halvings > 2 || !step_to(0.5f)) return;
      dx *= 0.5f, dy *= 0.5f, dt *= 0.5f;
      continue;
    }
    scored = true;
    halvings = 0;
    pose = at;
    score = a.signed_r2;
    if (!a.has_step) return;
    dx = clamp_to(a.dx, 1.0f), dy = clamp_to(a.dy, 1.0f), dt = clamp_to(a.dtheta_deg, max_deg);
    if (!step_to(1.0f)) return;
  }
}

bool distinct(const Pose& a, const Pose& b, float distance_px) noexcept {
  const float dx = a.x - b.x, dy = a.y - b.y;
  return a.depth != b.depth || dx * dx + dy * dy >= distance_px * distance_px;
}

}  // namespace

Status verify(const ImageView& frame, const FocusStack& stack, const Proposals& proposals, const VerifyOptions& options,
              Verdict& out) noexcept {
  out = Verdict{};
  if (!frame.valid() || !valid_focus_stack(stack) || proposals.count > kMaxProposals ||
      !(options.spacing_px > 0.0f && options.spacing_px <= 4.0f) || !(options.distinct_px >= 0.0f) ||
      !(options.tie_margin >= 0.0f && options.tie_margin <= 2.0f) || !(options.max_offset_px > 0.0f) ||
      !(options.max_angle_spacings > 0.0f && options.max_angle_spacings <= 180.0f)) {
    return Status::kInvalidArgument;
  }
  for (std::uint32_t i = 0; i < proposals.count; ++i) {
    const Pose& p = proposals.poses[i];
    if (!pose_in_range(p) || !within_limit(p.theta_deg, 1.0e5f) || p.depth >= stack.images.size()) return Status::kInvalidArgument;
  }
  float scores[kMaxProposals];
  bool scored[kMaxProposals];
  // Every pose of the frame scored over the same samples: the outline's
  // ring compared or not as it is at the first proposal scored (the
  // caller's own choice, where it lies in the frame; OutlineRing).
  OutlineRing ring = OutlineRing::kWhereItAgrees;
  bool ring_compared = false;
  for (std::uint32_t i = 0; i < proposals.count; ++i) {
    ++out.correlations;
    scored[i] = correlation_at(frame, proposals.poses[i], stack, proposals.poses[i].depth, ring, scores[i], ring_compared);
    if (scored[i] && ring == OutlineRing::kWhereItAgrees) ring = ring_as_found(ring_compared);
    if (scored[i] && (!out.found || scores[i] > scores[out.winner])) {
      out.found = true;
      out.winner = i;
    }
  }
  out.samples = out.correlations * samples_per_correlation(stack);
  if (!out.found) return Status::kOk;
  if (out.winner != 0 && scored[0] && distinct(proposals.poses[0], proposals.poses[out.winner], options.distinct_px) &&
      correlation_from_signed_square(scores[0]) >= correlation_from_signed_square(scores[out.winner]) - options.tie_margin) {
    out.winner = 0;
  }
  const Pose& won = proposals.poses[out.winner];
  float runner_up = -1.0f;
  for (std::uint32_t i = 0; i < proposals.count; ++i) {
    if (scored[i] && i != out.winner && distinct(proposals.poses[i], won, options.distinct_px) && scores[i] > runner_up)
      runner_up = scores[i];
  }
  Pose pose = won;
  float score = scores[out.winner];
  if (options.refine) {
    // A small model is sampled at every pixel for the refinement, so that
    // its score is smooth enough to place the peak to a tenth of a pixel.
    const ImageView& model = stack.images[0];
    FocusStack fine = stack;
    while (fine.step > 1 && (model.width / fine.step) * (model.height / fine.step) < options.refine_samples) --fine.step;
    // The outline's reach from the reference point: an angle moves its far
    // points by the angle (radians) times this. The angle's spacing moves
    // them by the spacing (0.1 to 1 degree).
    const float reach = 0.5f * static_cast<float>(model.width > model.height ? model.width : model.height);
    float spacing_deg = options.spacing_px / reach * 57.2957795f;
    spacing_deg = spacing_deg < 0.1f ? 0.1f : (spacing_deg > 1.0f ? 1.0f : spacing_deg);
    float fine_score = 0.0f;
    const std::uint32_t scored_before = out.correlations;
    if (options.refine_by == RefineBy::kGaussNewton) {
      fine_score = score;  // replaced by the first pass's, at the fine step
      ascend(frame, fine, ring, options.refine_angle, reach, won, options.max_offset_px, options.max_angle_spacings * spacing_deg, pose,
             fine_score, out.correlations);
    } else {
      ++out.correlations;
      if (!correlation_at(frame, pose, fine, pose.depth, ring, fine_score, ring_compared)) fine = stack, fine_score = score;
      float step_px = options.spacing_px, step_deg = spacing_deg;
      for (int round = 0; round < kRefineRounds; ++round, step_px *= 0.5f, step_deg *= 0.5f) {
        if (!refine_round(frame, fine, ring, step_px, step_deg, options.refine_angle, pose, fine_score, out.correlations)) break;
        if (clamp_near(won, options.max_offset_px, pose)) {
          ++out.correlations;
          if (!correlation_at(frame, pose, fine, pose.depth, ring, fine_score, ring_compared)) break;
        }
      }
    }
    out.samples += (out.correlations - scored_before) * samples_per_correlation(fine);
    if (fine.step != stack.step) {
      ++out.correlations;
      out.samples += samples_per_correlation(stack);
      if (!correlation_at(frame, pose, stack, pose.depth, ring, score, ring_compared)) score = fine_score;
    } else {
      score = fine_score;
    }
  }
  out.pose = pose;
  out.score = correlation_from_signed_square(score);
  out.runner_up = runner_up > -1.0f ? correlation_from_signed_square(runner_up) : -1.0f;
  return Status::kOk;
}

}  // namespace gabarit
