#pragma once
// Vocabulary tree of 256-bit ORB descriptors (bag of binary words, of the DBoW2 kind; our own code).
//
// Node 0 is the root; every other node has a parent with a smaller id, a 32-byte descriptor (the
// bitwise-majority centre of its cluster) and, when it has no children, is a word with an IDF weight
// (log(N_images / n_images_containing_word) over the training images). Word ids number the leaves in
// increasing node-id order. A descriptor's word is found by descending from the root, at each level
// taking the child at the smallest Hamming distance (ties: lower node id).
//
// Storage is flat (structure of arrays, children in one CSR array), so loading a 1M-word binary file is
// one read and a few linear passes, with no per-node allocation.
//
// Binary file format (little-endian), see vocabulary_io.cpp:
//   header (32 bytes): magic "CSLMVOC1" (8), version u32 = 1, descriptor bytes u32 = 32, k u32,
//                      L u32, node count u64;
//   then per node (44 bytes): parent u32 (0xFFFFFFFF for the root), descriptor 32 bytes,
//                      weight f32, word id u32 (0xFFFFFFFF for inner nodes).
#include <cstddef>
#include <cstdint>
#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "crowdslam/bow/bow_vector.h"

namespace crowdslam::bow {

inline constexpr std::uint32_t kNoNode = 0xFFFFFFFFu;
inline constexpr std::uint32_t kNoWord = 0xFFFFFFFFu;
// Default direct-index level, counted up from the leaves. ORB-SLAM2 indexes its 6-level tree 4 levels up,
// i.e. at level 2 (100 nodes for k = 10); with our default 5-level tree 3 levels up is that same level
// (4 would leave 10 groups, too coarse to speed up matching).
inline constexpr int kDefaultLevelsUp = 3;

// Where training is: `level` (1..L) is the tree level being built, `descriptors_done` of
// `descriptors_total` the descriptors whose node at that level has been clustered.
struct VocabularyTrainProgress {
  int level = 0;
  int levels = 0;
  std::size_t descriptors_done = 0;
  std::size_t descriptors_total = 0;
};

struct VocabularyTrainOptions {
  int k = 10;               // branching factor
  int levels = 6;           // depth L (levels below the root)
  std::uint64_t seed = 1;   // k-means++ seeding; same seed and data give the same vocabulary
  int max_iterations = 10;  // Lloyd iterations per k-means
  // Called on the training thread after each tree node is clustered (or found to be a leaf); may be empty.
  std::function<void(const VocabularyTrainProgress&)> progress;
  // Throws InputError naming the bad option and its value.
  void check() const;
};

// Throws InputError unless `descriptors` is empty or CV_8UC1 with 32 columns.
void check_descriptors(const cv::Mat& descriptors);

class Vocabulary {
 public:
  Vocabulary() = default;

  // Hierarchical k-means++ on the descriptors of all images (each CV_8UC1, N x 32), then IDF weights
  // from the same images (images without descriptors are not counted). Throws InputError for bad
  // options, wrong descriptor matrices or no descriptors at all.
  static Vocabulary train(const std::vector<cv::Mat>& descriptors_per_image,
                          const VocabularyTrainOptions& options = {});

  // Our binary format. load() throws InputError naming the file when it is missing, truncated, of
  // another format (magic), version or descriptor length, or not a consistent tree.
  void save(const std::string& path) const;
  static Vocabulary load(const std::string& path);
  // DBoW2 / ORB-SLAM2 text format ("k L scoring weighting", then "parent is_leaf d0 .. d31 weight" per
  // node). Only L1-norm scoring with TF-IDF weighting (0 0, as in ORBvoc.txt) is accepted. Errors name
  // the file and line.
  static Vocabulary import_dbow2_text(const std::string& path);
  // load() for a file starting with our magic, import_dbow2_text() otherwise.
  static Vocabulary read(const std::string& path);

  // Bag of words of the descriptors (CV_8UC1, N x 32; empty gives empty vectors): TF-IDF weights,
  // L1-normalised (words of weight 0 are left out). `features` maps the node at
  // direct_index_level(levels_up) on each descriptor's path (its word if the path is shorter) to the
  // descriptor rows. Throws InputError for a non-empty matrix of another type or width.
  void transform(const cv::Mat& descriptors, BowVector& bow) const;
  void transform(const cv::Mat& descriptors, BowVector& bow, FeatureVector& features,
                 int levels_up = kDefaultLevelsUp) const;

  // Word of one 32-byte descriptor; also the node at `direct_level` on its path (if not null).
  WordId word_of(const std::uint8_t* descriptor, NodeId* direct_node = nullptr, int direct_level = 0) const;

  // Direct-index level for `levels_up` levels above the leaves: depth() - levels_up clamped to
  // [0, depth()], so it is never deeper than the tree (0 = the root: one group of all features).
  int direct_index_level(int levels_up) const;

  bool empty() const { return parent_.empty(); }
  int k() const { return k_; }
  int levels() const { return levels_; }  // L of the file / training options
  int depth() const { return depth_; }    // deepest leaf level actually present
  std::size_t num_nodes() const { return parent_.size(); }
  std::size_t num_words() const { return word_node_.size(); }

  NodeId parent(NodeId node) const { return parent_[node]; }
  int node_level(NodeId node) const { return level_[node]; }
  const std::uint8_t* node_descriptor(NodeId node) const { return &descriptors_[32 * std::size_t{node}]; }
  NodeId word_node(WordId word) const { return word_node_[word]; }
  float word_weight(WordId word) const { return weight_[word_node_[word]]; }
  // Children of `node`, increasing ids.
  const NodeId* children_begin(NodeId node) const { return children_.data() + child_begin_[node]; }
  const NodeId* children_end(NodeId node) const { return children_.data() + child_begin_[node + 1]; }

 private:
  // With k_, levels_, parent_, descriptors_ and weight_ filled (and word_id_ unless assign_words):
  // builds children, levels and the word list and checks the tree (root first, parents before children,
  // words exactly at the leaves, unique word ids, at most k children, depth <= L). assign_words numbers
  // the leaves in node-id order. Throws InputError naming `source` when inconsistent.
  void finish(const std::string& source, bool assign_words);

  int k_ = 0;
  int levels_ = 0;
  int depth_ = 0;
  std::vector<NodeId> parent_;
  std::vector<std::uint8_t> descriptors_;  // 32 bytes per node
  std::vector<float> weight_;              // IDF weight of words, 0 for inner nodes
  std::vector<WordId> word_id_;            // kNoWord for inner nodes
  std::vector<std::uint8_t> level_;
  std::vector<std::uint32_t> child_begin_;  // num_nodes + 1 offsets into children_
  std::vector<NodeId> children_;
  std::vector<NodeId> word_node_;
};

}  // namespace crowdslam::bow
