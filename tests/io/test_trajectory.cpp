#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "crowdslam/io/trajectory.h"
#include "crowdslam/util/error.h"
#include "test_support.h"

using namespace crowdslam;
using crowdslam::geometry::SE3;
using crowdslam::geometry::Vec3;
using crowdslam::io::StampedPose;
using crowdslam::io::Trajectory;
using crowdslam::io::TrajectoryFormat;
using crowdslam::test::TempDir;
using crowdslam::test::write_text;

namespace {

// A few poses with non-trivial rotations and translations.
Trajectory sample_trajectory() {
  Trajectory trajectory;
  for (int k = 0; k < 5; ++k) {
    const Eigen::Quaterniond q(Eigen::AngleAxisd(0.3 * k + 0.1, Vec3(1.0, 2.0, -0.5 * k).normalized()));
    trajectory.push_back(
        {1548339819.894270 + 0.033333 * k, SE3(q, Vec3(0.5 * k - 1.0, -2.25 + k, 3.125 * k))});
  }
  return trajectory;
}

// Rotation difference as an angle (quaternion sign does not matter).
double angle_between(const SE3& a, const SE3& b) { return a.rotation().angularDistance(b.rotation()); }

void expect_same_poses(const Trajectory& expected, const Trajectory& actual, double stamp_tolerance,
                       double value_tolerance) {
  ASSERT_EQ(expected.size(), actual.size());
  for (std::size_t k = 0; k < expected.size(); ++k) {
    EXPECT_NEAR(expected[k].timestamp_s, actual[k].timestamp_s, stamp_tolerance) << k;
    EXPECT_LT((expected[k].world_from_cam.translation() - actual[k].world_from_cam.translation()).norm(),
              value_tolerance)
        << k;
    EXPECT_LT(angle_between(expected[k].world_from_cam, actual[k].world_from_cam), value_tolerance) << k;
  }
}

// Expects read_tum_trajectory(path) to throw an InputError whose message contains `needle`.
template <typename Read>
void expect_input_error(Read read, const std::string& needle) {
  try {
    read();
    FAIL() << "expected InputError containing '" << needle << "'";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

}  // namespace

TEST(TumTrajectory, RoundTripKeepsPosesToWrittenPrecision) {
  TempDir dir;
  const std::string path = (dir / "t.txt").string();
  const Trajectory original = sample_trajectory();
  io::write_tum_trajectory(path, original);
  // 6 decimals on stamps (error <= 5e-7), 9 on pose values (error <= 5e-10 per value).
  expect_same_poses(original, io::read_tum_trajectory(path), 5e-7, 1e-8);
}

TEST(TumTrajectory, WriterUsesSixAndNineDecimalsAndNormalisesQuaternion) {
  TempDir dir;
  const std::string path = (dir / "t.txt").string();
  // 90 degrees about z: q = (w, x, y, z) = (cos 45, 0, 0, sin 45).
  const Eigen::Quaterniond q(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitZ()));
  io::write_tum_trajectory(path, {{12.5, SE3(q, Vec3(1.0, -2.0, 0.25))}});
  const std::string text = test::read_text(path);
  EXPECT_NE(text.find("12.500000 1.000000000 -2.000000000 0.250000000 0.000000000 0.000000000 0.707106781 "
                      "0.707106781\n"),
            std::string::npos)
      << text;
}

TEST(TumTrajectory, ReadsCommentsCommasTabsAndNormalisesQuaternion) {
  TempDir dir;
  const auto path = dir / "t.txt";
  write_text(path,
             "# timestamp tx ty tz qx qy qz qw\n"
             "\n"
             "1.0 1 2 3 0 0 0 2\n"
             "2.0,4,5,6,0,0,0,1\n"
             "3.0\t7\t8\t9\t0\t0\t1\t1\r\n");
  const Trajectory t = io::read_tum_trajectory(path.string());
  ASSERT_EQ(t.size(), 3u);
  EXPECT_EQ(t[0].timestamp_s, 1.0);
  EXPECT_EQ(t[0].world_from_cam.translation(), Vec3(1, 2, 3));
  EXPECT_NEAR(t[0].world_from_cam.rotation().w(), 1.0, 1e-15);  // (0,0,0,2) normalised to identity
  EXPECT_EQ(t[1].world_from_cam.translation(), Vec3(4, 5, 6));
  // qz = qw = 1 -> 90 degrees about z: maps x onto y.
  EXPECT_LT((t[2].world_from_cam.rotation_matrix() * Vec3::UnitX() - Vec3::UnitY()).norm(), 1e-12);
  EXPECT_EQ(t[2].world_from_cam.translation(), Vec3(7, 8, 9));
}

TEST(TumTrajectory, KeepsFileOrderAndDuplicates) {
  TempDir dir;
  const auto path = dir / "t.txt";
  write_text(path, "3 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n3 2 0 0 0 0 0 1\n");
  const Trajectory t = io::read_tum_trajectory(path.string());
  ASSERT_EQ(t.size(), 3u);
  EXPECT_EQ(t[0].timestamp_s, 3.0);
  EXPECT_EQ(t[1].timestamp_s, 1.0);
  EXPECT_EQ(t[2].world_from_cam.translation().x(), 2.0);
}

TEST(TumTrajectory, EmptyOrCommentOnlyFileGivesEmptyTrajectory) {
  TempDir dir;
  write_text(dir / "empty.txt", "");
  write_text(dir / "comments.txt", "# nothing\n\n# here\n");
  EXPECT_TRUE(io::read_tum_trajectory((dir / "empty.txt").string()).empty());
  EXPECT_TRUE(io::read_trajectory((dir / "comments.txt").string()).empty());
}

TEST(TumTrajectory, MalformedLinesNameFileAndLine) {
  TempDir dir;
  const std::string good = "1 0 0 0 0 0 0 1\n";
  const struct {
    const char* name;
    std::string bad_line;
    const char* message;
  } cases[] = {
      {"few.txt", "2 0 0 0 0 0 1\n", "too few fields"},
      {"word.txt", "2 0 0 abc 0 0 0 1\n", "non-numeric value 'abc'"},
      {"nan.txt", "2 0 nan 0 0 0 0 1\n", "non-finite value 'nan'"},
      {"inf.txt", "2 0 0 0 0 0 0 inf\n", "non-finite value 'inf'"},
      {"zeroq.txt", "2 1 2 3 0 0 0 0\n", "zero quaternion"},
  };
  for (const auto& c : cases) {
    const std::string path = (dir / c.name).string();
    write_text(path, "# header\n" + good + c.bad_line + good);
    expect_input_error([&] { io::read_tum_trajectory(path); }, path + ":3: " + c.message);
    expect_input_error([&] { io::read_trajectory(path); }, path + ":3: " + c.message);
  }
}

TEST(TumTrajectory, MissingFileIsInputErrorNamingFile) {
  expect_input_error([] { io::read_trajectory("/nonexistent/traj.txt"); }, "/nonexistent/traj.txt");
}

TEST(KittiTrajectory, RoundTripWithIndexStamps) {
  TempDir dir;
  const std::string path = (dir / "k.txt").string();
  const Trajectory original = sample_trajectory();
  io::write_kitti_trajectory(path, original);
  const Trajectory read = io::read_kitti_trajectory(path);
  ASSERT_EQ(read.size(), original.size());
  for (std::size_t k = 0; k < read.size(); ++k) {
    EXPECT_EQ(read[k].timestamp_s, static_cast<double>(k));
    EXPECT_LT((read[k].world_from_cam.translation() - original[k].world_from_cam.translation()).norm(), 1e-8);
    EXPECT_LT(angle_between(read[k].world_from_cam, original[k].world_from_cam), 1e-8);
  }
}

TEST(KittiTrajectory, RowMajorLayoutAndGivenStamps) {
  TempDir dir;
  const std::string path = (dir / "k.txt").string();
  // Rotation 90 degrees about z (columns: x -> y), translation (1, 2, 3).
  write_text(path, "0 -1 0 1 1 0 0 2 0 0 1 3\n1 0 0 0 0 1 0 0 0 0 1 0\n");
  const Trajectory t = io::read_kitti_trajectory(path, {10.5, 11.5});
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t[0].timestamp_s, 10.5);
  EXPECT_EQ(t[1].timestamp_s, 11.5);
  EXPECT_EQ(t[0].world_from_cam.translation(), Vec3(1, 2, 3));
  EXPECT_LT((t[0].world_from_cam.rotation_matrix() * Vec3::UnitX() - Vec3::UnitY()).norm(), 1e-12);
  expect_input_error([&] { io::read_kitti_trajectory(path, {1.0}); }, path + ": 2 poses but 1 timestamps");
}

