#pragma once
// How much longer the timing of the tests that run svslam's threads must allow in a sanitizer
// build. ThreadSanitizer makes the stages 5-20x slower (a 320x240 synthetic frame takes about
// 0.4 s to render and 1-2 s through the front end on two loaded cores), so a stall timeout of 1 s
// trips on ordinary frames there; AddressSanitizer costs about 2-3x.
//
// Tests scale their timeouts and fault durations by kSanitizerTimeScale, and leave out
// throughput properties (no frame dropped at 10 Hz) that only a release build can show: those
// are checked by the release build's run of the same test, which CI runs too.

namespace svslam::test {

#if defined(__SANITIZE_THREAD__)
#define SVSLAM_TEST_TSAN 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define SVSLAM_TEST_TSAN 1
#endif
#endif

#if defined(__SANITIZE_ADDRESS__)
#define SVSLAM_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SVSLAM_TEST_ASAN 1
#endif
#endif

#if defined(SVSLAM_TEST_TSAN)
inline constexpr double kSanitizerTimeScale = 4.0;
inline constexpr bool kSanitized = true;
#elif defined(SVSLAM_TEST_ASAN)
inline constexpr double kSanitizerTimeScale = 2.0;
inline constexpr bool kSanitized = true;
#else
inline constexpr double kSanitizerTimeScale = 1.0;
inline constexpr bool kSanitized = false;
#endif

}  // namespace svslam::test
