#pragma once
// Bag-of-words vectors and their similarity score.
//
// BowVector: word id -> TF-IDF weight, L1-normalised (weights sum to 1) by Vocabulary::transform.
// FeatureVector: the "direct index": vocabulary node id at the direct-index level -> indices of the
// features (descriptor rows) that descend through that node, in increasing order. Two frames' features
// that share a node are the candidates for descriptor matching.
#include <cstdint>
#include <map>
#include <vector>

namespace crowdslam::bow {

using WordId = std::uint32_t;
using NodeId = std::uint32_t;

using BowVector = std::map<WordId, double>;
using FeatureVector = std::map<NodeId, std::vector<unsigned>>;

// Divides every weight by the sum of absolute weights (no-op for an empty or all-zero vector).
void normalize_l1(BowVector& bow);

// L1 score of two L1-normalised vectors: 1 - 0.5 * sum_i |a_i - b_i|, in [0, 1] (1: identical,
// 0: no word in common), symmetric. Empty vectors score 0.
double l1_score(const BowVector& a, const BowVector& b);

}  // namespace crowdslam::bow
