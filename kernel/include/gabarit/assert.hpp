// GABARIT_ASSERT(condition): a documented precondition, checked where the
// build asks for it (GABARIT_ASSERTS, on in Debug builds such as the dev
// preset; off in release and firmware builds, where it costs nothing and the
// condition is not evaluated). A failed check is a programming error, not an
// input error (those are Status values): it stops the program at once with
// __builtin_trap, which needs no runtime support on any target.
#pragma once

#if defined(GABARIT_ASSERTS_ENABLED) && GABARIT_ASSERTS_ENABLED
#define GABARIT_ASSERT(condition) ((condition) ? static_cast<void>(0) : __builtin_trap())
#else
#define GABARIT_ASSERT(condition) static_cast<void>(sizeof(static_cast<bool>(condition)))
#endif
