// Internal to the kernel: which vector body the loops with one run on this
// CPU (canny_rows.cpp, dense_lanes.cpp). Not installed.
//
// With Google Highway (GABARIT_HIGHWAY, kernel/CMakeLists.txt) x86-64 builds
// an AVX2 and an SSE4 body and runs the best the CPU has (the baseline
// x86-64 has neither, and a binary must still run there); AArch64 builds
// NEON, which every AArch64 core has. Everywhere else (armhf, the Cortex-M
// builds, a build without the headers or with -DGABARIT_HIGHWAY=OFF) only
// the scalar body exists. Every body gives the scalar body's results bit
// for bit.
#pragma once

namespace gabarit {

enum class VectorBody { kScalar, kSse4, kAvx2, kNeon };

// The best body this build has and this CPU runs.
[[nodiscard]] VectorBody vector_body() noexcept;
// Whether this build has `body` and this CPU runs it (tests run every one).
[[nodiscard]] bool vector_body_runs(VectorBody body) noexcept;
// "AVX2", "SSE4", "NEON" or "scalar".
[[nodiscard]] const char* vector_body_name(VectorBody body) noexcept;

}  // namespace gabarit
