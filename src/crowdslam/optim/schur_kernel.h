#pragma once
// The innermost loop of the Schur LM (schur_lm.cpp): for one point, subtract W_a V^-1 W_b^T from the
// reduced camera system for every pair of its observations by free poses. It is most of a local BA's
// time, so it is compiled twice: once for the baseline x86-64 target (SSE2) and once with AVX2 + FMA,
// chosen at run time by what the CPU supports. No architecture flag is added to the build:
// a robot's low-power CPU without AVX still runs the baseline.
//
// Plain arrays, no Eigen: Eigen's templates compiled with AVX in one translation unit and without in
// another would be two different definitions of the same inline functions (the linker keeps one of
// them) and would disagree on the alignment of fixed-size matrices. schur_kernel.cpp includes nothing
// but this header.
#include <cstddef>

namespace crowdslam::optim::schur_kernel {

// One point's observations by free poses, m of them:
//   y[18 a .. 18 a + 17] = W_a V^-1 (6x3, column-major), w[18 a ..] = W_a (6x3, column-major),
//   pose[a] = the free-pose index of observation a.
// For every pair a <= b, with block = y_a w_b^T (6x6), the upper triangle of the symmetric matrix S
// (column-major, leading dimension ld, 6x6 blocks per free pose) gets:
//   a == b or pose[a] < pose[b]: S(pose[a], pose[b]) -= block
//   pose[a] > pose[b]:           S(pose[b], pose[a]) -= block^T
//   pose[a] == pose[b], a != b:  S(pose[a], pose[a]) -= block + block^T
struct PointPairs {
  const double* y = nullptr;
  const double* w = nullptr;
  const int* pose = nullptr;
  int m = 0;
};

using SubtractPairs = void (*)(const PointPairs& point, double* s, std::ptrdiff_t ld);

// The baseline build, and the AVX2 + FMA build when this CPU (and compiler) has it (nullptr otherwise).
void subtract_pairs_baseline(const PointPairs& point, double* s, std::ptrdiff_t ld);
[[nodiscard]] SubtractPairs subtract_pairs_avx2_fma();

// The fastest variant this CPU runs (decided once).
[[nodiscard]] SubtractPairs subtract_pairs();
// "avx2+fma" or "baseline": which variant subtract_pairs() is.
[[nodiscard]] const char* subtract_pairs_variant();

}  // namespace crowdslam::optim::schur_kernel
