// `crowdslam eval ate|rpe`: exit codes, human and JSON output, error messages.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "crowdslam/util/text.h"
#include "test_support.h"

using crowdslam::test::run_cli;
using crowdslam::test::TempDir;
using crowdslam::test::write_text;

namespace {

// A non-planar path of `count` positions at stamps first + k * step.
struct Point {
  double x, y, z;
};
Point path_point(int k) { return {std::cos(0.5 * k) * (1.0 + 0.1 * k), std::sin(0.5 * k), 0.3 * k}; }

// TUM text; the position of pose k is path_point(k) * position_scale + shift, identity orientation.
std::string tum_text(int count, double step, double first, double position_scale, Point shift) {
  std::string text = "# timestamp tx ty tz qx qy qz qw\n";
  for (int k = 0; k < count; ++k) {
    const Point p = path_point(k);
    char line[256];
    std::snprintf(line, sizeof(line), "%.6f %.9f %.9f %.9f 0 0 0 1\n", first + step * k,
                  p.x * position_scale + shift.x, p.y * position_scale + shift.y,
                  p.z * position_scale + shift.z);
    text += line;
  }
  return text;
}

// Constant velocity along x at `speed` m/s, 10 Hz, `count` poses.
std::string moving_text(int count, double speed, bool euroc = false) {
  std::string text = euroc ? "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],"
                             "q_RS_y [],q_RS_z []\n"
                           : "";
  for (int k = 0; k < count; ++k) {
    char line[256];
    if (euroc) {
      std::snprintf(line, sizeof(line), "%lld,%.9f,0,0,1,0,0,0\n", 100000000LL * k, speed * 0.1 * k);
    } else {
      std::snprintf(line, sizeof(line), "%.6f %.9f 0 0 0 0 0 1\n", 0.1 * k, speed * 0.1 * k);
    }
    text += line;
  }
  return text;
}

nlohmann::json parse_json(const std::string& out) {
  try {
    return nlohmann::json::parse(out);
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not JSON: " << e.what() << "\n" << out;
    return {};
  }
}

bool contains(const std::string& text, const std::string& needle) {
  return text.find(needle) != std::string::npos;
}

}  // namespace

