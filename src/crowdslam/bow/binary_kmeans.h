#pragma once
// k-means++ on 256-bit binary descriptors under the Hamming distance, with bitwise-majority centroids
// (a centre bit is 1 when more than half of its members have it set): the clustering step of the
// vocabulary tree.
#include <array>
#include <cstddef>
#include <cstdint>
#include <random>
#include <vector>

#include "crowdslam/feature/descriptor.h"

namespace crowdslam::bow {

using Descriptor = std::array<std::uint8_t, feature::kDescriptorBytes>;

struct BinaryClusters {
  std::vector<Descriptor> centres;                // non-empty clusters only
  std::vector<std::vector<std::size_t>> members;  // per centre: indices into the input, increasing
};

// Bitwise majority of the given rows (ties give 0).
Descriptor majority_centroid(const std::vector<const std::uint8_t*>& rows,
                             const std::vector<std::size_t>& members);

// Clusters `rows` (each pointing at 32 bytes) into at most k clusters: k-means++ seeding (first centre
// uniform, then each next one with probability proportional to the squared Hamming distance to the
// nearest centre chosen so far; seeding stops early when every row equals a centre, so n distinct rows
// with n <= k give n singleton clusters), then Lloyd iterations until no assignment changes or
// max_iterations. Ties go to the lower centre index. Deterministic for a given rng state.
BinaryClusters kmeans_binary(const std::vector<const std::uint8_t*>& rows, int k, int max_iterations,
                             std::mt19937_64& rng);

}  // namespace crowdslam::bow
