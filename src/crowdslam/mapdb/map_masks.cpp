// count_points_on_masks (map_export.h): map points observed on moving pixels.
#include <cstdio>
#include <filesystem>
#include <set>

#include "crowdslam/io/image_check.h"
#include "crowdslam/map/keyframe.h"
#include "crowdslam/map/map.h"
#include "crowdslam/map/map_point.h"
#include "crowdslam/mapdb/map_database.h"
#include "crowdslam/mapdb/map_export.h"
#include "crowdslam/util/error.h"

namespace crowdslam::mapdb {

MaskCount count_points_on_masks(const std::filesystem::path& map_file, const std::filesystem::path& mask_dir) {
  const auto header = read_map_header(map_file);
  map::Map map;
  auto camera = std::make_shared<const geometry::PinholeCamera>(header.identity.camera);
  auto levels = std::make_shared<const map::ScaleLevels>(static_cast<float>(header.identity.orb_scale_factor),
                                                         header.identity.orb_levels);
  load_map(map_file, header.identity, map, camera, levels, nullptr);
  std::set<uint64_t> seen, on_mask;
  MaskCount count;
  for (const auto& kf : map.keyframes()) {
    char name[32];
    std::snprintf(name, sizeof name, "%06llu.png", static_cast<unsigned long long>(kf->frame_id));
    if (!std::filesystem::is_regular_file(mask_dir / name)) continue;
    const cv::Mat mask = io::read_mask_image((mask_dir / name).string());
    ++count.keyframes_with_mask;
    for (const auto& point : kf->valid_map_points()) {
      seen.insert(point->id);
      const long index = point->index_in(kf->id);
      if (index < 0) continue;
      const cv::Point2f p = kf->features->keys[static_cast<size_t>(index)].pt;
      const int x = cvRound(p.x), y = cvRound(p.y);
      if (x >= 0 && y >= 0 && x < mask.cols && y < mask.rows && mask.at<uint8_t>(y, x) > 0) on_mask.insert(point->id);
    }
  }
  if (count.keyframes_with_mask == 0) {
    throw input_error(mask_dir.string(), "no mask (NNNNNN.png by frame index) for any keyframe of " + map_file.string());
  }
  count.points_checked = seen.size();
  count.points_on_mask = on_mask.size();
  return count;
}

}  // namespace crowdslam::mapdb
