#include "gabarit/depth_by_intensity.hpp"

#include <cstddef>

#include "gabarit/deterministic_math.hpp"
#include "intensity_samples.hpp"

namespace gabarit {

using namespace intensity;

namespace {

// Stack images correlated in one pass over the frame: the frame samples (and
// their sums) are shared, each image adds its own. Up to kGroup at a time,
// so the sums live on the stack.
constexpr std::size_t kGroup = 8;

// The correlation of each of `images` (at most kGroup, all of the stack's
// size) with the frame at a pose, as the sign of the correlation times its
// square (ordered like the correlation, no square root); ok[i] is false when
// too few samples fall in the frame or either side is flat. With
// matched_blur, each model value is blurred as MatchedBlur says (for
// comparing stack images with each other); with a support, only the samples
// inside it are compared (the same ones for every image).
void correlations(const ImageView& frame, std::span<const ImageView> images, const Pose& pose, const FocusStack& stack,
                  float* scores, bool* ok, bool matched_blur = false, const ObjectSupport* support = nullptr) noexcept {
  FrameSums f;
  ImageSums s[kGroup];
  const std::uint8_t* model_rows[kGroup];
  std::uint32_t row_v = 0;
  walk_samples(
      frame, images[0].width, images[0].height, pose, stack,
      [&](std::uint32_t v) {
        row_v = v;
        for (std::size_t i = 0; i < images.size(); ++i) model_rows[i] = images[i].pixels + std::size_t{v} * images[i].stride;
        return support != nullptr ? support->row_columns(v) : ColumnSpan{0, images[0].width};
      },
      [&](std::uint32_t u, const FrameSample& at) {
        if (support != nullptr && !support->contains(u, row_v)) return;
        const std::uint64_t b = at.value();
        ++f.n;
        f.b += b;
        f.bb += b * b;
        const MatchedBlur blur = matched_blur ? MatchedBlur(images[0], u, row_v, at) : MatchedBlur{};
        for (std::size_t i = 0; i < images.size(); ++i) {
          const std::uint64_t a = matched_blur ? blur.value(model_rows[i], u) : model_rows[i][u];
          s[i].a += a;
          s[i].aa += a * a;
          s[i].ab += a * b;
        }
      });
  for (std::size_t i = 0; i < images.size(); ++i) {
    scores[i] = 0.0f;
    ok[i] = signed_r2(f, s[i], scores[i]);
  }
}

// Over the model's outline where it has a flat surround (ObjectSupport);
// over every sample if it has none, or too few of the outline's fall in the
// frame.
bool outline_correlation(const ImageView& frame, const ImageView& m, const Pose& pose, const FocusStack& stack,
                         const ObjectSupport& outline, OutlineRing ring, float& score, bool& ring_compared) noexcept {
  OutlineParts parts;
  std::uint32_t model_v = 0;
  walk_samples(
      frame, m.width, m.height, pose, stack,
      [&](std::uint32_t v) {
        model_v = v;
        return outline.row_columns(v);
      },
      [&](std::uint32_t u, const FrameSample& at) {
        const ObjectSupport::Place place = outline.place(u, model_v);
        if (place == ObjectSupport::kOutside) return;
        const bool object = place == ObjectSupport::kObject;
        add_sample(object ? parts.object_frame : parts.ring_frame, object ? parts.object_model : parts.ring_model, m.at(u, model_v),
                   at.value());
      });
  FrameSums f;
  ImageSums s;
  parts.compared(outline.surround(), ring, f, s);
  ring_compared = parts.ring_used(outline.surround(), ring);
  return signed_r2(f, s, score);
}

bool correlation(const ImageView& frame, const ImageView& m, const Pose& pose, const FocusStack& stack, OutlineRing ring,
                 float& score, bool& ring_compared) noexcept {
  const std::span<const ImageView> image(&m, 1);
  const ObjectSupport outline(image, ObjectSupport::kOutline);
  if (outline.flat() && outline_correlation(frame, m, pose, stack, outline, ring, score, ring_compared)) return true;
  ring_compared = false;
  bool ok = false;
  correlations(frame, image, pose, stack, &score, &ok);
  return ok;
}

bool valid_inputs(const ImageView& frame, const Pose& pose, const FocusStack& stack) noexcept {
  // The bounds keep the 16.16 geometry's products below 2^62.
  return frame.valid() && pose_in_range(pose) && within_limit(pose.theta_deg, 1.0e5f) && valid_focus_stack(stack);
}

}  // namespace

bool valid_focus_stack(const FocusStack& stack) noexcept {
  if (stack.images.empty() || stack.images.size() > 65535u || stack.step == 0 || stack.step > kMaxStackStep ||
      !within_limit(stack.ref_x, static_cast<float>(kMaxStackSide)) ||
      !within_limit(stack.ref_y, static_cast<float>(kMaxStackSide))) {
    return false;
  }
  for (const ImageView& m : stack.images) {
    if (!m.valid() || m.width != stack.images[0].width || m.height != stack.images[0].height || m.width > kMaxStackSide ||
        m.height > kMaxStackSide) {
      return false;
    }
  }
  return true;
}

bool correlation_at(const ImageView& frame, const Pose& pose, const FocusStack& stack, std::uint16_t depth,
                    float& signed_r2) noexcept {
  bool ring_compared = false;
  return correlation(frame, stack.images[depth], pose, stack, OutlineRing::kWhereItAgrees, signed_r2, ring_compared);
}

bool correlation_at(const ImageView& frame, const Pose& pose, const FocusStack& stack, std::uint16_t depth, OutlineRing ring,
                    float& signed_r2, bool& ring_compared) noexcept {
  return correlation(frame, stack.images[depth], pose, stack, ring, signed_r2, ring_compared);
}

bool frame_variance_at(const ImageView& frame, const Pose& pose, const FocusStack& stack, std::uint16_t depth,
                       float& variance) noexcept {
  const std::span<const ImageView> image = stack.images.subspan(depth, 1);
  const ObjectSupport outline(image, ObjectSupport::kOutline);
  // The samples correlation_at compares: the outline's, or every one.
  for (const bool on_outline : {true, false}) {
    if (on_outline && !outline.flat()) continue;
    FrameSums f;
    std::uint32_t model_v = 0;
    walk_samples(
        frame, image[0].width, image[0].height, pose, stack,
        [&](std::uint32_t v) {
          model_v = v;
          return on_outline ? outline.row_columns(v) : ColumnSpan{0, image[0].width};
        },
        [&](std::uint32_t u, const FrameSample& at) {
          if (on_outline && outline.place(u, model_v) == ObjectSupport::kOutside) return;
          const std::uint64_t b = at.value();
          ++f.n;
          f.b += b;
          f.bb += b * b;
        });
    if (f.n < 16) continue;
    // n^2 times the variance in (1/256 grey level)^2, exact, then to grey levels^2.
    const float n = static_cast<float>(f.n);
    variance = difference(f.n, f.bb, f.b, f.b) / (n * n) * (1.0f / 65536.0f);
    return true;
  }
  return false;
}


Status depth_by_intensity(const ImageView& frame, const Pose& pose, const FocusStack& stack, std::uint16_t& depth,
                          float switch_margin) noexcept {
  if (!valid_inputs(frame, pose, stack) || !(switch_margin >= 0.0f && switch_margin <= 2.0f)) return Status::kInvalidArgument;
  bool have_best = false, have_current = false;
  float best_score = 0.0f, current_score = 0.0f;
  std::uint16_t best_depth = depth;
  const ObjectSupport object(stack.images, ObjectSupport::kInterior);
  // Over the object's samples where the stack has a flat surround; over all
  // of them if it has none, or too few of the object's fall in the frame.
  for (const bool on_object : {true, false}) {
    if (have_best || (on_object && !object.flat())) continue;
    for (std::size_t first = 0; first < stack.images.size(); first += kGroup) {
      const std::span<const ImageView> group =
          stack.images.subspan(first, stack.images.size() - first < kGroup ? stack.images.size() - first : kGroup);
      float scores[kGroup];
      bool ok[kGroup];
      correlations(frame, group, pose, stack, scores, ok, true, on_object ? &object : nullptr);
      for (std::size_t i = 0; i < group.size(); ++i) {
        if (!ok[i]) continue;
        if (first + i == depth) have_current = true, current_score = scores[i];
        if (!have_best || scores[i] > best_score) {
          have_best = true;
          best_score = scores[i];
          best_depth = static_cast<std::uint16_t>(first + i);
        }
      }
    }
  }
  // Hysteresis: the current depth stays unless another correlates better by the margin.
  if (have_best && (!have_current || best_score > current_score + switch_margin)) depth = best_depth;
  return Status::kOk;
}

Status angle_by_intensity(const ImageView& frame, const Pose& pose, const FocusStack& stack, float& theta_deg) noexcept {
  if (!valid_inputs(frame, pose, stack) || pose.depth >= stack.images.size()) return Status::kInvalidArgument;
  const ImageView& m = stack.images[pose.depth];
  float scores[2 * kAngleSteps + 1];
  int best = -1;
  // One choice of the outline's ring for every angle compared (OutlineRing):
  // the first angle's.
  OutlineRing ring = OutlineRing::kWhereItAgrees;
  for (int k = -kAngleSteps; k <= kAngleSteps; ++k) {
    Pose p = pose;
    p.theta_deg = pose.theta_deg + static_cast<float>(k) * kAngleIncrementDeg;
    float score = 0.0f;
    bool ring_compared = false;
    if (!correlation(frame, m, p, stack, ring, score, ring_compared)) return Status::kOk;  // leaving the frame: keep the angle
    if (ring == OutlineRing::kWhereItAgrees) ring = ring_as_found(ring_compared);
    scores[k + kAngleSteps] = score;
    if (best < 0 || score > scores[best]) best = k + kAngleSteps;
  }
  float offset = static_cast<float>(best - kAngleSteps) * kAngleIncrementDeg;
  if (best > 0 && best < 2 * kAngleSteps) {
    // A parabola through the peak and its neighbours places it between samples.
    const float a = scores[best - 1], b = scores[best], c = scores[best + 1];
    const float curvature = a - 2.0f * b + c;
    if (curvature < 0.0f) offset += kAngleIncrementDeg * (0.5f * (a - c) / curvature);
  }
  theta_deg = pose.theta_deg + offset;
  return Status::kOk;
}

}  // namespace gabarit
