#pragma once
// The people filter scored against the dataset's person masks (`crowdslam run --score-filter`): for every
// frame with a mask (DIR/NNNNNN.png by frame index, non-zero where a person is, as `crowdslam synth`
// writes people_mask/), the keypoints the filter kept and removed, each counted as on a person, on a
// person's edge (background within kEdgeRadiusPx of a person pixel: the middle of the ORB patch sees the
// person, so the descriptor moves with them; the filter's silhouette rule drops these) or on the clear
// background. The detector's and the filter's share of a crowd's error, measured without the rest of
// SLAM's run-to-run spread: keypoints kept on people are what tracking may follow as they move; background
// removed is what it lost. The counts go to run.json `people_masks` (with or without the filter).
#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "crowdslam/system/run_observer.h"

namespace crowdslam::run {

inline constexpr int kEdgeRadiusPx = 8;

struct FilterMaskCounts {
  size_t frames_scored = 0;
  size_t frames_without_mask = 0;  // no DIR/NNNNNN.png for the frame (counted, not scored)
  size_t kept_on_people = 0;
  size_t kept_on_edges = 0;
  size_t kept_on_background = 0;
  size_t removed_on_people = 0;
  size_t removed_on_edges = 0;
  size_t removed_on_background = 0;
  size_t outside_mask = 0;  // keypoints outside the mask's image (a mask of another size)
};

class FilterMaskScore : public system::RunObserver {
 public:
  // Throws InputError when `mask_dir` is not a directory.
  explicit FilterMaskScore(std::filesystem::path mask_dir);
  // Needs the frame's kept and removed keypoints (SystemOptions::record_keypoints). Reads the mask
  // (a PNG decode on the tracking thread, about a millisecond at 640 x 480).
  void on_frame(const system::FrameReport& report, const std::optional<geometry::SE3>& world_from_cam,
                const io::FrameImages& images) override;
  [[nodiscard]] const FilterMaskCounts& counts() const { return counts_; }
  // The counts and their ratios: the share of the people's keypoints removed (`people_removed`), of the
  // clear background's kept (`background_kept`), and of the kept keypoints on people or their edges
  // (`kept_on_people_share`).
  [[nodiscard]] nlohmann::json to_json() const;

 private:
  std::filesystem::path mask_dir_;
  FilterMaskCounts counts_;
};

}  // namespace crowdslam::run
