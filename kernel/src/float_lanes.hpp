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

// GCC's and Clang's generic vectors, which every toolchain the kernel
// builds with (host, aarch64, armhf, arm-none-eabi) has; on a target
// without a SIMD unit they are lowered to the scalar operations.
#if !defined(__GNUC__)
#error "FloatLanes needs GCC or Clang generic vectors (__attribute__((vector_size)))"
#endif
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

}  // namespace gabarit
