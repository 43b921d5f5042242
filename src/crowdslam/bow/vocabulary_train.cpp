// Vocabulary training: hierarchical k-means++ (breadth first, so parents get smaller ids than their
// children) and IDF weights from the training images.
#include <cmath>
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

  // Level by level (parents in id order, so this is a breadth-first order): node ids increase with the
  // level, and one generator drives every k-means in that order.
  std::mt19937_64 rng(options.seed);
  std::vector<std::pair<NodeId, std::vector<std::size_t>>> current;
  std::vector<std::pair<NodeId, std::vector<std::size_t>>> next;
  std::vector<std::size_t> all(rows.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
  current.emplace_back(0, std::move(all));
  std::vector<const std::uint8_t*> subset;
  for (int depth = 0; depth < options.levels && !current.empty(); ++depth) {
    VocabularyTrainProgress progress{depth + 1, options.levels, 0, 0};
    for (const auto& node : current) progress.descriptors_total += node.second.size();
    for (auto& [node, members] : current) {
      progress.descriptors_done += members.size();
      if (members.size() > 1) {
        subset.clear();
        for (std::size_t m : members) subset.push_back(rows[m]);
        BinaryClusters clusters = kmeans_binary(subset, options.k, options.max_iterations, rng);
        if (clusters.centres.size() > 1) {  // else all members are identical: a leaf
          for (std::size_t c = 0; c < clusters.centres.size(); ++c) {
            const auto child = static_cast<NodeId>(voc.parent_.size());
            voc.parent_.push_back(node);
            voc.descriptors_.insert(voc.descriptors_.end(), clusters.centres[c].begin(),
                                    clusters.centres[c].end());
            voc.weight_.push_back(0.0f);
            std::vector<std::size_t> child_members;
            child_members.reserve(clusters.members[c].size());
            for (std::size_t s : clusters.members[c]) child_members.push_back(members[s]);
            next.emplace_back(child, std::move(child_members));
          }
        }
      }
      std::vector<std::size_t>().swap(members);
      if (options.progress) options.progress(progress);
    }
    current.swap(next);
    next.clear();
  }
  voc.finish("vocabulary training", true);
  const std::vector<float> weights = idf_weights(voc, descriptors_per_image);
  for (std::size_t w = 0; w < weights.size(); ++w) voc.weight_[voc.word_node_[w]] = weights[w];
  return voc;
}

}  // namespace crowdslam::bow
