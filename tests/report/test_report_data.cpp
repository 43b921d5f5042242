// The report's data: the alignment equals run.json's ATE, what is read from a run's files, and the
// errors bad input gives (file and key named).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>

#include "crowdslam/eval/unique_stamps.h"
#include "crowdslam/io/trajectory.h"
#include "crowdslam/report/chartjs.h"
#include "crowdslam/report/frame_strip.h"
#include "crowdslam/report/page_data.h"
#include "crowdslam/report/report.h"
#include "crowdslam/report/run_data.h"
#include "crowdslam/run/run_document.h"
#include "report_test_helpers.h"

using namespace crowdslam;
namespace fs = std::filesystem;

namespace {

// One synthetic run shared by the tests of this file (sequential: the same run every time).
class ReportRun : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    tmp_ = new test::TempDir();
    dataset_ = test::make_crowd_room(*tmp_, 4);
    out_ = tmp_->path() / "out";
    summary_ = new run::RunSummary(test::run_room(dataset_, out_, true, 10));
  }
  static void TearDownTestSuite() {
    delete summary_;
    delete tmp_;
  }
  // A copy of the run's directory, to break.
  static fs::path copy_run(const std::string& name) {
    const auto dir = tmp_->path() / name;
    fs::remove_all(dir);
    fs::copy(out_, dir, fs::copy_options::recursive);
    return dir;
  }
  static test::TempDir* tmp_;
  static fs::path dataset_, out_;
  static run::RunSummary* summary_;
};
test::TempDir* ReportRun::tmp_ = nullptr;
fs::path ReportRun::dataset_, ReportRun::out_;
run::RunSummary* ReportRun::summary_ = nullptr;

nlohmann::json read_json(const fs::path& path) { return nlohmann::json::parse(test::read_text(path)); }
void write_json(const fs::path& path, const nlohmann::json& doc) { test::write_text(path, doc.dump(1)); }

}  // namespace

TEST_F(ReportRun, RunWritesReportBesideItsOutputs) {
  ASSERT_TRUE(fs::is_regular_file(out_ / "report.html"));
  const std::string page = test::read_text(out_ / "report.html");
  EXPECT_NE(page.find("window.Chart"), std::string::npos);  // Chart.js inlined
  EXPECT_NE(page.find("<script type=\"application/json\" id=\"report-data\">"), std::string::npos);
  EXPECT_EQ(page.find("<script src="), std::string::npos);  // nothing loaded from elsewhere
  EXPECT_EQ(page.find("<link"), std::string::npos);
  EXPECT_EQ(summary_->json.count("report_error"), 0u);
}

TEST_F(ReportRun, AlignmentEqualsRunJsonAte) {
  const auto run = report::load_run(out_);
  const auto& accuracy = run.document["accuracy"];
  ASSERT_TRUE(accuracy.is_object());
  ASSERT_TRUE(run.evaluated_segment.has_value());
  const auto& segment = run.segments[*run.evaluated_segment];
  ASSERT_TRUE(segment.ate.has_value());
  EXPECT_EQ(run.alignment, eval::Alignment::kSe3);  // RGB-D
  EXPECT_NEAR(segment.ate->translation_error_m.rmse, accuracy["ate_rmse_m"].get<double>(), 1e-9);
  EXPECT_NEAR(segment.ate->translation_error_m.max, accuracy["ate_max_m"].get<double>(), 1e-9);
  EXPECT_EQ(segment.ate->matches.size(), accuracy["ate_pairs"].get<size_t>());
  EXPECT_EQ(segment.estimate.size(), summary_->tracked);
  // The aligned poses are where the errors say: |aligned_i - gt_i| = e_i for the matches.
  const auto gt = eval::unique_sorted_by_stamp(run.ground_truth);
  const auto est = eval::unique_sorted_by_stamp(segment.aligned);
  for (size_t k = 0; k < segment.ate->matches.size(); ++k) {
    const auto& m = segment.ate->matches[k];
    const double e =
        (est[m.second_index].world_from_cam.translation() - gt[m.first_index].world_from_cam.translation())
            .norm();
    ASSERT_NEAR(e, segment.ate->errors_m[k], 1e-9) << "match " << k;
  }
}

