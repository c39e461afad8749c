// Run-time choice of the stereo kernel backend from the CPU's features.
#include <cstring>
#include <initializer_list>

#include "simd/stereo_kernels.hpp"

namespace svslam::simd {

bool backendAvailable(Backend b) {
  switch (b) {
    case Backend::kAuto:
    case Backend::kScalar:
      return true;
#if defined(SVSLAM_HAVE_AVX2)
    case Backend::kAvx2:
      return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("popcnt");
#endif
#if defined(SVSLAM_HAVE_AVX512)
    case Backend::kAvx512:
      // The AVX-512 backend uses F + BW + VL and the VPOPCNTDQ extension (Ice Lake, Zen 4).
      return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
             __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512vpopcntdq") &&
             __builtin_cpu_supports("avx512bitalg");
#endif
#if defined(SVSLAM_HAVE_NEON)
    case Backend::kNeon:
      return true;  // NEON (Advanced SIMD) is mandatory on AArch64 and required by armhf builds
#endif
    default:
      return false;
  }
}

Backend bestBackend() {
  if (backendAvailable(Backend::kAvx512)) return Backend::kAvx512;
  if (backendAvailable(Backend::kAvx2)) return Backend::kAvx2;
  if (backendAvailable(Backend::kNeon)) return Backend::kNeon;
  return Backend::kScalar;
}

const StereoKernels& kernels(Backend b) {
  if (b == Backend::kAuto) b = bestBackend();
  if (!backendAvailable(b)) return scalarKernels();
  switch (b) {
#if defined(SVSLAM_HAVE_AVX2)
    case Backend::kAvx2:
      return avx2Kernels();
#endif
#if defined(SVSLAM_HAVE_AVX512)
    case Backend::kAvx512:
      return avx512Kernels();
#endif
#if defined(SVSLAM_HAVE_NEON)
    case Backend::kNeon:
      return neonKernels();
#endif
    default:
      return scalarKernels();
  }
}

const char* backendName(Backend b) {
  switch (b) {
    case Backend::kAuto:
      return "auto";
    case Backend::kScalar:
      return "scalar";
    case Backend::kAvx2:
      return "avx2";
    case Backend::kAvx512:
      return "avx512";
    case Backend::kNeon:
      return "neon";
  }
  return "unknown";
}

bool parseBackend(const char* s, Backend& out) {
  for (Backend b :
       {Backend::kAuto, Backend::kScalar, Backend::kAvx2, Backend::kAvx512, Backend::kNeon}) {
    if (std::strcmp(s, backendName(b)) == 0) {
      out = b;
      return true;
    }
  }
  return false;
}

}  // namespace svslam::simd
