#pragma once
// Synthetic binary descriptors for the vocabulary tests: random centres and noisy copies of them.
#include <opencv2/core.hpp>
#include <random>
#include <vector>

#include "crowdslam/bow/binary_kmeans.h"

namespace crowdslam::bow::testing {

inline Descriptor random_descriptor(std::mt19937& rng) {
  Descriptor d;
  for (auto& byte : d) byte = static_cast<std::uint8_t>(rng() & 0xFF);
  return d;
}

// `centre` with `flips` distinct random bits inverted.
inline Descriptor noisy_copy(const Descriptor& centre, int flips, std::mt19937& rng) {
  Descriptor d = centre;
  std::vector<int> bits(256);
  for (int i = 0; i < 256; ++i) bits[i] = i;
  for (int i = 0; i < flips; ++i) {
    const int j = i + static_cast<int>(rng() % (256 - i));
    std::swap(bits[i], bits[j]);
    d[bits[i] / 8] ^= static_cast<std::uint8_t>(1u << (bits[i] % 8));
  }
  return d;
}

inline cv::Mat to_mat(const std::vector<Descriptor>& rows) {
  cv::Mat m(static_cast<int>(rows.size()), 32, CV_8UC1);
  for (int r = 0; r < m.rows; ++r) std::copy(rows[r].begin(), rows[r].end(), m.ptr<std::uint8_t>(r));
  return m;
}

// `per_centre` noisy copies (`flips` bits) of each centre, centre after centre.
inline cv::Mat clustered(const std::vector<Descriptor>& centres, int per_centre, int flips,
                         std::mt19937& rng) {
  std::vector<Descriptor> rows;
  for (const auto& c : centres) {
    for (int i = 0; i < per_centre; ++i) rows.push_back(noisy_copy(c, flips, rng));
  }
  return to_mat(rows);
}

}  // namespace crowdslam::bow::testing
