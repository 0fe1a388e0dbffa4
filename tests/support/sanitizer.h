// Whether this test program is built with AddressSanitizer (.ci/test's second build), for the few
// compute-heavy tests that check the same property on many cases: under the sanitizer they check a
// fixed, named subset of their cases, with the same tolerances. The sanitizer build is there to find
// memory errors and undefined behaviour on every code path, and a subset of cases runs the same paths;
// the full case lists run in the Release suite (docs/maintainer/build-options.md).
//
// Example:
//   for (int i = 0; i < static_cast<int>(cases.size()); ++i) {
//     if (!ident::testing::RunsCase(i, /*sanitizer_stride=*/3)) continue;   // every case, or every 3rd
//     ...
//   }
#pragma once

// IDENT_TESTS_UNDER_ASAN (for #if, e.g. tests/support/alloc_counter.cc): GCC says __SANITIZE_ADDRESS__,
// clang __has_feature(address_sanitizer).
#if defined(__SANITIZE_ADDRESS__)
#define IDENT_TESTS_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define IDENT_TESTS_UNDER_ASAN 1
#endif
#endif

namespace ident::testing {

#if defined(IDENT_TESTS_UNDER_ASAN)
inline constexpr bool kUnderSanitizer = true;
#else
inline constexpr bool kUnderSanitizer = false;
#endif

// Case i runs: always in an uninstrumented build; under the sanitizer only every `sanitizer_stride`-th
// case (i = 0, sanitizer_stride, 2·sanitizer_stride, …).
constexpr bool RunsCase(int i, int sanitizer_stride) { return !kUnderSanitizer || i % sanitizer_stride == 0; }

// `full` in an uninstrumented build, `reduced` under the sanitizer (a sample size, a number of steps).
template <class T>
constexpr T FullOrUnderSanitizer(T full, T reduced) {
  return kUnderSanitizer ? reduced : full;
}

}  // namespace ident::testing