TEST_F(ReportRun, FrameSeriesAndPageDataFollowRunJson) {
  const auto run = report::load_run(out_);
  const auto& frames = run.document["frames"];
  ASSERT_EQ(run.frames.size(), frames.size());
  ASSERT_EQ(run.frames.size(), 40u);
  int removed = 0;
  for (size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(run.frames.keypoints[i], frames[i]["keypoints"].get<double>());
    EXPECT_EQ(run.frames.method[i], frames[i]["method"].get<std::string>());
    removed += frames[i]["keypoints_before_filter"].get<int>() - frames[i]["keypoints"].get<int>();
  }
  EXPECT_GT(removed, 0);                   // the filter removed keypoints on people
  EXPECT_EQ(run.saved_frames.size(), 4u);  // --save-frames 10 over 40 frames
  const auto page = report::page_data({run}, {});
  ASSERT_EQ(page["runs"].size(), 1u);
  const auto& r = page["runs"][0];
  EXPECT_EQ(r["frames"]["t"].size(), 40u);
  EXPECT_DOUBLE_EQ(r["frames"]["t"][0].get<double>(), 0.0);
  EXPECT_EQ(r["saved_frames"].size(), 4u);
  EXPECT_EQ(r["saved_frames"][0]["src"].get<std::string>().rfind("data:image/jpeg;base64,", 0), 0u);
  EXPECT_EQ(r["summary"].size(), report::summary_rows().size());
  EXPECT_EQ(r["segments"][0]["errors"]["e"].size(), run.segments[0].ate->matches.size());
  EXPECT_EQ(r["mapping"]["steps"].size(), 6u);
}

TEST_F(ReportRun, WriteReportRegeneratesAndCompares) {
  const auto other = copy_run("copy");
  const auto html = tmp_->path() / "compare.html";
  const auto result = report::write_report(out_, {other}, html);
  EXPECT_EQ(result.runs, 2u);
  EXPECT_EQ(result.bytes, fs::file_size(html));
  EXPECT_EQ(result.frames_embedded, 2u * 4u);  // 24 frames per report, shared: 12 per run, 4 saved each
  const std::string page = test::read_text(html);
  EXPECT_NE(page.find("\"label\":\"copy\""), std::string::npos);
  EXPECT_NE(page.find("\"label\":\"out\""), std::string::npos);
}

TEST_F(ReportRun, KittiTrajectoryGetsTheTrackedFramesStamps) {
  // Output.trajectory_format: kitti writes no stamps: they come from run.json's tracked frames.
  const auto dir = copy_run("kitti_format");
  for (const char* name : {"CameraTrajectory.txt", "KeyFrameTrajectory.txt"}) {
    const auto poses = io::read_tum_trajectory((out_ / name).string());
    io::write_kitti_trajectory((dir / name).string(), poses);
  }
  ASSERT_EQ(io::detect_trajectory_format((dir / "CameraTrajectory.txt").string()),
            io::TrajectoryFormat::kKitti);
  const auto tum = report::load_run(out_);
  const auto kitti = report::load_run(dir);
  ASSERT_TRUE(kitti.evaluated_segment.has_value());
  const auto& a = tum.segments[0];
  const auto& b = kitti.segments[0];
  ASSERT_EQ(a.estimate.size(), b.estimate.size());
  for (size_t i = 0; i < a.estimate.size(); ++i)
    ASSERT_EQ(a.estimate[i].timestamp_s, b.estimate[i].timestamp_s);
  EXPECT_NEAR(b.ate->translation_error_m.rmse, tum.document["accuracy"]["ate_rmse_m"].get<double>(), 1e-8);
}

