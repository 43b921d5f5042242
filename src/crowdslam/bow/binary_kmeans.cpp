#include "crowdslam/bow/binary_kmeans.h"

#include <algorithm>
#include <cstring>
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

// A descriptor as four 64-bit words (memcpy: no alignment assumption).
struct Words {
  std::uint64_t w[feature::kDescriptorBytes / 8];
};

Words load_words(const std::uint8_t* bytes) {
  Words words;
  std::memcpy(words.w, bytes, sizeof words.w);
  return words;
}

int distance(const Words& a, const Words& b) {
  return feature::popcount64(a.w[0] ^ b.w[0]) + feature::popcount64(a.w[1] ^ b.w[1]) +
         feature::popcount64(a.w[2] ^ b.w[2]) + feature::popcount64(a.w[3] ^ b.w[3]);
}

std::size_t nearest_centre(const std::uint8_t* row, const std::vector<Words>& centres) {
  const Words words = load_words(row);
  std::size_t best = 0;
  int best_distance = std::numeric_limits<int>::max();
  for (std::size_t c = 0; c < centres.size(); ++c) {
    const int d = distance(words, centres[c]);
    if (d < best_distance) {
      best_distance = d;
      best = c;
    }
  }
  return best;
}

// kSpread[b]: byte i (i = 0..7) is bit i of b, so adding spread bytes counts 8 bits at once.
constexpr std::array<std::uint64_t, 256> make_spread() {
  std::array<std::uint64_t, 256> table{};
  for (int b = 0; b < 256; ++b) {
    for (int bit = 0; bit < 8; ++bit) table[b] |= static_cast<std::uint64_t>((b >> bit) & 1) << (8 * bit);
  }
  return table;
}
constexpr std::array<std::uint64_t, 256> kSpread = make_spread();

}  // namespace

Descriptor majority_centroid(const std::vector<const std::uint8_t*>& rows,
                             const std::vector<std::size_t>& members) {
  // Per descriptor byte, eight 8-bit counters packed in one word; they are emptied into `ones` before
  // any can overflow (at most 255 rows per batch).
  std::array<std::size_t, 8 * feature::kDescriptorBytes> ones{};
  std::array<std::uint64_t, feature::kDescriptorBytes> lanes{};
  auto flush = [&] {
    for (int byte = 0; byte < feature::kDescriptorBytes; ++byte) {
      for (int bit = 0; bit < 8; ++bit) ones[8 * byte + bit] += (lanes[byte] >> (8 * bit)) & 0xFF;
      lanes[byte] = 0;
    }
  };
  std::size_t batch = 0;
  for (std::size_t m : members) {
    const std::uint8_t* row = rows[m];
    for (int byte = 0; byte < feature::kDescriptorBytes; ++byte) lanes[byte] += kSpread[row[byte]];
    if (++batch == 255) {
      flush();
      batch = 0;
    }
  }
  flush();
  Descriptor centre{};
  for (int byte = 0; byte < feature::kDescriptorBytes; ++byte) {
    std::uint8_t value = 0;
    for (int bit = 0; bit < 8; ++bit) {
      if (2 * ones[8 * byte + bit] > members.size()) value |= 1u << bit;
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
  std::vector<Words> centre_words(centres.size());
  for (int iteration = 0; iteration < std::max(1, max_iterations); ++iteration) {
    bool changed = false;
    for (auto& m : members) m.clear();
    for (std::size_t c = 0; c < centres.size(); ++c) centre_words[c] = load_words(centres[c].data());
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const std::size_t c = nearest_centre(rows[i], centre_words);
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
