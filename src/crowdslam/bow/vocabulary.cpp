#include "crowdslam/bow/vocabulary.h"

#include <algorithm>

#include "crowdslam/feature/descriptor.h"
#include "crowdslam/util/error.h"

namespace crowdslam::bow {

void VocabularyTrainOptions::check() const {
  const std::string where = "vocabulary training options";
  if (k < 2) throw input_error(where, "k must be at least 2, got " + std::to_string(k));
  if (levels < 1 || levels > 255) {
    throw input_error(where, "levels must be in [1, 255], got " + std::to_string(levels));
  }
  if (max_iterations < 1) {
    throw input_error(where, "max_iterations must be at least 1, got " + std::to_string(max_iterations));
  }
}

void Vocabulary::finish(const std::string& source, bool assign_words) {
  const std::size_t n = parent_.size();
  if (n == 0) throw input_error(source, "vocabulary has no nodes");
  if (k_ < 1) throw input_error(source, "branching factor k must be positive, got " + std::to_string(k_));
  if (levels_ < 1 || levels_ > 255) {
    throw input_error(source, "depth L must be in [1, 255], got " + std::to_string(levels_));
  }
  if (parent_[0] != kNoNode) throw input_error(source, "node 0 is not a root");
  // Children in CSR form by a counting sort on the parent (children stay in increasing id order).
  child_begin_.assign(n + 1, 0);
  for (std::size_t i = 1; i < n; ++i) {
    if (parent_[i] >= i) {
      throw input_error(source, "node " + std::to_string(i) + " has parent " + std::to_string(parent_[i]) +
                                    " (parents must come before their children)");
    }
    ++child_begin_[parent_[i] + 1];
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (static_cast<int>(child_begin_[i + 1]) > k_) {
      throw input_error(
          source, "node " + std::to_string(i) + " has more than k = " + std::to_string(k_) + " children");
    }
    child_begin_[i + 1] += child_begin_[i];
  }
  children_.resize(n - 1);
  std::vector<std::uint32_t> fill(child_begin_.begin(), child_begin_.end() - 1);
  level_.assign(n, 0);
  depth_ = 0;
  for (std::size_t i = 1; i < n; ++i) {
    children_[fill[parent_[i]]++] = static_cast<NodeId>(i);
    const int level = level_[parent_[i]] + 1;
    if (level > levels_) {
      throw input_error(source,
                        "node " + std::to_string(i) + " is deeper than L = " + std::to_string(levels_));
    }
    level_[i] = static_cast<std::uint8_t>(level);
    depth_ = std::max(depth_, level);
  }
  // Words: exactly the leaves.
  std::size_t num_leaves = 0;
  for (std::size_t i = 0; i < n; ++i) num_leaves += child_begin_[i] == child_begin_[i + 1];
  if (assign_words) word_id_.assign(n, kNoWord);
  word_node_.assign(num_leaves, kNoNode);
  WordId next_word = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const bool leaf = child_begin_[i] == child_begin_[i + 1];
    if (assign_words) {
      if (leaf) word_id_[i] = next_word++;
      if (!leaf) weight_[i] = 0.0f;
    } else if (leaf != (word_id_[i] != kNoWord)) {
      throw input_error(source, "node " + std::to_string(i) +
                                    (leaf ? " is a leaf without a word id" : " has children and a word id"));
    }
    if (!leaf) continue;
    const WordId word = word_id_[i];
    if (word >= num_leaves || word_node_[word] != kNoNode) {
      throw input_error(source, "node " + std::to_string(i) + " has an invalid or repeated word id " +
                                    std::to_string(word));
    }
    word_node_[word] = static_cast<NodeId>(i);
  }
}

WordId Vocabulary::word_of(const std::uint8_t* descriptor, NodeId* direct_node, int direct_level) const {
  NodeId node = 0;
  if (direct_node != nullptr && direct_level <= 0) *direct_node = 0;
  while (child_begin_[node] != child_begin_[node + 1]) {
    NodeId best = kNoNode;
    int best_distance = 1 << 30;
    for (const NodeId* c = children_begin(node); c != children_end(node); ++c) {
      const int d = feature::hamming_distance(descriptor, node_descriptor(*c));
      if (d < best_distance) {
        best_distance = d;
        best = *c;
      }
    }
    node = best;
    if (direct_node != nullptr && level_[node] == direct_level) *direct_node = node;
  }
  // A path shorter than the direct level ends at its word.
  if (direct_node != nullptr && level_[node] < direct_level) *direct_node = node;
  return word_id_[node];
}

int Vocabulary::direct_index_level(int levels_up) const { return std::clamp(depth_ - levels_up, 0, depth_); }

void check_descriptors(const cv::Mat& descriptors) {
  if (descriptors.empty()) return;
  if (descriptors.type() != CV_8UC1 || descriptors.cols != feature::kDescriptorBytes) {
    throw InputError("vocabulary: descriptors must be CV_8UC1 with 32 columns, got type " +
                     std::to_string(descriptors.type()) + " with " + std::to_string(descriptors.cols) +
                     " columns");
  }
}

void Vocabulary::transform(const cv::Mat& descriptors, BowVector& bow) const {
  bow.clear();
  check_descriptors(descriptors);
  if (empty()) return;
  for (int r = 0; r < descriptors.rows; ++r) {
    const WordId word = word_of(descriptors.ptr<std::uint8_t>(r));
    const double weight = weight_[word_node_[word]];
    if (weight > 0.0) bow[word] += weight;
  }
  normalize_l1(bow);
}

void Vocabulary::transform(const cv::Mat& descriptors, BowVector& bow, FeatureVector& features,
                           int levels_up) const {
  bow.clear();
  features.clear();
  check_descriptors(descriptors);
  if (empty()) return;
  const int direct_level = direct_index_level(levels_up);
  for (int r = 0; r < descriptors.rows; ++r) {
    NodeId direct_node = 0;
    const WordId word = word_of(descriptors.ptr<std::uint8_t>(r), &direct_node, direct_level);
    const double weight = weight_[word_node_[word]];
    if (weight > 0.0) bow[word] += weight;
    features[direct_node].push_back(static_cast<unsigned>(r));
  }
  normalize_l1(bow);
}

}  // namespace crowdslam::bow
