#include "crowdslam/optim/schur_kernel.h"

// Nothing else is included here (see the header): every function below is ours and file-local, so the
// AVX2 + FMA build of the loop shares no code with the rest of the program.

namespace crowdslam::optim::schur_kernel {
namespace {

// dst(r, c) -= sum_k left(r, k) right(c, k), 6x6 column-major at dst with leading dimension ld; left and
// right 6x3 column-major. Column c of the product is left * right(c, :)^T: three scaled copies of
// left's contiguous columns, which the compiler turns into vector multiply-adds.
#define CROWDSLAM_SCHUR_SUB_OUTER                                                                            \
  inline __attribute__((always_inline)) void sub_outer(const double* left, const double* right, double* dst, \
                                                       std::ptrdiff_t ld) {                                  \
    for (int c = 0; c < 6; ++c) {                                                                            \
      const double r0 = right[c];                                                                            \
      const double r1 = right[c + 6];                                                                        \
      const double r2 = right[c + 12];                                                                       \
      double* column = dst + c * ld;                                                                         \
      for (int r = 0; r < 6; ++r) column[r] -= left[r] * r0 + left[r + 6] * r1 + left[r + 12] * r2;          \
    }                                                                                                        \
  }

// The pair loop of the header's contract, on top of a sub_outer.
#define CROWDSLAM_SCHUR_PAIRS_BODY                         \
  for (int a = 0; a < point.m; ++a) {                      \
    const double* y_a = point.y + 18 * a;                  \
    const int fa = point.pose[a];                          \
    for (int b = a; b < point.m; ++b) {                    \
      const double* w_b = point.w + 18 * b;                \
      const int fb = point.pose[b];                        \
      if (a == b || fa < fb) {                             \
        sub_outer(y_a, w_b, s + 6 * fa + 6 * fb * ld, ld); \
      } else if (fa > fb) {                                \
        sub_outer(w_b, y_a, s + 6 * fb + 6 * fa * ld, ld); \
      } else {                                             \
        sub_outer(y_a, w_b, s + 6 * fa + 6 * fa * ld, ld); \
        sub_outer(w_b, y_a, s + 6 * fa + 6 * fa * ld, ld); \
      }                                                    \
    }                                                      \
  }

namespace baseline {
CROWDSLAM_SCHUR_SUB_OUTER
}  // namespace baseline

#if defined(__x86_64__) && defined(__GNUC__)
#define CROWDSLAM_SCHUR_HAVE_AVX2 1
namespace avx2_fma {
#pragma GCC push_options
#pragma GCC target("avx2,fma")
CROWDSLAM_SCHUR_SUB_OUTER

void subtract_pairs(const PointPairs& point, double* s, std::ptrdiff_t ld) { CROWDSLAM_SCHUR_PAIRS_BODY }
#pragma GCC pop_options
}  // namespace avx2_fma
#endif

}  // namespace

void subtract_pairs_baseline(const PointPairs& point, double* s, std::ptrdiff_t ld) {
  using baseline::sub_outer;
  CROWDSLAM_SCHUR_PAIRS_BODY
}

SubtractPairs subtract_pairs_avx2_fma() {
#ifdef CROWDSLAM_SCHUR_HAVE_AVX2
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return &avx2_fma::subtract_pairs;
#endif
  return nullptr;
}

SubtractPairs subtract_pairs() {
  static const SubtractPairs chosen =
      subtract_pairs_avx2_fma() != nullptr ? subtract_pairs_avx2_fma() : &subtract_pairs_baseline;
  return chosen;
}

const char* subtract_pairs_variant() {
  return subtract_pairs() == &subtract_pairs_baseline ? "baseline" : "avx2+fma";
}

}  // namespace crowdslam::optim::schur_kernel
