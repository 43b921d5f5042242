#include "crowdslam/feature/quadtree.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <functional>

namespace crowdslam::feature {
namespace {

using KeyPointIt = std::vector<cv::KeyPoint>::iterator;

KeyPointIt partition_x(KeyPointIt first, KeyPointIt last, float x) {
  return std::partition(first, last, [x](const cv::KeyPoint& k) { return k.pt.x < x; });
}

KeyPointIt partition_y(KeyPointIt first, KeyPointIt last, float y) {
  return std::partition(first, last, [y](const cv::KeyPoint& k) { return k.pt.y < y; });
}

}  // namespace

bool QuadtreeDistributor::can_split(const Node& node) const {
  // Nodes below one pixel cannot separate integer FAST positions any further (guards duplicates).
  return node.count() > 1 && (node.x1 - node.x0 >= 1.f || node.y1 - node.y0 >= 1.f);
}

int QuadtreeDistributor::split(std::vector<cv::KeyPoint>& candidates, std::size_t index) {
  const Node node = nodes_[index];
  const float xm = 0.5f * (node.x0 + node.x1);
  const float ym = 0.5f * (node.y0 + node.y1);
  const auto first = candidates.begin() + node.begin;
  const auto last = candidates.begin() + node.end;
  const auto y_split = partition_y(first, last, ym);
  const auto top_split = partition_x(first, y_split, xm);
  const auto bottom_split = partition_x(y_split, last, xm);
  const auto offset = [&](KeyPointIt it) { return static_cast<int>(it - candidates.begin()); };
  const Node children[4] = {
      {node.x0, node.y0, xm, ym, node.begin, offset(top_split)},
      {xm, node.y0, node.x1, ym, offset(top_split), offset(y_split)},
      {node.x0, ym, xm, node.y1, offset(y_split), offset(bottom_split)},
      {xm, ym, node.x1, node.y1, offset(bottom_split), node.end},
  };
  bool replaced = false;
  int added = 0;
  for (const Node& child : children) {
    if (child.count() == 0) continue;
    if (!replaced) {
      nodes_[index] = child;
      replaced = true;
    } else {
      nodes_.push_back(child);
      ++added;
    }
  }
  return added;
}

void QuadtreeDistributor::make_root_nodes(std::vector<cv::KeyPoint>& candidates, const cv::Rect2f& region) {
  // Roughly square roots: as many side by side as the region's aspect ratio.
  const int num_roots =
      std::max(1, static_cast<int>(std::lround(region.width / std::max(region.height, 1e-3f))));
  const float root_width = region.width / static_cast<float>(num_roots);
  auto first = candidates.begin();
  for (int i = 0; i < num_roots; ++i) {
    const float x0 = region.x + root_width * static_cast<float>(i);
    const bool last_root = i + 1 == num_roots;
    const auto last = last_root ? candidates.end() : partition_x(first, candidates.end(), x0 + root_width);
    const Node node{x0,
                    region.y,
                    x0 + root_width,
                    region.y + region.height,
                    static_cast<int>(first - candidates.begin()),
                    static_cast<int>(last - candidates.begin())};
    if (node.count() > 0) nodes_.push_back(node);
    first = last;
  }
}

void QuadtreeDistributor::split_all(std::vector<cv::KeyPoint>& candidates) {
  const std::size_t num_nodes = nodes_.size();
  for (std::size_t i = 0; i < num_nodes; ++i) {
    if (can_split(nodes_[i])) split(candidates, i);
  }
}

void QuadtreeDistributor::split_largest_first(std::vector<cv::KeyPoint>& candidates, std::size_t target) {
  order_.clear();
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    if (can_split(nodes_[i])) order_.push_back(i);
  }
  std::stable_sort(order_.begin(), order_.end(),
                   [this](std::size_t a, std::size_t b) { return nodes_[a].count() > nodes_[b].count(); });
  for (const std::size_t index : order_) {
    last_split_ = index;
    last_split_added_ = split(candidates, index);
    if (nodes_.size() >= target) return;
  }
}

void QuadtreeDistributor::distribute(std::vector<cv::KeyPoint>& candidates, const cv::Rect2f& region,
                                     int target, std::vector<cv::KeyPoint>& selected) {
  if (target <= 0 || candidates.empty()) return;
  const auto wanted = static_cast<std::size_t>(target);
  nodes_.clear();
  make_root_nodes(candidates, region);

  while (nodes_.size() < wanted) {
    std::size_t splittable = 0;
    for (const Node& node : nodes_) splittable += can_split(node) ? 1 : 0;
    if (splittable == 0) break;
    // A full round adds at most three nodes per split; split by size only when that could overshoot.
    if (nodes_.size() + 3 * splittable <= wanted) {
      split_all(candidates);
    } else {
      split_largest_first(candidates, wanted);
    }
  }

  best_.clear();
  for (const Node& node : nodes_) {
    const auto first = candidates.begin() + node.begin;
    const auto last = candidates.begin() + node.end;
    best_.push_back(*std::max_element(
        first, last, [](const cv::KeyPoint& a, const cv::KeyPoint& b) { return a.response < b.response; }));
  }
  if (best_.size() > wanted) drop_overshoot(wanted);
  selected.insert(selected.end(), best_.begin(), best_.end());
}

void QuadtreeDistributor::drop_overshoot(std::size_t target) {
  // Only a size-ordered split can overshoot, and only by its own children (a full round never does).
  const std::size_t excess = best_.size() - target;
  const std::size_t first_appended = best_.size() - static_cast<std::size_t>(last_split_added_);
  assert(excess <= static_cast<std::size_t>(last_split_added_));
  order_.clear();
  order_.push_back(last_split_);
  for (std::size_t i = first_appended; i < best_.size(); ++i) order_.push_back(i);
  std::sort(order_.begin(), order_.end(),
            [this](std::size_t a, std::size_t b) { return best_[a].response < best_[b].response; });
  order_.resize(excess);
  // Remove the weakest children, highest index first so that the remaining indices stay valid.
  std::sort(order_.begin(), order_.end(), std::greater<>());
  for (const std::size_t index : order_) best_.erase(best_.begin() + static_cast<std::ptrdiff_t>(index));
}

}  // namespace crowdslam::feature