TEST(CliEval, AteWithoutAlignmentReportsTheShift) {
  TempDir dir;
  const std::string gt = (dir / "gt.txt").string();
  const std::string est = (dir / "est.txt").string();
  write_text(gt, tum_text(12, 0.1, 100.0, 1.0, {0, 0, 0}));
  write_text(est, tum_text(12, 0.1, 100.0, 1.0, {-1.0, -2.0, -2.0}));  // |(1, 2, 2)| = 3
  const auto human = run_cli({"eval", "ate", gt, est, "--align", "none"});
  ASSERT_EQ(human.exit_code, 0) << human.err;
  EXPECT_TRUE(contains(human.out, "compared_pose_pairs 12 pairs\n")) << human.out;
  EXPECT_TRUE(contains(human.out, "absolute_translational_error.rmse 3.000000 m\n")) << human.out;
  EXPECT_TRUE(contains(human.out, "absolute_translational_error.std 0.000000 m\n")) << human.out;

  const auto r = run_cli({"--json", "eval", "ate", gt, est, "--align", "none"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = parse_json(r.out);
  EXPECT_EQ(j["compared_pose_pairs"], 12);
  EXPECT_EQ(j["alignment"], "none");
  EXPECT_NEAR(j["absolute_translational_error_m"]["rmse"].get<double>(), 3.0, 1e-8);
  EXPECT_NEAR(j["absolute_translational_error_m"]["max"].get<double>(), 3.0, 1e-8);
}

TEST(CliEval, AteSe3AbsorbsShiftAndSavesAlignedTrajectory) {
  TempDir dir;
  const std::string gt = (dir / "gt.txt").string();
  const std::string est = (dir / "est.txt").string();
  const std::string aligned = (dir / "aligned.txt").string();
  write_text(gt, tum_text(12, 0.1, 100.0, 1.0, {0, 0, 0}));
  write_text(est, tum_text(12, 0.1, 100.0, 1.0, {-1.0, -2.0, -2.0}));
  const auto r = run_cli({"eval", "ate", gt, est, "--save-aligned", aligned, "--json"});  // --json after
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = parse_json(r.out);
  EXPECT_NEAR(j["absolute_translational_error_m"]["rmse"].get<double>(), 0.0, 1e-8);
  EXPECT_NEAR(j["transform"]["translation"][1].get<double>(), 2.0, 1e-8);
  EXPECT_NEAR(j["transform"]["scale"].get<double>(), 1.0, 1e-12);
  // The saved estimate lies on the ground truth.
  const auto lines = crowdslam::read_lines(aligned);
  int poses = 0;
  for (const auto& line : lines) {
    if (line.empty() || line[0] == '#') continue;
    const auto fields = crowdslam::split_fields(line);
    ASSERT_EQ(fields.size(), 8u);
    const Point p = path_point(poses);
    EXPECT_NEAR(*crowdslam::parse_double(fields[1]), p.x, 1e-8);
    EXPECT_NEAR(*crowdslam::parse_double(fields[3]), p.z, 1e-8);
    ++poses;
  }
  EXPECT_EQ(poses, 12);
}

TEST(CliEval, AteSim3RecoversScale) {
  TempDir dir;
  const std::string gt = (dir / "gt.txt").string();
  const std::string est = (dir / "est.txt").string();
  write_text(gt, tum_text(12, 0.1, 5.0, 1.0, {0, 0, 0}));
  write_text(est, tum_text(12, 0.1, 5.0, 0.5, {0.25, 0, 0}));
  const auto r = run_cli({"--json", "eval", "ate", gt, est, "--align", "sim3"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = parse_json(r.out);
  EXPECT_NEAR(j["transform"]["scale"].get<double>(), 2.0, 1e-7);
  EXPECT_NEAR(j["absolute_translational_error_m"]["rmse"].get<double>(), 0.0, 1e-7);
}

TEST(CliEval, RpeSecondsAndFramesAcrossFormats) {
  TempDir dir;
  const std::string gt = (dir / "gt.txt").string();
  const std::string est = (dir / "est.csv").string();
  write_text(gt, moving_text(51, 1.0));
  write_text(est, moving_text(51, 1.1, /*euroc=*/true));  // EuRoC, nanosecond stamps
  const auto r = run_cli({"--json", "eval", "rpe", gt, est});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = parse_json(r.out);
  EXPECT_EQ(j["compared_pose_pairs"], 40);  // 51 poses, delta 1 s = 10 poses, last index excluded
  EXPECT_NEAR(j["translational_error_m"]["rmse"].get<double>(), 0.1, 1e-8);
  EXPECT_NEAR(j["rotational_error_deg"]["max"].get<double>(), 0.0, 1e-6);

  const auto frames = run_cli({"eval", "rpe", gt, est, "--delta", "3", "--delta-unit", "frames"});
  ASSERT_EQ(frames.exit_code, 0) << frames.err;
  EXPECT_TRUE(contains(frames.out, "compared_pose_pairs 47 pairs\n")) << frames.out;
  EXPECT_TRUE(contains(frames.out, "translational_error.rmse 0.030000 m\n")) << frames.out;
  EXPECT_TRUE(contains(frames.out, "rotational_error.rmse 0.000000 deg\n")) << frames.out;
}

TEST(CliEval, MalformedLineIsOneLineErrorNamingFileAndLine) {
  TempDir dir;
  const std::string gt = (dir / "gt.txt").string();
  const std::string est = (dir / "est.txt").string();
  write_text(gt, tum_text(12, 0.1, 0.0, 1.0, {0, 0, 0}));
  write_text(est, "1.0 0 0 0 0 0 0 1\n1.1 0 0 0 0 0 0 1\n1.2 nan 0 0 0 0 0 1\n");
  for (const char* metric : {"ate", "rpe"}) {
    const auto r = run_cli({"eval", metric, gt, est});
    EXPECT_EQ(r.exit_code, 1) << metric;
    EXPECT_TRUE(contains(r.err, "error: " + est + ":3: non-finite value 'nan'")) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
}

TEST(CliEval, NoOverlapAndBadOptionsAreInputErrors) {
  TempDir dir;
  const std::string gt = (dir / "gt.txt").string();
  const std::string est = (dir / "est.txt").string();
  write_text(gt, tum_text(12, 0.1, 0.0, 1.0, {0, 0, 0}));
  write_text(est, tum_text(12, 0.1, 500.0, 1.0, {0, 0, 0}));
  const auto ate = run_cli({"eval", "ate", gt, est});
  EXPECT_EQ(ate.exit_code, 1);
  EXPECT_TRUE(contains(ate.err, "no overlapping timestamps")) << ate.err;
  EXPECT_TRUE(contains(ate.err, gt) && contains(ate.err, est)) << ate.err;
  const auto rpe = run_cli({"eval", "rpe", gt, est});
  EXPECT_EQ(rpe.exit_code, 1);
  EXPECT_TRUE(contains(rpe.err, "too small")) << rpe.err;
  // --offset -500 brings them together.
  EXPECT_EQ(run_cli({"eval", "ate", gt, est, "--offset", "-500"}).exit_code, 0);

  const auto align = run_cli({"eval", "ate", gt, gt, "--align", "affine"});
  EXPECT_EQ(align.exit_code, 1);
  EXPECT_TRUE(contains(align.err, "'affine'")) << align.err;
  const auto unit = run_cli({"eval", "rpe", gt, gt, "--delta-unit", "m"});
  EXPECT_EQ(unit.exit_code, 1);
  EXPECT_TRUE(contains(unit.err, "'m'")) << unit.err;
  const auto diff = run_cli({"eval", "ate", gt, gt, "--max-diff", "0"});
  EXPECT_EQ(diff.exit_code, 1);
  EXPECT_TRUE(contains(diff.err, "--max-diff")) << diff.err;
  const auto missing = run_cli({"eval", "ate", gt, (dir / "nope.txt").string()});
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_TRUE(contains(missing.err, "nope.txt")) << missing.err;
}