TEST(KittiTrajectory, RejectsWrongFieldCountAndNonRotation) {
  TempDir dir;
  const std::string few = (dir / "few.txt").string();
  write_text(few, "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1\n");
  expect_input_error([&] { io::read_kitti_trajectory(few); }, few + ":2: too few fields");
  const std::string scaled = (dir / "scaled.txt").string();
  write_text(scaled, "2 0 0 0 0 2 0 0 0 0 2 0\n");
  expect_input_error([&] { io::read_kitti_trajectory(scaled); },
                     scaled + ":1: the 3x3 part is not a rotation");
  const std::string mirrored = (dir / "mirrored.txt").string();
  write_text(mirrored, "1 0 0 0 0 1 0 0 0 0 -1 0\n");
  expect_input_error([&] { io::read_kitti_trajectory(mirrored); },
                     mirrored + ":1: the 3x3 part is not a rotation");
}

TEST(EurocTrajectory, ReadsNanosecondStampsWxyzOrderAndIgnoresExtraColumns) {
  TempDir dir;
  const std::string path = (dir / "data.csv").string();
  write_text(path,
             "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z [],"
             "v_RS_R_x [m s^-1]\n"
             "1403715274312143104.0000000000,1,2,3,0.70710678118654752,0,0,0.70710678118654752,9\n"
             "1403715274362142976,4,5,6,1,0,0,0,9\n");
  const Trajectory t = io::read_euroc_trajectory(path);
  ASSERT_EQ(t.size(), 2u);
  // 1403715274 s + 312143104 ns; a double holds about 2.4e-7 s at this magnitude.
  EXPECT_NEAR(t[0].timestamp_s, 1403715274.312143104, 3e-7);
  EXPECT_NEAR(t[1].timestamp_s - t[0].timestamp_s, 0.049999872, 5e-7);
  EXPECT_EQ(t[0].world_from_cam.translation(), Vec3(1, 2, 3));
  EXPECT_LT((t[0].world_from_cam.rotation_matrix() * Vec3::UnitX() - Vec3::UnitY()).norm(), 1e-12);
  EXPECT_EQ(io::detect_trajectory_format(path), TrajectoryFormat::kEuroc);
}

