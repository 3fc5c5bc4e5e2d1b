// Function multi-versioning: SSSLAB_AVX2_CLONES before a hot function compiles it twice (AVX2 and
// the baseline) and lets the loader pick one through an ifunc resolver. Under ThreadSanitizer the
// resolver runs instrumented before the TSan runtime is set up and the program dies while loading
// (GCC 12), so a TSan build compiles the baseline only.
#pragma once

#include "core/sanitizers.h"

#ifdef SSSLAB_TSAN
#define SSSLAB_AVX2_CLONES
#else
#define SSSLAB_AVX2_CLONES __attribute__((target_clones("avx2", "default")))
#endif
