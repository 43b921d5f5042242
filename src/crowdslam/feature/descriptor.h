#pragma once
// Binary ORB descriptors (256 bits = 32 bytes per row of a CV_8UC1 matrix) and their Hamming distance.
//
// hamming_distance loads the descriptor as four 64-bit words (memcpy: no alignment or aliasing
// assumptions) and counts bits with popcount64. No architecture flag is added to the build (portability):
// the default x86-64 target has no popcnt instruction, so __builtin_popcountll would become a libgcc call;
// popcount64 then uses an inline bit-trick count instead. bench/bench_orb_extractor.cpp measures both.
#include <cstddef>
#include <cstdint>
#include <cstring>

namespace crowdslam::feature {

inline constexpr int kDescriptorBytes = 32;

// Bits set in a 64-bit word. With popcnt available at compile time (-mpopcnt, -march=native, ...) the
// builtin is one instruction; otherwise GCC would call libgcc's __popcountdi2, which is several times
// slower than this inline SWAR count.
inline int popcount64(std::uint64_t x) {
#if defined(__POPCNT__)
  return __builtin_popcountll(x);
#else
  x = x - ((x >> 1) & 0x5555555555555555ULL);
  x = (x & 0x3333333333333333ULL) + ((x >> 2) & 0x3333333333333333ULL);
  x = (x + (x >> 4)) & 0x0F0F0F0F0F0F0F0FULL;
  return static_cast<int>((x * 0x0101010101010101ULL) >> 56);
#endif
}

// Number of differing bits between two 32-byte descriptors, 0..256.
inline int hamming_distance(const std::uint8_t* a, const std::uint8_t* b) {
  int distance = 0;
  for (std::size_t word = 0; word < kDescriptorBytes / 8; ++word) {
    std::uint64_t wa = 0;
    std::uint64_t wb = 0;
    std::memcpy(&wa, a + 8 * word, sizeof wa);
    std::memcpy(&wb, b + 8 * word, sizeof wb);
    distance += popcount64(wa ^ wb);
  }
  return distance;
}

}  // namespace crowdslam::feature
