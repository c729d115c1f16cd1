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
  for (int i = 0; i < 12; ++i) x = 0.5f * (x + s / x);
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

using Vector10 = Eigen::Matrix<float, 10, 1>;
using Matrix10 = Eigen::Matrix<float, 10, 10>;
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

// A quadratic c + g.u + u'Hu/2 in x and y fitted by least squares to the
// nine samples in the plane; its peak as below, the angle's offset 0.
bool planar_peak(const float (&f)[kSamples], Vector3& peak) noexcept {
  using Vector6 = Eigen::Matrix<float, 6, 1>;
  Eigen::Matrix<float, 6, 6> ata = Eigen::Matrix<float, 6, 6>::Zero();
  Vector6 atf = Vector6::Zero();
  for (int k = 0; k < kSamples; ++k) {
    if (!in_plane(k)) continue;
    const float u = kDesign[k].x, v = kDesign[k].y;
    Vector6 row;
    row << 1.0f, u, v, 0.5f * u * u, 0.5f * v * v, u * v;
    ata += row * row.transpose();
    atf += row * f[k];
  }
  const Vector6 beta = Eigen::LDLT<Eigen::Matrix<float, 6, 6>>(ata).solve(atf);
  Eigen::Matrix<float, 2, 2> negative_h;
  negative_h << -beta(3), -beta(5), -beta(5), -beta(4);
  const Eigen::LDLT<Eigen::Matrix<float, 2, 2>> curvature(negative_h);
  if (curvature.info() != Eigen::Success || !(curvature.vectorD().minCoeff() > 0.0f)) return false;
  const Eigen::Matrix<float, 2, 1> uv = curvature.solve(Eigen::Matrix<float, 2, 1>(beta(1), beta(2)));
  peak = Vector3(uv(0), uv(1), 0.0f);
  return true;
}

// A quadratic c + g.u + u'Hu/2 fitted to the 19 samples by least squares;
// its peak u* = -H^-1 g when H is negative definite, each coordinate clamped
// to one spacing. False when the samples do not form a peak.
bool quadratic_peak(const float (&f)[kSamples], bool with_angle, Vector3& peak) noexcept {
  if (!with_angle) return planar_peak(f, peak);
  Matrix10 ata = Matrix10::Zero();
  Vector10 atf = Vector10::Zero();
  for (int k = 0; k < kSamples; ++k) {
    const float u = kDesign[k].x, v = kDesign[k].y, w = kDesign[k].t;
    Vector10 row;
    row << 1.0f, u, v, w, 0.5f * u * u, 0.5f * v * v, 0.5f * w * w, u * v, u * w, v * w;
    ata += row * row.transpose();
    atf += row * f[k];
  }
  const Eigen::LDLT<Matrix10> fit(ata);
  const Vector10 beta = fit.solve(atf);
  Matrix3 negative_h;
  negative_h << -beta(4), -beta(7), -beta(8), -beta(7), -beta(5), -beta(9), -beta(8), -beta(9), -beta(6);
  const Vector3 g(beta(1), beta(2), beta(3));
  const Eigen::LDLT<Matrix3> curvature(negative_h);
  if (curvature.info() == Eigen::Success && curvature.vectorD().minCoeff() > 0.0f) {
    peak = curvature.solve(g);  // -H u = g
  } else {
    // No peak in all three (a near-circular outline has none along the
    // angle): the peak in x and y with the angle kept, if there is one there.
    const Eigen::Matrix<float, 2, 2> h2 = negative_h.topLeftCorner<2, 2>();
    const Eigen::LDLT<Eigen::Matrix<float, 2, 2>> planar(h2);
    if (planar.info() != Eigen::Success || !(planar.vectorD().minCoeff() > 0.0f)) return false;
    const Eigen::Matrix<float, 2, 1> uv = planar.solve(g.head<2>());
    peak = Vector3(uv(0), uv(1), 0.0f);
  }
  for (int i = 0; i < 3; ++i) {
    if (!is_finite(peak(i))) return false;
    peak(i) = peak(i) > 1.0f ? 1.0f : (peak(i) < -1.0f ? -1.0f : peak(i));
  }
  return true;
}

// One round of refinement at spacing (step_px, step_deg) around `centre`,
// whose score is `score`: the fitted peak if it scores better than every
// sample, else the best sample. False (centre unchanged) when a sample falls
// outside the frame.
bool refine_round(const ImageView& frame, const FocusStack& stack, float step_px, float step_deg, bool with_angle, Pose& centre,
                  float& score, std::uint32_t& correlations) noexcept {
  float f[kSamples] = {};
  f[0] = score;
  int best = 0;
  for (int k = 1; k < kSamples; ++k) {
    if (!with_angle && !in_plane(k)) continue;
    const Pose p = moved(centre, kDesign[k].x * step_px, kDesign[k].y * step_px, kDesign[k].t * step_deg);
    ++correlations;
    if (!correlation_at(frame, p, stack, centre.depth, f[k])) return false;
    if (f[k] > f[best]) best = k;
  }
  Vector3 peak;
  if (quadratic_peak(f, with_angle, peak)) {
    const Pose p = moved(centre, peak(0) * step_px, peak(1) * step_px, peak(2) * step_deg);
    float at_peak = 0.0f;
    ++correlations;
    if (correlation_at(frame, p, stack, centre.depth, at_peak) && at_peak >= f[best]) {
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
      !(options.tie_margin >= 0.0f && options.tie_margin <= 2.0f) || !(options.max_offset_px > 0.0f)) {
    return Status::kInvalidArgument;
  }
  for (std::uint32_t i = 0; i < proposals.count; ++i) {
    const Pose& p = proposals.poses[i];
    if (!pose_in_range(p) || !within_limit(p.theta_deg, 1.0e5f) || p.depth >= stack.images.size()) return Status::kInvalidArgument;
  }
  float scores[kMaxProposals];
  bool scored[kMaxProposals];
  for (std::uint32_t i = 0; i < proposals.count; ++i) {
    ++out.correlations;
    scored[i] = correlation_at(frame, proposals.poses[i], stack, proposals.poses[i].depth, scores[i]);
    if (scored[i] && (!out.found || scores[i] > scores[out.winner])) {
      out.found = true;
      out.winner = i;
    }
  }
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
    float fine_score = 0.0f;
    ++out.correlations;
    if (!correlation_at(frame, pose, fine, pose.depth, fine_score)) fine = stack, fine_score = score;
    // The angle that moves the outline's far points by the spacing.
    const float reach = 0.5f * static_cast<float>(model.width > model.height ? model.width : model.height);
    float step_px = options.spacing_px, step_deg = options.spacing_px / reach * 57.2957795f;
    step_deg = step_deg < 0.1f ? 0.1f : (step_deg > 1.0f ? 1.0f : step_deg);
    for (int round = 0; round < kRefineRounds; ++round, step_px *= 0.5f, step_deg *= 0.5f) {
      if (!refine_round(frame, fine, step_px, step_deg, options.refine_angle, pose, fine_score, out.correlations)) break;
      if (clamp_near(won, options.max_offset_px, pose)) {
        ++out.correlations;
        if (!correlation_at(frame, pose, fine, pose.depth, fine_score)) break;
      }
    }
    if (fine.step != stack.step) {
      ++out.correlations;
      if (!correlation_at(frame, pose, stack, pose.depth, score)) score = fine_score;
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
