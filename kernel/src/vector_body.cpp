#include "vector_body.hpp"

namespace gabarit {
namespace {
#if defined(GABARIT_HIGHWAY) && defined(__x86_64__)
bool sse4_runs() noexcept {
  return __builtin_cpu_supports("sse4.2") && __builtin_cpu_supports("pclmul") && __builtin_cpu_supports("aes");
}
#endif
}  // namespace

bool vector_body_runs(VectorBody body) noexcept {
  switch (body) {
    case VectorBody::kScalar: return true;
#if defined(GABARIT_HIGHWAY) && defined(__x86_64__)
    // Highway compiles each target for all that its name implies (SSE4 with
    // PCLMUL and AES; AVX2 with those, BMI1/2, FMA and F16C), so the CPU must
    // have all of it. F16C, which clang 14 cannot ask for, came before AVX2
    // on Intel's and AMD's cores alike. GCC's runtime reads the flags once,
    // at start-up: each question is a load and a test.
    case VectorBody::kSse4: return sse4_runs();
    case VectorBody::kAvx2:
      return sse4_runs() && __builtin_cpu_supports("avx2") && __builtin_cpu_supports("bmi") &&
             __builtin_cpu_supports("bmi2") && __builtin_cpu_supports("fma");
#elif defined(GABARIT_HIGHWAY) && defined(__aarch64__)
    case VectorBody::kNeon: return true;
#endif
    default: return false;
  }
}

VectorBody vector_body() noexcept {
  constexpr VectorBody kBestFirst[] = {VectorBody::kAvx2, VectorBody::kSse4, VectorBody::kNeon};
  for (const VectorBody body : kBestFirst)
    if (vector_body_runs(body)) return body;
  return VectorBody::kScalar;
}

const char* vector_body_name(VectorBody body) noexcept {
  switch (body) {
    case VectorBody::kAvx2: return "AVX2";
    case VectorBody::kSse4: return "SSE4";
    case VectorBody::kNeon: return "NEON";
    case VectorBody::kScalar: break;
  }
  return "scalar";
}

}  // namespace gabarit
