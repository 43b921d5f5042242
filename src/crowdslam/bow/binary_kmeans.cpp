#include "crowdslam/bow/binary_kmeans.h"

#include <algorithm>
#include <limits>

namespace crowdslam::bow {
namespace {

// Uniform double in [0, 1) from the raw generator (std distributions differ between libraries).
double uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

std::vector<Descriptor> seed_plus_plus(const std::vector<const std::uint8_t*>& rows, int k,
                                       std::mt19937_64& rng) {
  std::vector<Descriptor> centres;
  const std::size_t n = rows.size();
  Descriptor first;
  std::copy_n(rows[rng() % n], first.size(), first.begin());
  centres.push_back(first);
  std::vector<double> nearest_sq(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double d = feature::hamming_distance(rows[i], first.data());
    nearest_sq[i] = d * d;
  }
  while (static_cast<int>(centres.size()) < k) {
    double total = 0.0;
    for (double v : nearest_sq) total += v;
    if (total <= 0.0) break;  // every row equals a centre
    double target = uniform01(rng) * total;
    std::size_t pick = n;
    for (std::size_t i = 0; i < n; ++i) {
      if (nearest_sq[i] <= 0.0) continue;
      pick = i;
      target -= nearest_sq[i];
      if (target < 0.0) break;
    }
    Descriptor centre;
    std::copy_n(rows[pick], centre.size(), centre.begin());
    centres.push_back(centre);
    for (std::size_t i = 0; i < n; ++i) {
      const double d = feature::hamming_distance(rows[i], centre.data());
      nearest_sq[i] = std::min(nearest_sq[i], d * d);
    }
  }
  return centres;
}

std::size_t nearest_centre(const std::uint8_t* row, const std::vector<Descriptor>& centres) {
  std::size_t best = 0;
  int best_distance = std::numeric_limits<int>::max();
  for (std::size_t c = 0; c < centres.size(); ++c) {
    const int d = feature::hamming_distance(row, centres[c].data());
    if (d < best_distance) {
      best_distance = d;
      best = c;
    }
  }
  return best;
}

}  // namespace

Descriptor majority_centroid(const std::vector<const std::uint8_t*>& rows,
                             const std::vector<std::size_t>& members) {
  std::array<int, 8 * feature::kDescriptorBytes> ones{};
  for (std::size_t m : members) {
    const std::uint8_t* row = rows[m];
    for (int byte = 0; byte < feature::kDescriptorBytes; ++byte) {
      for (int bit = 0; bit < 8; ++bit) ones[8 * byte + bit] += (row[byte] >> bit) & 1;
    }
  }
  Descriptor centre{};
  for (int byte = 0; byte < feature::kDescriptorBytes; ++byte) {
    std::uint8_t value = 0;
    for (int bit = 0; bit < 8; ++bit) {
      if (2 * static_cast<std::size_t>(ones[8 * byte + bit]) > members.size()) value |= 1u << bit;
    }
    centre[byte] = value;
  }
  return centre;
}

BinaryClusters kmeans_binary(const std::vector<const std::uint8_t*>& rows, int k, int max_iterations,
                             std::mt19937_64& rng) {
  BinaryClusters result;
  if (rows.empty() || k <= 0) return result;
  std::vector<Descriptor> centres = seed_plus_plus(rows, k, rng);
  std::vector<std::size_t> assignment(rows.size(), centres.size());
  std::vector<std::vector<std::size_t>> members(centres.size());
  for (int iteration = 0; iteration < std::max(1, max_iterations); ++iteration) {
    bool changed = false;
    for (auto& m : members) m.clear();
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const std::size_t c = nearest_centre(rows[i], centres);
      changed = changed || c != assignment[i];
      assignment[i] = c;
      members[c].push_back(i);
    }
    for (std::size_t c = 0; c < centres.size(); ++c) {
      if (!members[c].empty()) centres[c] = majority_centroid(rows, members[c]);
    }
    if (!changed) break;
  }
  for (std::size_t c = 0; c < centres.size(); ++c) {
    if (members[c].empty()) continue;
    result.centres.push_back(centres[c]);
    result.members.push_back(std::move(members[c]));
  }
  return result;
}

}  // namespace crowdslam::bow
