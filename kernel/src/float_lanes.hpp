// Internal to the kernel: four floats added and multiplied lane by lane.
// Not installed.
//
// Each lane is its own IEEE single-precision operation, so four sums kept
// in one FloatLanes give the same bits as four float sums kept apart, on
// every target: where the compiler has a SIMD unit that is exact for
// floats (SSE, AArch64's NEON) it uses it, and the sums stay in registers;
// elsewhere (a Cortex-M's FPU; ARMv7's NEON, which flushes denormals and
// which GCC does not use for floats without -funsafe-math-optimizations)
// it emits the four scalar operations. The kernel builds with
// -ffp-contract=off, so no multiply and add are fused on any of them.
#pragma once

namespace gabarit {

#if defined(__GNUC__)  // GCC and Clang: their generic vectors
class FloatLanes {
 public:
  FloatLanes() noexcept = default;
  FloatLanes(float a, float b, float c, float d) noexcept : v_{a, b, c, d} {}
  float operator[](int i) const noexcept { return v_[i]; }
  FloatLanes& operator+=(const FloatLanes& o) noexcept {
    v_ += o.v_;
    return *this;
  }
  friend FloatLanes operator*(const FloatLanes& a, const FloatLanes& b) noexcept { return FloatLanes(a.v_ * b.v_); }
  friend FloatLanes operator*(const FloatLanes& a, float s) noexcept { return FloatLanes(a.v_ * s); }

 private:
  using Vector = float __attribute__((vector_size(16)));
  explicit FloatLanes(Vector v) noexcept : v_(v) {}
  Vector v_ = {0.0f, 0.0f, 0.0f, 0.0f};
};
#else
class FloatLanes {
 public:
  FloatLanes() noexcept = default;
  FloatLanes(float a, float b, float c, float d) noexcept : v_{a, b, c, d} {}
  float operator[](int i) const noexcept { return v_[i]; }
  FloatLanes& operator+=(const FloatLanes& o) noexcept {
    for (int i = 0; i < 4; ++i) v_[i] += o.v_[i];
    return *this;
  }
  friend FloatLanes operator*(const FloatLanes& a, const FloatLanes& b) noexcept {
    return {a.v_[0] * b.v_[0], a.v_[1] * b.v_[1], a.v_[2] * b.v_[2], a.v_[3] * b.v_[3]};
  }
  friend FloatLanes operator*(const FloatLanes& a, float s) noexcept { return a * FloatLanes(s, s, s, s); }

 private:
  float v_[4] = {};
};
#endif

}  // namespace gabarit
