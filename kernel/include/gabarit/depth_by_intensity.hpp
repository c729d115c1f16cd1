// The focus-stack depth (and a finer angle) from intensities, at a tracked pose.
//
// Edge features change little when an object goes out of focus, so the
// stencils tell neighbouring stack depths apart poorly (docs/tracking.md).
// Intensities do: at the pose the votes found, each stack image is laid over
// the frame (rotated by the pose's angle about the model's reference point)
// and compared by normalised cross-correlation; the best-correlated image is
// the depth. Where the stack images show the object on a flat surround
// (their border one grey value), only the object's own samples are compared:
// the frame shows something else behind it (kernel/src/intensity_samples.hpp,
// ObjectSupport). The frame is sampled bilinearly in 1/256-pixel fixed point
// and the sums are integers (the final ratio is one float division), so every
// target gets the same answer; every
// `step`-th model pixel in each direction is sampled.
#pragma once
#include <cstdint>
#include <span>

#include "gabarit/image_view.hpp"
#include "gabarit/status.hpp"
#include "gabarit/pose.hpp"

namespace gabarit {

struct FocusStack {
  std::span<const ImageView> images;  // one per depth, all the same size, in depth order
  float ref_x = 0.0f, ref_y = 0.0f;   // the model's reference point in those images
  std::uint32_t step = 2;             // sample every step-th pixel (>= 1)
};

// The stack's images may be at most kMaxStackSide pixels a side, with the
// reference point within +-kMaxStackSide, and sampled every 1..kMaxStackStep
// pixels: the sample geometry is 16.16 fixed point in 64 bits.
inline constexpr std::uint32_t kMaxStackSide = 16384;
inline constexpr std::uint32_t kMaxStackStep = 256;

// kInvalidArgument for an empty stack, invalid images, images of different
// sizes or beyond those bounds, a step of 0 or above kMaxStackStep, more than
// 65535 depths, or a pose outside pose_in_range or |theta| >= 1e5; `depth` is
// then left unchanged. When fewer than 16 samples fall inside the frame (the
// object is leaving it) there is nothing to compare: kOk, `depth` unchanged.
// With a switch_margin, `depth` (the current one, e.g. the votes' choice)
// is kept unless another depth's score beats its score by the margin
// (hysteresis; kInvalidArgument outside [0, 2]); 0 takes the best-correlated
// depth, the current one on a tie.
[[nodiscard]] Status depth_by_intensity(const ImageView& frame, const Pose& pose, const FocusStack& stack,
                                        std::uint16_t& depth, float switch_margin = 0.0f) noexcept;

// The angle by intensity: the stack image of pose.depth correlated with the
// frame (sampled bilinearly) at the pose's angle plus -1.5 .. +1.5 degrees in
// 0.75-degree steps; `theta_deg` is the best, placed between steps by a
// parabola through the peak. Stencil cells are 0.5 degrees or more wide; the
// intensities pin the angle down further. On the microscope scene five
// samples placed the angle as well as thirteen 0.25-degree ones did, and
// sampling every third model pixel instead of every second cost 4% of the
// frames within 1 degree (docs/tracking.md). kInvalidArgument as above or
// for a depth outside the stack; kOk with `theta_deg` unchanged when the
// object is leaving the frame.
// The stack valid for the calls above (and correlation_at): images of one
// size within the bounds, a step in 1..kMaxStackStep, at most 65535 depths.
[[nodiscard]] bool valid_focus_stack(const FocusStack& stack) noexcept;

// The samples one correlation with `stack` walks: every step-th pixel of a
// stack image, along both axes. Precondition: valid_focus_stack(stack).
constexpr std::uint64_t samples_per_correlation(const FocusStack& stack) noexcept {
  const ImageView& model = stack.images[0];
  return std::uint64_t{(model.width + stack.step - 1) / stack.step} * ((model.height + stack.step - 1) / stack.step);
}

// The normalised cross-correlation of stack image `depth` with the frame at
// `pose` (its depth ignored), as sign(r) r^2 (ordered like r, no square
// root), exact integer sums then float: the same bits on every target.
// Where the image shows the object on a flat surround (its border one grey
// value), over the object and a one-pixel ring of the surround only (the
// outline's contrast kept, the clutter behind the surround left out); over
// every sample if it has none or too few of those fall in the frame.
// False when fewer than 16 samples fall inside the frame or either side is
// flat. Preconditions: valid_focus_stack(stack), depth < the stack's size,
// pose_in_range(pose) and |theta| < 1e5.
[[nodiscard]] bool correlation_at(const ImageView& frame, const Pose& pose, const FocusStack& stack, std::uint16_t depth,
                                  float& signed_r2) noexcept;

// Whether an outline's ring of surround is compared. Alone, correlation_at
// compares it where the frame's surround stands against the object on the
// side the model's surround does (kWhereItAgrees), decided at each pose.
// Poses that are compared with one another (a frame's proposals and the
// refinement between them) need one choice for all: decided pose by pose,
// the score jumps where the frame's ring mean crosses the object's (on a
// coin over a printed page, by a third of itself between poses half a pixel
// apart), and the best-scored pose is where the ring happened to be left
// out, not where the model fits (docs/tracking.md, "Vote, then verify").
enum class OutlineRing : std::uint8_t { kWhereItAgrees, kCompared, kLeftOut };
// The choice a pose scored with kWhereItAgrees made, fixed for the others.
constexpr OutlineRing ring_as_found(bool ring_compared) noexcept {
  return ring_compared ? OutlineRing::kCompared : OutlineRing::kLeftOut;
}
// correlation_at with the ring as `ring` says; `ring_compared` tells whether
// the ring was in the sums (false without a ring: a model with no flat
// surround, or the fallback to every sample), so that a caller can fix
// kWhereItAgrees's choice at one pose for the others.
[[nodiscard]] bool correlation_at(const ImageView& frame, const Pose& pose, const FocusStack& stack, std::uint16_t depth,
                                  OutlineRing ring, float& signed_r2, bool& ring_compared) noexcept;

// The variance of the frame's samples (grey levels squared) over the samples
// correlation_at compares at `pose` with stack image `depth`: how much
// contrast the frame shows there (a dimmed frame, less). False when fewer
// than 16 samples fall inside the frame. Preconditions as correlation_at's.
[[nodiscard]] bool frame_variance_at(const ImageView& frame, const Pose& pose, const FocusStack& stack, std::uint16_t depth,
                                     float& variance) noexcept;

// One Gauss-Newton step up the correlation at `pose`: the enhanced
// correlation coefficient's maximisation (Evangelidis and Psarakis, "Parametric
// image alignment using enhanced correlation coefficient maximization", IEEE
// TPAMI 2008) for a rigid motion (x, y, angle about the reference point): the
// zero-mean model and frame samples and the zero-mean Jacobian give the
// closed-form step that maximises the linearised correlation, gain and
// offset eliminated. The frame's slope in the Jacobian is the model's slope
// turned through the pose, times the gain between the frame's slope (central
// differences of the bilinear samples) and the model's, least squares: the
// clutter's and the noise's slopes, unrelated to the model's, would inflate
// the curvature and shorten every step (correlation_ascent.cpp, ecc_step).
// One pass over the samples gives the step and, from the same exact integer
// sums, correlation_at's value at `pose` (the same bits). The Jacobian's sums
// are floats added per model row in one order: the same bits on every target.
struct CorrelationAscent {
  float signed_r2 = 0.0f;  // correlation_at's value at the pose
  bool has_step = false;   // false where the linearised correlation has no maximum (flat, or not correlated)
  float dx = 0.0f, dy = 0.0f, dtheta_deg = 0.0f;
};
// False (as correlation_at) when fewer than 16 samples fall inside the frame
// or either side is flat. `with_angle` false: x and y only (dtheta 0); where
// the angle is not observable (a near-circular outline) the step is x and y
// only too. Preconditions as correlation_at's.
[[nodiscard]] bool correlation_ascent_at(const ImageView& frame, const Pose& pose, const FocusStack& stack, std::uint16_t depth,
                                         bool with_angle, CorrelationAscent& out,
                                         OutlineRing ring = OutlineRing::kWhereItAgrees) noexcept;

inline constexpr int kAngleSteps = 2;
inline constexpr float kAngleIncrementDeg = 0.75f;
[[nodiscard]] Status angle_by_intensity(const ImageView& frame, const Pose& pose, const FocusStack& stack,
                                        float& theta_deg) noexcept;

}  // namespace gabarit
