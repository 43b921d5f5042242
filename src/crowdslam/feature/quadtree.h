#pragma once
// Spatial distribution of keypoints by quadtree (ORB-SLAM): the region is split into square-ish nodes,
// nodes holding more than one keypoint are split into four until there are as many nodes as wanted keypoints
// or no node can be split; each node then keeps its strongest keypoint (largest response).
#include <opencv2/core.hpp>
#include <vector>

namespace crowdslam::feature {

class QuadtreeDistributor {
 public:
  // Appends to `selected` at most `target` keypoints chosen from `candidates` (which is reordered).
  // `region` bounds the candidates' positions; candidates outside it are clamped into the edge nodes.
  // Keeps its scratch buffers between calls, so reuse one distributor per thread.
  void distribute(std::vector<cv::KeyPoint>& candidates, const cv::Rect2f& region, int target,
                  std::vector<cv::KeyPoint>& selected);

 private:
  struct Node {
    float x0, y0, x1, y1;  // [x0, x1) x [y0, y1)
    int begin, end;        // range of candidates inside
    int count() const { return end - begin; }
  };

  bool can_split(const Node& node) const;
  // Replaces nodes_[index] by its first non-empty child and appends the others; returns children added.
  int split(std::vector<cv::KeyPoint>& candidates, std::size_t index);
  void make_root_nodes(std::vector<cv::KeyPoint>& candidates, const cv::Rect2f& region);
  void split_all(std::vector<cv::KeyPoint>& candidates);
  void split_largest_first(std::vector<cv::KeyPoint>& candidates, std::size_t target);
  // Splitting the last node may overshoot the target by up to 3: drop that node's weakest children.
  void drop_overshoot(std::size_t target);

  std::size_t last_split_ = 0;  // node replaced by the last split's first child
  int last_split_added_ = 0;    // children the last split appended at the end of nodes_

  std::vector<Node> nodes_;
  std::vector<std::size_t> order_;
  std::vector<cv::KeyPoint> best_;
};

}  // namespace crowdslam::feature