TEST_F(ReportRun, ReportCommand) {
  const auto html = tmp_->path() / "cli" / "both.html";
  fs::create_directories(html.parent_path());
  auto r =
      test::run_cli({"--json", "report", out_.string(), "--compare", out_.string(), "--out", html.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["runs"], 2);
  EXPECT_EQ(doc["bytes"].get<size_t>(), fs::file_size(html));
  EXPECT_NE(test::read_text(html).find("/out (2)\","), std::string::npos);  // the same run twice

  const auto copy = copy_run("cli_default");
  fs::remove(copy / "report.html");
  r = test::run_cli({"report", copy.string()});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::is_regular_file(copy / "report.html"));  // default: OUT/report.html

  r = test::run_cli({"report", (tmp_->path() / "not_a_run").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("error: " + (tmp_->path() / "not_a_run" / "run.json").string() + ": not found"),
            std::string::npos)
      << r.err;
}

TEST_F(ReportRun, MissingOrBrokenRunJsonNamesFileAndKey) {
  const auto html = tmp_->path() / "bad.html";
  auto dir = copy_run("no_json");
  fs::remove(dir / "run.json");
  auto message = test::error_of([&] { report::write_report(dir, {}, html); });
  EXPECT_NE(message.find("no_json/run.json"), std::string::npos) << message;
  EXPECT_NE(message.find("not found"), std::string::npos) << message;

  dir = copy_run("bad_json");
  test::write_text(dir / "run.json", "{\"end_state\": \"completed\", ");
  message = test::error_of([&] { report::write_report(dir, {}, html); });
  EXPECT_NE(message.find("bad_json/run.json"), std::string::npos) << message;
  EXPECT_NE(message.find("not valid JSON"), std::string::npos) << message;

  dir = copy_run("no_key");
  auto doc = read_json(dir / "run.json");
  doc["summary"].erase("map_points");
  write_json(dir / "run.json", doc);
  message = test::error_of([&] { report::write_report(dir, {}, html); });
  EXPECT_NE(message.find("no_key/run.json"), std::string::npos) << message;
  EXPECT_NE(message.find("'summary.map_points': missing"), std::string::npos) << message;

  dir = copy_run("bad_frame");
  doc = read_json(dir / "run.json");
  doc["frames"][3]["state"] = 7;
  write_json(dir / "run.json", doc);
  message = test::error_of([&] { report::write_report(dir, {}, html); });
  EXPECT_NE(message.find("'frames[3].state': expected a string, got number"), std::string::npos) << message;

  dir = copy_run("running");
  doc = read_json(dir / "run.json");
  doc["end_state"] = "running";
  write_json(dir / "run.json", doc);
  message = test::error_of([&] { report::write_report(dir, {}, html); });
  EXPECT_NE(message.find("'end_state' is \"running\""), std::string::npos) << message;
  EXPECT_FALSE(fs::exists(html));  // nothing written for bad input
}

TEST_F(ReportRun, TrajectoryThatDoesNotMatchTheSegmentsIsAnError) {
  const auto dir = copy_run("short_trajectory");
  auto poses = io::read_tum_trajectory((dir / "CameraTrajectory.txt").string());
  poses.pop_back();
  io::write_tum_trajectory((dir / "CameraTrajectory.txt").string(), poses);
  const auto message = test::error_of([&] { report::load_run(dir); });
  EXPECT_NE(message.find("short_trajectory/CameraTrajectory.txt"), std::string::npos) << message;
  EXPECT_NE(message.find(std::to_string(poses.size()) + " poses, but run.json's segments give " +
                         std::to_string(poses.size() + 1)),
            std::string::npos)
      << message;
}

TEST_F(ReportRun, MovedDatasetGivesAReportWithoutGroundTruth) {
  const auto dir = copy_run("moved");
  auto doc = read_json(dir / "run.json");
  doc["dataset"] = (tmp_->path() / "nowhere").string();
  write_json(dir / "run.json", doc);
  const auto run = report::load_run(dir);
  EXPECT_TRUE(run.ground_truth.empty());
  EXPECT_NE(run.ground_truth_note.find("nowhere"), std::string::npos);
  EXPECT_FALSE(run.evaluated_segment.has_value());
  // Shown as tracked, in the run's own frame.
  EXPECT_EQ(run.segments[0].aligned.size(), summary_->tracked);
}

TEST_F(ReportRun, MapperTimeOfEveryKeyframeInRunJsonAndThePage) {
  const auto doc = read_json(out_ / "run.json");
  const auto& mapping = doc["local_mapping"];
  const auto& list = mapping["keyframe_times_ms"];
  ASSERT_TRUE(list.is_array());
  ASSERT_GT(mapping["keyframes_processed"].get<size_t>(), 2u);
  ASSERT_EQ(list.size(), mapping["keyframes_processed"].get<size_t>());
  std::vector<double> totals;
  for (size_t n = 0; n < list.size(); ++n) {
    const auto& k = list[n];
    EXPECT_EQ(k["n"].get<size_t>(), n);
    double steps = 0;
    for (const char* step : {"register", "triangulation", "fusion", "local_ba", "culling"}) {
      EXPECT_GE(k[step].get<double>(), 0.0) << n << " " << step;
      steps += k[step].get<double>();
    }
    EXPECT_GE(k["total"].get<double>() + 1e-9, steps) << "keyframe " << n;  // the steps are parts of the total
    totals.push_back(k["total"].get<double>());
  }
  // The list is what the summary aggregates.
  EXPECT_DOUBLE_EQ(run::percentile(totals, 0.5), mapping["per_keyframe_ms"]["total"]["median"].get<double>());
  EXPECT_DOUBLE_EQ(run::percentile(totals, 0.95), mapping["per_keyframe_ms"]["total"]["p95"].get<double>());

  const auto page = report::page_data({report::load_run(out_)}, {});
  const auto& keyframes = page["runs"][0]["mapping"]["keyframes"];
  ASSERT_TRUE(keyframes.is_object());
  for (const char* key : {"n", "register", "triangulation", "fusion", "local_ba", "culling", "total"})
    EXPECT_EQ(keyframes[key].size(), list.size()) << key;
  EXPECT_NEAR(keyframes["total"].back().get<double>(), list.back()["total"].get<double>(), 1e-3);

  // A run.json written before the list existed still gives a page (without the per-keyframe chart's data).
  const auto dir = copy_run("no_keyframe_times");
  auto old = read_json(dir / "run.json");
  old["local_mapping"].erase("keyframe_times_ms");
  write_json(dir / "run.json", old);
  EXPECT_TRUE(report::page_data({report::load_run(dir)}, {})["runs"][0]["mapping"]["keyframes"].is_null());
}

TEST_F(ReportRun, RelativeDatasetPathIsWrittenAbsoluteSoTheReportFindsTheGroundTruthFromAnywhere) {
  const fs::path start = fs::current_path();
  const fs::path relative = fs::relative(dataset_, start);
  ASSERT_TRUE(relative.is_relative()) << relative;
  const auto out = tmp_->path() / "relative_dataset";
  test::run_room(relative, out, true);
  const auto doc = read_json(out / "run.json");
  const fs::path written = doc["dataset"].get<std::string>();
  EXPECT_TRUE(written.is_absolute()) << written;
  EXPECT_TRUE(fs::equivalent(written, dataset_)) << written;

  // From another working directory (where the relative path names nothing) the report still has it.
  // Deeper than the first one, so that the path's ".." do not climb back to "/".
  auto elsewhere = tmp_->path() / "elsewhere";
  for (auto part = start.begin(); part != start.end(); ++part) elsewhere /= "d";
  fs::create_directories(elsewhere);
  fs::current_path(elsewhere);
  const bool relative_resolves_here = fs::exists(relative);
  const auto run = report::load_run(out);
  fs::current_path(start);
  EXPECT_FALSE(relative_resolves_here);
  EXPECT_FALSE(run.ground_truth.empty()) << run.ground_truth_note;
  EXPECT_TRUE(run.evaluated_segment.has_value());
}

TEST(Report, RunWhoseReportFailsKeepsItsOutputsAndExitCode) {
  test::TempDir tmp;
  const auto dataset = test::make_crowd_room(tmp, 0, 20);
  const char* previous = std::getenv("CROWDSLAM_CHARTJS");
  const std::string saved = previous ? previous : "";
  setenv("CROWDSLAM_CHARTJS", (tmp / "missing.js").c_str(), 1);
  run::RunSummary summary;
  const auto message = test::error_of([&] { summary = test::run_room(dataset, tmp / "out", false); });
  if (previous) {
    setenv("CROWDSLAM_CHARTJS", saved.c_str(), 1);
  } else {
    unsetenv("CROWDSLAM_CHARTJS");
  }
  EXPECT_EQ(message, "");  // the run did not fail
  EXPECT_EQ(summary.end.to_string(), "completed");
  EXPECT_EQ(summary.tracked, 20u);
  EXPECT_FALSE(fs::exists(tmp / "out" / "report.html"));
  EXPECT_EQ(io::read_tum_trajectory((tmp / "out" / "CameraTrajectory.txt").string()).size(), 20u);
  const auto doc = read_json(tmp / "out" / "run.json");
  ASSERT_TRUE(doc.contains("report_error"));
  EXPECT_NE(doc["report_error"].get<std::string>().find("libjs-chart.js"), std::string::npos);
  EXPECT_EQ(doc["end_state"], "completed");
  EXPECT_EQ(doc["summary"]["tracked_frames"], 20);
}

TEST(Report, MonocularAlignmentIsSim3) {
  // A fabricated monocular run: the ground truth at half scale, rotated and moved. Sim3 recovers it
  // exactly (scale 2); SE3, as for RGB-D, cannot.
  test::TempDir tmp;
  const auto dataset = test::make_crowd_room(tmp, 0, 20);
  const auto gt = io::read_tum_trajectory((dataset / "groundtruth.txt").string());
  const geometry::SE3 moved(Eigen::AngleAxisd(0.4, geometry::Vec3::UnitY()).toRotationMatrix(),
                            geometry::Vec3(1, 2, 3));
  io::Trajectory estimate;
  for (const auto& pose : gt) {
    const geometry::Vec3 p =
        moved.rotation_matrix() * (0.5 * pose.world_from_cam.translation()) + moved.translation();
    estimate.push_back({pose.timestamp_s, geometry::SE3(pose.world_from_cam.rotation_matrix(), p)});
  }
  std::vector<report::SegmentTrajectory> segments(1);
  segments[0].estimate = estimate;
  ASSERT_EQ(report::align_segments(gt, eval::Alignment::kSim3, segments), std::optional<size_t>(0));
  EXPECT_NEAR(segments[0].ate->alignment.scale, 2.0, 1e-9);
  EXPECT_LT(segments[0].ate->translation_error_m.rmse, 1e-9);
  EXPECT_NEAR(
      (segments[0].aligned[7].world_from_cam.translation() - gt[7].world_from_cam.translation()).norm(), 0,
      1e-9);
  ASSERT_EQ(report::align_segments(gt, eval::Alignment::kSe3, segments), std::optional<size_t>(0));
  EXPECT_GT(segments[0].ate->translation_error_m.rmse, 1e-3);
}

TEST(Report, SplitByCountsAndSegmentsTooShortToAlign) {
  io::Trajectory poses(5);
  for (size_t i = 0; i < poses.size(); ++i) {
    const double x = static_cast<double>(i);
    poses[i] = {x, geometry::SE3(geometry::Mat3::Identity(), geometry::Vec3(x, x * x, 1.0))};
  }
  const auto parts = report::split_by_counts(poses, {3, 0, 2}, "T.txt", "tracked frames");
  ASSERT_EQ(parts.size(), 3u);
  EXPECT_EQ(parts[0].size(), 3u);
  EXPECT_EQ(parts[2].front().timestamp_s, 3.0);
  const auto message = test::error_of([&] {
    report::split_by_counts(poses, {3, 3}, "T.txt", "tracked frames");
  });
  EXPECT_EQ(message,
            "T.txt: 5 poses, but run.json's segments give 6 tracked frames (is the file from another run?)");
  std::vector<report::SegmentTrajectory> segments(2);
  segments[0].estimate = parts[2];  // 2 poses: not evaluated, shown as they are
  segments[1].estimate = parts[0];
  EXPECT_EQ(report::align_segments(poses, eval::Alignment::kSe3, segments), std::optional<size_t>(1));
  EXPECT_EQ(segments[0].error, "fewer than 3 poses");
  EXPECT_FALSE(segments[0].ate.has_value());
  EXPECT_EQ(segments[0].aligned.size(), 2u);
  ASSERT_TRUE(segments[1].ate.has_value());
  EXPECT_LT(segments[1].ate->translation_error_m.rmse, 1e-12);
}

TEST(Report, ChartJsMissingNamesThePackage) {
  const char* previous = std::getenv("CROWDSLAM_CHARTJS");
  const std::string saved = previous ? previous : "";
  setenv("CROWDSLAM_CHARTJS", "/nonexistent/chart.min.js", 1);
  EXPECT_EQ(report::chartjs_path(), fs::path("/nonexistent/chart.min.js"));
  const auto message = test::error_of([] { report::read_chartjs(report::chartjs_path()); });
  if (previous) {
    setenv("CROWDSLAM_CHARTJS", saved.c_str(), 1);
  } else {
    unsetenv("CROWDSLAM_CHARTJS");
  }
  EXPECT_NE(message.find("/nonexistent/chart.min.js: Chart.js not found"), std::string::npos) << message;
  EXPECT_NE(message.find("libjs-chart.js"), std::string::npos) << message;
}

TEST(Report, PageEmbedsDataSafely) {
  nlohmann::json data = {{"title", "a </script><b>"},
                         {"runs", nlohmann::json::array({{{"label", "</script>"}}})}};
  const std::string page = report::render_page(data, "window.Chart = {};");
  EXPECT_EQ(page.find("</script><b>"), std::string::npos);
  EXPECT_NE(page.find("<title>a &lt;/script&gt;&lt;b&gt;</title>"), std::string::npos);
  // The JSON block parses back to the data.
  const std::string open = "<script type=\"application/json\" id=\"report-data\">";
  const auto begin = page.find(open) + open.size();
  const auto end = page.find("</script>", begin);
  EXPECT_EQ(nlohmann::json::parse(page.substr(begin, end - begin)), data);
  EXPECT_EQ(report::script_safe_json("{\"a\":\"<!--\"}"), "{\"a\":\"\\u003c!--\"}");
  // Chart.js source containing "</script" is inlined without ending its element.
  const std::string chart = report::render_page(data, "var s = '</script>';");
  EXPECT_NE(chart.find("var s = '<\\/script>';"), std::string::npos);
}

TEST(Report, FrameStripHelpers) {
  EXPECT_EQ(report::spread_indices(3, 5), (std::vector<size_t>{0, 1, 2}));
  EXPECT_EQ(report::spread_indices(10, 4), (std::vector<size_t>{0, 3, 6, 9}));
  EXPECT_EQ(report::spread_indices(10, 1), (std::vector<size_t>{0}));
  EXPECT_TRUE(report::spread_indices(0, 4).empty());
  const std::string text = "foobar";
  const auto* bytes = reinterpret_cast<const unsigned char*>(text.data());
  EXPECT_EQ(report::base64_encode(bytes, 6), "Zm9vYmFy");
  EXPECT_EQ(report::base64_encode(bytes, 5), "Zm9vYmE=");
  EXPECT_EQ(report::base64_encode(bytes, 4), "Zm9vYg==");
  EXPECT_EQ(report::base64_encode(bytes, 0), "");
}

TEST(Report, ViewAxesFollowTheLongestExtents) {
  io::Trajectory t;
  for (int i = 0; i < 10; ++i) {
    // x spans 9, y 0.9 (the height), z 4.5: from above x-z, from the side x-y.
    t.push_back({i * 0.1, geometry::SE3(geometry::Mat3::Identity(), geometry::Vec3(i, 0.1 * i, 0.5 * i))});
  }
  auto axes = report::choose_view_axes(t);
  EXPECT_EQ(axes.top[0], 0);
  EXPECT_EQ(axes.top[1], 2);
  EXPECT_EQ(axes.side[0], 0);
  EXPECT_EQ(axes.side[1], 1);
  for (auto& pose : t) {  // Bonn-like: z is the height
    const auto p = pose.world_from_cam.translation();
    pose.world_from_cam = geometry::SE3(geometry::Mat3::Identity(), geometry::Vec3(p.z(), p.x(), p.y()));
  }
  axes = report::choose_view_axes(t);
  EXPECT_EQ(axes.top[0], 0);
  EXPECT_EQ(axes.top[1], 1);
  EXPECT_EQ(axes.side[0], 1);
  EXPECT_EQ(axes.side[1], 2);
}
