#include "crowdslam/tracking/frame_bow.h"

#include <memory>

namespace crowdslam::tracking {

void ensure_bow(map::Frame& frame, const bow::Vocabulary& vocabulary) {
  if (frame.features->has_bow() || frame.features->descriptors.empty() || vocabulary.empty()) return;
  auto features = std::make_shared<map::FrameFeatures>(*frame.features);
  vocabulary.transform(features->descriptors, features->bow, features->bow_features);
  frame.features = std::move(features);
}

std::shared_ptr<map::FrameFeatures> features_without(const map::FrameFeatures& in, const std::vector<bool>& drop,
                                                     std::vector<long>& new_index, const bow::Vocabulary* vocabulary) {
  auto out = std::make_shared<map::FrameFeatures>();
  new_index.assign(in.size(), -1);
  std::vector<int> rows;
  for (size_t i = 0; i < in.size(); ++i) {
    if (drop[i]) continue;
    new_index[i] = static_cast<long>(out->keys_un.size());
    rows.push_back(static_cast<int>(i));
    out->keys.push_back(in.keys[i]);
    out->keys_un.push_back(in.keys_un[i]);
    if (!in.right_u.empty()) out->right_u.push_back(in.right_u[i]);
    if (!in.depth_m.empty()) out->depth_m.push_back(in.depth_m[i]);
  }
  out->descriptors.create(static_cast<int>(rows.size()), in.descriptors.cols, in.descriptors.type());
  for (size_t k = 0; k < rows.size(); ++k) in.descriptors.row(rows[k]).copyTo(out->descriptors.row(static_cast<int>(k)));
  out->grid = map::FeatureGrid(out->keys_un, in.grid.bounds());
  if (vocabulary && !vocabulary->empty() && !out->descriptors.empty()) {
    vocabulary->transform(out->descriptors, out->bow, out->bow_features);
  }
  return out;
}

}  // namespace crowdslam::tracking
