// The people stage's per-sensor defaults: which boxes mask keypoints (docs/CROWDS.md).
#include <gtest/gtest.h>

#include "crowdslam/io/settings.h"
#include "crowdslam/people/people_stage.h"
#include "test_support.h"

namespace crowdslam::people {
namespace {

bool masks_with_raw_boxes(io::SensorKind sensor, std::optional<bool> setting, const std::string& detections) {
  io::Settings settings;
  settings.detector.filter_before_nms = setting;
  PeopleStageOptions options;
  options.sensor = sensor;
  options.detections_file = detections;
  return PeopleStage(settings, options).filter_before_nms();
}

TEST(PeopleStageDefaults, OnlyRgbdMasksWithTheRawBoxesUnlessSet) {
  test::TempDir dir;
  test::write_text(dir / "det.txt", "1,-1,10,20,30,40,0.9,-1,-1,-1\n");
  const std::string det = (dir / "det.txt").string();
  // A depth camera gives the background in the raw boxes back (depth mode); stereo's depths are its
  // matched keypoints' only, and monocular has none.
  EXPECT_TRUE(masks_with_raw_boxes(io::SensorKind::kRgbd, std::nullopt, det));
  EXPECT_FALSE(masks_with_raw_boxes(io::SensorKind::kStereo, std::nullopt, det));
  EXPECT_FALSE(masks_with_raw_boxes(io::SensorKind::kMonocular, std::nullopt, det));
  // Detector.filter_before_nms wins on every sensor.
  EXPECT_TRUE(masks_with_raw_boxes(io::SensorKind::kStereo, true, det));
  EXPECT_TRUE(masks_with_raw_boxes(io::SensorKind::kMonocular, true, det));
  EXPECT_FALSE(masks_with_raw_boxes(io::SensorKind::kRgbd, false, det));
}

}  // namespace
}  // namespace crowdslam::people
