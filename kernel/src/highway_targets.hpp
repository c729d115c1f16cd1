// Internal to the kernel: the Google Highway targets the vector bodies are
// compiled for (canny_rows.cpp, dense_lanes.cpp), which vector_body.cpp
// chooses from at run time. Included where GABARIT_HIGHWAY is set, before
// <hwy/foreach_target.h>. Not installed.
#pragma once

#if !defined(GABARIT_HIGHWAY)
#error "highway_targets.hpp is for builds with Google Highway (GABARIT_HIGHWAY)"
#endif

// Highway's debug checks call hwy::Abort, which lives in libhwy: the kernel
// uses Highway header-only, without linking it.
#define HWY_IS_DEBUG_BUILD 0
#if defined(__x86_64__)
#define HWY_TARGETS (HWY_AVX2 | HWY_SSE4)
#else
#define HWY_TARGETS HWY_STATIC_TARGET  // NEON on AArch64; no SVE build
#endif
