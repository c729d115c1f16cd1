// Vote, then verify: the votes propose, a dense score decides.
//
// A vote counts edge pixels in stencils; on a small object, a near-circular
// outline or a textured background the cell it ranks first is often a
// neighbour of the true one, or clutter (docs/tracking.md, "Vote, then
// verify"). So the session gathers a few proposals each frame (the vote's
// best cells, the plain loop's winner, the motion filter's prediction, the
// last pose), scores each by the normalised cross-correlation of the model
// image (the focus stack's image of the proposal's depth) with the frame at
// that pose, keeps the best, and refines its x, y and angle on the same
// score by Gauss-Newton steps (correlation_ascent_at), or as the first
// refinement did by a quadratic fitted by least squares to 19 correlations
// around it (the centre, six along the axes, twelve on the diagonals of each
// pair), its peak taken by a Newton step (fixed-size Eigen), three rounds at
// halving spacings. Correlations are exact integer sums
// (depth_by_intensity.hpp), the algebra scalar floats: the same bits on
// every target.
//
// NCC over the model image was chosen over the mean cosine of gradient
// directions because it is the score a user compares us with (an OpenCV
// matchTemplate bank), it is already the session's depth and angle measure
// (the same integer code, tested across targets), and it is invariant to the
// gain and offset changes of the suite's illumination.
#pragma once

#include <cstdint>

#include "gabarit/depth_by_intensity.hpp"
#include "gabarit/image_view.hpp"
#include "gabarit/pose.hpp"
#include "gabarit/status.hpp"

namespace gabarit {

inline constexpr std::uint32_t kMaxProposals = 16;

// A fixed-size set of poses to verify, in the order they were added.
struct Proposals {
  Pose poses[kMaxProposals];
  std::uint32_t count = 0;
  // Adds `p` unless the set is full or holds the same pose already.
  void add(const Pose& p) noexcept;
};

// How the winner is refined on the score.
enum class RefineBy : std::uint8_t {
  // Gauss-Newton ascent of the correlation (correlation_ascent_at, the
  // enhanced correlation coefficient's step): one pass over the samples per
  // step, at most kAscentPasses.
  kGaussNewton,
  // A quadratic fitted by least squares to 19 correlations around the
  // winner, three rounds at halving spacings (the first refinement; 57
  // correlations and more).
  kQuadraticDesign,
};

inline constexpr int kAscentPasses = 6;
// A Gauss-Newton pass reads each sample's 4 x 4 frame neighbourhood and the
// model's neighbours and adds fifteen products: it took about as long as two
// correlations on the suite (docs/performance.md), so it counts as two in
// Verdict::correlations and Verdict::samples.
inline constexpr std::uint32_t kAscentPassCost = 2;

struct VerifyOptions {
  bool refine = true;  // sub-pixel x, y and sub-degree angle on the score
  RefineBy refine_by = RefineBy::kGaussNewton;
  // The angle refined too; false where the motion has no rotation (a table
  // without an angle axis): x and y only.
  bool refine_angle = true;
  // The quadratic design's first spacing: this many pixels along x and y,
  // and the angle that moves the model's outline (half its larger side from
  // the reference point) by as much, within [0.1, 1] degree. The quadratic
  // design's three rounds keep the angle within 1.75 such angles of the
  // winner's.
  float spacing_px = 0.5f;
  // Gauss-Newton keeps the angle within this many of those angles of the
  // winner's (0 .. 180]. Where the votes barely tell angles apart (a
  // near-circular coin), every proposal is near the predicted angle; 1.75
  // (the quadratic design's reach) let a wrong prediction stand, and the
  // angle ran away from the truth frame after frame. 3.5 lets the intensities pull it back
  // (docs/tracking.md, "Vote, then verify").
  float max_angle_spacings = 3.5f;
  // The refinement samples the model at every stack.step-th pixel, or finer
  // until it has at least this many samples (a small model).
  std::uint32_t refine_samples = 4096;
  // The refined x and y stay within this many pixels of the winning
  // proposal (a vote's cell is 1 px): where the correlation is flat along a
  // direction (an elongated object along its axis) the votes' cell, anchored
  // by edges across it, bounds the slide.
  float max_offset_px = 0.5f;
  // The runner-up: the best proposal at least this far from the winner
  // (pixels), or at another depth; what tells an ambiguous frame.
  float distinct_px = 2.0f;
  // Near-ties between distinct placements go to the first proposal (the
  // caller's own choice, e.g. the one the motion model expects): it wins
  // while its correlation r is within this margin of a best that lies at
  // least distinct_px away. A best nearer than that wins outright.
  float tie_margin = 0.02f;
};

struct Verdict {
  bool found = false;        // some proposal lay inside the frame with contrast on both sides
  Pose pose;                 // the best proposal, refined
  float score = 0.0f;        // its correlation r, -1..1
  float runner_up = -1.0f;   // the best distinct proposal's r (-1 without one)
  std::uint32_t winner = 0;  // the index of the winning proposal
  std::uint32_t correlations = 0;  // correlations computed
  // The model samples those correlations compared (an ascent pass's counted
  // kAscentPassCost times): the cost, in the frame ledger's terms. The
  // refinement may sample a small model more finely than the stack's step
  // (refine_samples), so correlations alone undercount it.
  std::uint64_t samples = 0;
};

// kInvalidArgument for an invalid frame or stack, or a proposal outside
// pose_in_range, with |theta| >= 1e5 or a depth the stack does not have.
[[nodiscard]] Status verify(const ImageView& frame, const FocusStack& stack, const Proposals& proposals,
                            const VerifyOptions& options, Verdict& out) noexcept;

// r from the signed r^2 correlation_at gives, by Newton's iteration in
// float (+, -, *, / only: the same bits on every target).
float correlation_from_signed_square(float signed_r2) noexcept;

}  // namespace gabarit
