// Which sanitizer a build runs under, for the few places that must behave differently there.
// SSSLAB_TSAN is defined in the ThreadSanitizer build (GCC's __SANITIZE_THREAD__, Clang's
// feature test) and undefined otherwise.
#pragma once

#if defined(__SANITIZE_THREAD__)
#define SSSLAB_TSAN 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define SSSLAB_TSAN 1
#endif
#endif