TEST(EurocTrajectory, RoundTripWritesIntegerNanoseconds) {
  TempDir dir;
  const std::string path = (dir / "out.csv").string();
  Trajectory original = sample_trajectory();
  for (std::size_t k = 0; k < original.size(); ++k)
    original[k].timestamp_s = 0.25 * k + 1.5;  // exact in binary
  io::write_euroc_trajectory(path, original);
  const std::string text = test::read_text(path);
  EXPECT_EQ(text.rfind("#timestamp [ns]", 0), 0u);
  EXPECT_NE(text.find("\n1500000000,"), std::string::npos);
  EXPECT_NE(text.find("\n1750000000,"), std::string::npos);
  expect_same_poses(original, io::read_trajectory(path), 0.0, 1e-8);
}

TEST(EurocTrajectory, MalformedStampNamesLine) {
  TempDir dir;
  const std::string path = (dir / "data.csv").string();
  write_text(path, "#timestamp [ns],x,y,z,w,x,y,z\n1000,0,0,0,1,0,0,0\nabc,0,0,0,1,0,0,0\n");
  expect_input_error([&] { io::read_trajectory(path); }, path + ":3: non-numeric value 'abc'");
}

TEST(TrajectoryFormat, DetectedFromContent) {
  TempDir dir;
  write_text(dir / "tum.txt", "# t x y z qx qy qz qw\n1.5 0 0 0 0 0 0 1\n");
  write_text(dir / "tum_commas.txt", "1.5,0,0,0,0,0,0,1\n");
  write_text(dir / "kitti.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n");
  write_text(dir / "euroc_noheader.csv", "1403715274312143104,1,2,3,1,0,0,0\n");
  write_text(dir / "euroc_header.csv", "#timestamp [ns],x,y,z,w,x,y,z\n5,1,2,3,1,0,0,0\n");
  EXPECT_EQ(io::detect_trajectory_format((dir / "tum.txt").string()), TrajectoryFormat::kTum);
  EXPECT_EQ(io::detect_trajectory_format((dir / "tum_commas.txt").string()), TrajectoryFormat::kTum);
  EXPECT_EQ(io::detect_trajectory_format((dir / "kitti.txt").string()), TrajectoryFormat::kKitti);
  EXPECT_EQ(io::detect_trajectory_format((dir / "euroc_noheader.csv").string()), TrajectoryFormat::kEuroc);
  EXPECT_EQ(io::detect_trajectory_format((dir / "euroc_header.csv").string()), TrajectoryFormat::kEuroc);
  // read_trajectory dispatches accordingly: 5 ns -> 5e-9 s, KITTI stamps are line indices.
  EXPECT_DOUBLE_EQ(io::read_trajectory((dir / "euroc_header.csv").string())[0].timestamp_s, 5e-9);
  EXPECT_EQ(io::read_trajectory((dir / "kitti.txt").string())[0].timestamp_s, 0.0);
  EXPECT_EQ(io::read_trajectory((dir / "tum_commas.txt").string())[0].timestamp_s, 1.5);
}

