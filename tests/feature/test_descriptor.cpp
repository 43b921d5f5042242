#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "crowdslam/feature/descriptor.h"

namespace crowdslam::feature {
namespace {

int reference_hamming(const std::uint8_t* a, const std::uint8_t* b) {
  int distance = 0;
  for (int byte = 0; byte < kDescriptorBytes; ++byte) {
    for (int bit = 0; bit < 8; ++bit) distance += ((a[byte] >> bit) & 1) != ((b[byte] >> bit) & 1);
  }
  return distance;
}

TEST(Popcount64, KnownWords) {
  EXPECT_EQ(popcount64(0), 0);
  EXPECT_EQ(popcount64(~std::uint64_t{0}), 64);
  EXPECT_EQ(popcount64(std::uint64_t{1} << 63), 1);
  EXPECT_EQ(popcount64(0x8000000000000001ULL), 2);
  EXPECT_EQ(popcount64(0xF0F0F0F0F0F0F0F0ULL), 32);
}

TEST(HammingDistance, MatchesBitByBitReferenceOnRandomData) {
  std::mt19937 rng(1234);
  std::uniform_int_distribution<int> byte(0, 255);
  // One extra byte so that unaligned descriptors are exercised too.
  std::vector<std::uint8_t> a(kDescriptorBytes + 1);
  std::vector<std::uint8_t> b(kDescriptorBytes + 1);
  for (int trial = 0; trial < 2000; ++trial) {
    for (auto& value : a) value = static_cast<std::uint8_t>(byte(rng));
    for (auto& value : b) value = static_cast<std::uint8_t>(byte(rng));
    const int offset = trial % 2;
    ASSERT_EQ(hamming_distance(a.data() + offset, b.data() + offset),
              reference_hamming(a.data() + offset, b.data() + offset))
        << "trial " << trial;
  }
}

TEST(HammingDistance, ExtremesAndSymmetry) {
  std::vector<std::uint8_t> zeros(kDescriptorBytes, 0);
  std::vector<std::uint8_t> ones(kDescriptorBytes, 0xFF);
  std::vector<std::uint8_t> one_bit(kDescriptorBytes, 0);
  one_bit[31] = 0x80;
  EXPECT_EQ(hamming_distance(zeros.data(), zeros.data()), 0);
  EXPECT_EQ(hamming_distance(zeros.data(), ones.data()), 256);
  EXPECT_EQ(hamming_distance(ones.data(), zeros.data()), 256);
  EXPECT_EQ(hamming_distance(zeros.data(), one_bit.data()), 1);
}

}  // namespace
}  // namespace crowdslam::feature
