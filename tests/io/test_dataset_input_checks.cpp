// Dataset readers on bad input (issue 10): list files given as the dataset, path errors per entry,
// duplicated and out-of-range stamps, unpaired stereo frames, no colour/depth pair, frame size changes.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "crowdslam/io/dataset.h"
#include "crowdslam/io/euroc_dataset.h"
#include "log_capture.h"
#include "test_dataset_helpers.h"

namespace crowdslam::io {
namespace {

namespace fs = std::filesystem;
using test::error_of;
using test::TempDir;
using test::write_text;

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(OpenSourceInput, ListFileGivenAsTheDatasetAsksForTheDirectory) {
  TempDir dir;
  test::make_tum(dir.path(), {0.0, 1.0}, {0.0, 1.0});
  const std::string list = (dir / "rgb.txt").string();
  const std::string message = error_of([&] { (void)open_source(list); });
  EXPECT_NE(message.find(list + ": is a list file"), std::string::npos) << message;
  EXPECT_TRUE(contains(message, "pass the dataset directory")) << message;
  EXPECT_TRUE(contains(message, dir.path().string())) << message;  // the parent, to pass instead
  // Other text files too, whatever their name.
  write_text(dir / "settings.yaml", "%YAML:1.0\nCamera.fx: 500\n");
  write_text(dir / "notes", "just some text\nin a file without extension\n");
  for (const char* name : {"settings.yaml", "notes"}) {
    const std::string m = error_of([&] { (void)open_source((dir / name).string()); });
    EXPECT_TRUE(contains(m, "is a text file")) << m;
    EXPECT_TRUE(contains(m, "pass the dataset directory")) << m;
  }
  EXPECT_EQ(open_source(dir.path().string())->layout(), "tum");  // the directory itself still opens
}

TEST(DatasetPathErrors, NameTooLongInTheListNamesListLineAndIsClipped) {
  TempDir dir;
  test::make_tum(dir.path(), {0.0}, {});
  const std::string long_name(2 * 1024 * 1024, 'x');  // 2 MB: one such message used to be 2 MB long
  write_text(dir / "rgb.txt", "# colour\n0.0 rgb/0.png\n1.0 rgb/" + long_name + ".png\n");
  const std::string message = error_of([&] { (void)open_dataset(dir.path().string()); });
  EXPECT_TRUE(contains(message, (dir / "rgb.txt").string() + ":3: listed image ")) << message.substr(0, 400);
  EXPECT_TRUE(contains(message, "File name too long")) << message.substr(0, 400);
  EXPECT_LT(message.size(), 1000u);
}

TEST(DatasetPathErrors, SymlinkLoopNamesListLineAndReason) {
  TempDir dir;
  test::make_tum(dir.path(), {0.0}, {0.0});
  fs::create_symlink("b.png", dir / "rgb" / "a.png");
  fs::create_symlink("a.png", dir / "rgb" / "b.png");
  write_text(dir / "rgb.txt", "0.0 rgb/0.png\n0.5 rgb/a.png\n");
  const std::string message = error_of([&] { (void)open_dataset(dir.path().string()); });
  EXPECT_TRUE(
      contains(message, (dir / "rgb.txt").string() + ":2: listed image " + (dir / "rgb/a.png").string()))
      << message;
  EXPECT_TRUE(contains(message, "Too many levels of symbolic links")) << message;
}

TEST(DatasetPathErrors, SymlinkLoopInEurocKittiAndImageFolders) {
  TempDir euroc;
  fs::create_directories(euroc / "mav0/cam0/data");
  fs::create_symlink("2.png", euroc / "mav0/cam0/data/1.png");
  fs::create_symlink("1.png", euroc / "mav0/cam0/data/2.png");
  write_text(euroc / "mav0/cam0/data.csv", "#timestamp [ns],filename\n1000,1.png\n");
  std::string message = error_of([&] { (void)open_dataset(euroc.path().string()); });
  EXPECT_TRUE(contains(message, "cam0/data.csv:2: listed image ")) << message;
  EXPECT_TRUE(contains(message, "Too many levels of symbolic links")) << message;

  TempDir kitti;
  fs::create_directories(kitti / "image_0");
  fs::create_symlink("000001.png", kitti / "image_0/000000.png");
  fs::create_symlink("000000.png", kitti / "image_0/000001.png");
  write_text(kitti / "times.txt", "0.0\n");
  write_text(kitti / "calib.txt", "P0: 700 0 600 0 0 710 180 0 0 0 1 0\n");
  message = error_of([&] { (void)open_dataset(kitti.path().string()); });
  EXPECT_TRUE(contains(message, "times.txt:1: listed image ")) << message;
  EXPECT_TRUE(contains(message, "Too many levels of symbolic links")) << message;

  TempDir folder;
  test::write_colour(folder / "a.png", 1);
  fs::create_symlink("c.png", folder / "b.png");
  fs::create_symlink("b.png", folder / "c.png");
  message = error_of([&] { (void)open_dataset(folder.path().string()); });
  EXPECT_TRUE(contains(message, (folder / "b.png").string()) ||
              contains(message, (folder / "c.png").string()))
      << message;
  EXPECT_TRUE(contains(message, "Too many levels of symbolic links")) << message;
}

TEST(DatasetPathErrors, HugeListLineIsClippedInTheMessage) {
  TempDir dir;
  write_text(dir / "rgb.txt", std::string(2 * 1024 * 1024, '7') + "\n");
  const std::string message = error_of([&] { (void)open_dataset(dir.path().string()); });
  EXPECT_TRUE(contains(message, "rgb.txt:1: expected 'timestamp filename'")) << message.substr(0, 400);
  EXPECT_TRUE(contains(message, "...")) << message.substr(0, 400);
  EXPECT_LT(message.size(), 1000u);
}

TEST(DatasetStamps, DuplicatedStampsAreSkippedWithOneWarningNamingTheFirstRepeat) {
  TempDir dir;
  test::make_tum(dir.path(), {0.0, 1.0, 2.0, 3.0}, {0.0, 1.0, 2.0, 3.0});
  // Lines 3 and 4 repeat 0.0 and 1.0 (both later entries win, as TUM's associate.py).
  write_text(dir / "rgb.txt", "# colour\n0.0 rgb/0.png\n0.0 rgb/1.png\n1.0 rgb/2.png\n1.0 rgb/3.png\n");
  test::LogCapture log;
  const auto dataset = open_dataset(dir.path().string());
  ASSERT_EQ(dataset->size(), 2u);
  EXPECT_EQ(fs::path(dataset->frame_info(0).colour_path).filename(), "1.png");
  EXPECT_EQ(fs::path(dataset->frame_info(1).colour_path).filename(), "3.png");
  EXPECT_EQ(dataset->summary().colour_entries, 4u);
  const auto warnings = log.warnings();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_TRUE(contains(warnings[0], (dir / "rgb.txt").string() + ":3: 2 entries repeat a time stamp"))
      << warnings[0];
  EXPECT_TRUE(contains(warnings[0], "line 2")) << warnings[0];
}

TEST(DatasetStamps, MonocularListsAreDedupedToo) {
  TempDir dir;
  test::make_tum(dir.path(), {0.0, 0.0, 1.0}, {});
  test::LogCapture log;
  EXPECT_EQ(open_dataset(dir.path().string())->size(), 2u);  // used to be 3 frames, two at t = 0
  EXPECT_EQ(log.warnings().size(), 1u);
}

TEST(DatasetStamps, HugeNegativeAndNonFiniteStampsNameFileAndLine) {
  for (const char* stamp : {"1e300", "-0.5", "inf", "nan"}) {
    SCOPED_TRACE(stamp);
    TempDir dir;
    test::make_tum(dir.path(), {0.0}, {0.0});
    write_text(dir / "depth.txt", std::string("# depth\n") + stamp + " depth/0.png\n");
    const std::string message = error_of([&] { (void)open_dataset(dir.path().string()); });
    EXPECT_TRUE(contains(message, (dir / "depth.txt").string() + ":2: timestamp '" + stamp + "'")) << message;
  }
  TempDir kitti;
  test::write_grey(kitti / "image_0/000000.png", 0);
  write_text(kitti / "times.txt", "1e300\n");
  write_text(kitti / "calib.txt", "P0: 700 0 600 0 0 710 180 0 0 0 1 0\n");
  EXPECT_TRUE(
      contains(error_of([&] { (void)open_dataset(kitti.path().string()); }), "times.txt:1: timestamp"));
}

TEST(DatasetStamps, NoColourDepthPairIsAnErrorNamingBothLists) {
  TempDir dir;
  test::make_tum(dir.path(), {0.0, 1.0}, {100.0, 101.0});
  const std::string message = error_of([&] { (void)open_dataset(dir.path().string()); });
  EXPECT_TRUE(contains(message, (dir / "rgb.txt").string() + ": no colour image has a depth map in " +
                                    (dir / "depth.txt").string()))
      << message;
  EXPECT_TRUE(contains(message, "100.000000")) << message;  // the depth time span
}

void make_euroc_lists(const fs::path& dir, int left, int right) {
  const std::string yaml =
      "%YAML:1.0\nT_BS:\n  cols: 4\n  rows: 4\n  data: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, "
      "1.0, "
      "0.0, 0.0, 0.0, 0.0, 1.0]\nrate_hz: 20\nresolution: [8, 6]\nintrinsics: [400.0, 401.0, 4.0, 3.0]\n"
      "distortion_model: radial-tangential\ndistortion_coefficients: [0.0, 0.0, 0.0, 0.0]\n";
  for (const auto& [cam, count] : {std::pair{"cam0", left}, {"cam1", right}}) {
    std::string csv = "#timestamp [ns],filename\n";
    for (int i = 0; i < count; ++i) {
      const std::string name = std::to_string(1000 + i) + ".png";
      test::write_grey(dir / "mav0" / cam / "data" / name, i);
      csv += std::to_string(1000 + i) + "," + name + "\n";
    }
    write_text(dir / "mav0" / cam / "data.csv", csv);
    write_text(dir / "mav0" / cam / "sensor.yaml", yaml);
  }
}

TEST(EurocStereo, ShorterRightListSkipsLeftFramesWithOneWarning) {
  TempDir dir;
  make_euroc_lists(dir.path(), 95, 49);
  test::LogCapture log;
  const auto dataset = open_dataset(dir.path().string());
  EXPECT_EQ(dataset->size(), 49u);
  const auto warnings = log.warnings();
  ASSERT_EQ(warnings.size(), 1u);
  // First unpaired left frame: stamp 1049 on line 51 of cam0/data.csv (header on line 1).
  EXPECT_TRUE(contains(warnings[0], "cam0/data.csv:51: 46 of 95 left images have no right image"))
      << warnings[0];
}

TEST(EurocStereo, EqualListsGiveNoWarning) {
  TempDir dir;
  make_euroc_lists(dir.path(), 5, 5);
  test::LogCapture log;
  EXPECT_EQ(open_dataset(dir.path().string())->size(), 5u);
  EXPECT_TRUE(log.warnings().empty());
}

TEST(DatasetFrameSize, ColourFrameOfAnotherSizeNamesTheColourFileAndTheFirstFrame) {
  TempDir dir;
  test::make_tum(dir.path(), {0.0, 1.0, 2.0}, {0.0, 1.0, 2.0});
  test::write_colour(dir / "rgb/1.png", 1, {4, 3});  // depth/1.png keeps the first frame's 8x6
  for (const bool in_order : {true, false}) {
    SCOPED_TRACE(in_order);
    const auto dataset = open_dataset(dir.path().string());
    if (in_order) {
      EXPECT_NO_THROW((void)dataset->load(0));
    }
    const std::string message = error_of([&] { (void)dataset->load(1); });
    EXPECT_TRUE(contains(message, (dir / "rgb/1.png").string() +
                                      ": colour image is 4x3, but the first frame's (" +
                                      (dir / "rgb/0.png").string() + ") is 8x6"))
        << message;
    EXPECT_FALSE(contains(message, "depth")) << message;
    EXPECT_NO_THROW((void)dataset->load(2));
  }
}

TEST(DatasetFrameSize, ImageFoldersMayHoldImagesOfAnySize) {
  TempDir dir;
  test::write_colour(dir / "a.png", 1, {8, 6});
  test::write_colour(dir / "b.png", 2, {16, 4});  // e.g. photos for vocabulary training
  const auto dataset = open_dataset(dir.path().string());
  EXPECT_EQ(dataset->load(0).colour.size(), cv::Size(8, 6));
  EXPECT_EQ(dataset->load(1).colour.size(), cv::Size(16, 4));
}

}  // namespace
}  // namespace crowdslam::io