TEST(TrajectoryFormat, KittiPosesTakeTheirStampsFromTimesTxtBesideThem) {
  TempDir dir;
  const std::string pose = "1 0 0 0 0 1 0 0 0 0 1 0\n";
  std::filesystem::create_directories(dir / "seq");
  write_text(dir / "seq" / "poses.txt", pose + pose + pose);
  write_text(dir / "seq" / "times.txt", "0.000000e+00\n1.036330e-01\n2.072460e-01\n");
  const Trajectory t = io::read_trajectory((dir / "seq" / "poses.txt").string());
  ASSERT_EQ(t.size(), 3u);
  EXPECT_DOUBLE_EQ(t[1].timestamp_s, 0.103633);
  EXPECT_DOUBLE_EQ(t[2].timestamp_s, 0.207246);
  // A times.txt that does not match the poses is an error naming both counts, not a silent mismatch.
  write_text(dir / "seq" / "times.txt", "0\n0.1\n");
  const std::string poses = (dir / "seq" / "poses.txt").string();
  expect_input_error([&] { io::read_trajectory(poses); }, poses + ": 3 poses but 2 timestamps");
}

TEST(TrajectoryFormat, WriteTrajectoryDispatchesAndReadBackMatches) {
  TempDir dir;
  const Trajectory original = sample_trajectory();
  for (TrajectoryFormat format :
       {TrajectoryFormat::kTum, TrajectoryFormat::kKitti, TrajectoryFormat::kEuroc}) {
    const std::string path = (dir / (std::string("t_") + io::to_string(format))).string();
    io::write_trajectory(path, original, format);
    EXPECT_EQ(io::detect_trajectory_format(path), format) << io::to_string(format);
    const Trajectory read = io::read_trajectory(path);
    ASSERT_EQ(read.size(), original.size());
    EXPECT_LT((read[3].world_from_cam.translation() - original[3].world_from_cam.translation()).norm(), 1e-8);
  }
}

TEST(TrajectoryWriter, UnwritableDirectoryIsInputErrorAndLeavesNoFile) {
  TempDir dir;
  const auto path = dir / "missing_dir" / "t.txt";
  EXPECT_THROW(io::write_tum_trajectory(path.string(), sample_trajectory()), InputError);
  EXPECT_FALSE(std::filesystem::exists(path));
}
