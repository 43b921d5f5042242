// Vocabulary training: hierarchical k-means++ (breadth first, so parents get smaller ids than their
// children) and IDF weights from the training images.
#include <cmath>
#include <deque>
#include <random>
#include <utility>

#include "crowdslam/bow/binary_kmeans.h"
#include "crowdslam/bow/vocabulary.h"
#include "crowdslam/util/error.h"

namespace crowdslam::bow {
namespace {

// IDF weight of every word: log(N / n_w) over the images with descriptors (n_w = 0 counts as 1).
std::vector<float> idf_weights(const Vocabulary& voc, const std::vector<cv::Mat>& per_image) {
  std::vector<std::uint32_t> images_with_word(voc.num_words(), 0);
  std::vector<std::uint32_t> last_image(voc.num_words(), 0);
  std::uint32_t num_images = 0;
  for (const cv::Mat& descriptors : per_image) {
    if (descriptors.rows == 0) continue;
    ++num_images;
    for (int r = 0; r < descriptors.rows; ++r) {
      const WordId word = voc.word_of(descriptors.ptr<std::uint8_t>(r));
      if (last_image[word] == num_images) continue;
      last_image[word] = num_images;
      ++images_with_word[word];
    }
  }
  std::vector<float> weights(voc.num_words());
  for (std::size_t w = 0; w < weights.size(); ++w) {
    const double n_w = std::max<std::uint32_t>(images_with_word[w], 1);
    weights[w] = static_cast<float>(std::log(num_images / n_w));
  }
  return weights;
}

}  // namespace

Vocabulary Vocabulary::train(const std::vector<cv::Mat>& descriptors_per_image,
                             const VocabularyTrainOptions& options) {
  options.check();
  std::vector<const std::uint8_t*> rows;
  for (const cv::Mat& descriptors : descriptors_per_image) {
    check_descriptors(descriptors);
    for (int r = 0; r < descriptors.rows; ++r) rows.push_back(descriptors.ptr<std::uint8_t>(r));
  }
  if (rows.empty()) throw InputError("vocabulary training: no descriptors to train on");

  Vocabulary voc;
  voc.k_ = options.k;
  voc.levels_ = options.levels;
  voc.parent_.push_back(kNoNode);
  voc.descriptors_.assign(feature::kDescriptorBytes, 0);
  voc.weight_.push_back(0.0f);
  std::vector<int> level{0};

  std::mt19937_64 rng(options.seed);
  std::deque<std::pair<NodeId, std::vector<std::size_t>>> queue;
  std::vector<std::size_t> all(rows.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
  queue.emplace_back(0, std::move(all));
  std::vector<const std::uint8_t*> subset;
  while (!queue.empty()) {
    const NodeId node = queue.front().first;
    const std::vector<std::size_t> members = std::move(queue.front().second);
    queue.pop_front();
    if (level[node] >= options.levels || members.size() <= 1) continue;
    subset.clear();
    for (std::size_t m : members) subset.push_back(rows[m]);
    BinaryClusters clusters = kmeans_binary(subset, options.k, options.max_iterations, rng);
    if (clusters.centres.size() <= 1) continue;  // all members identical: a leaf
    for (std::size_t c = 0; c < clusters.centres.size(); ++c) {
      const auto child = static_cast<NodeId>(voc.parent_.size());
      voc.parent_.push_back(node);
      voc.descriptors_.insert(voc.descriptors_.end(), clusters.centres[c].begin(), clusters.centres[c].end());
      voc.weight_.push_back(0.0f);
      level.push_back(level[node] + 1);
      std::vector<std::size_t> child_members;
      child_members.reserve(clusters.members[c].size());
      for (std::size_t s : clusters.members[c]) child_members.push_back(members[s]);
      queue.emplace_back(child, std::move(child_members));
    }
  }
  voc.finish("vocabulary training", true);
  const std::vector<float> weights = idf_weights(voc, descriptors_per_image);
  for (std::size_t w = 0; w < weights.size(); ++w) voc.weight_[voc.word_node_[w]] = weights[w];
  return voc;
}

}  // namespace crowdslam::bow
