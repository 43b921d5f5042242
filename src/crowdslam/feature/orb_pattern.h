#pragma once
// The standard ORB steered-BRIEF test pattern (256 point pairs in a 31x31 patch); see orb_pattern.cpp
// for its provenance and licence.
#include <array>
#include <cstddef>
#include <cstdint>

namespace crowdslam::feature {

inline constexpr int kOrbPatternSize = 256;  // number of tests = descriptor bits

inline constexpr std::size_t kOrbPatternValues = std::size_t{kOrbPatternSize} * 4;

// Test i compares the pixel at (p[4i], p[4i+1]) with the one at (p[4i+2], p[4i+3]), offsets from the
// keypoint before rotation by the keypoint angle. All coordinates lie in [-13, 12].
const std::array<std::int8_t, kOrbPatternValues>& orb_pattern();

}  // namespace crowdslam::feature
