// The live viewer in a real browser (issue 13): headless Chromium follows a synthetic run paced at the
// sensor's rate, receives updates, draws a non-blank canvas with WebGL, reports no JavaScript error, and
// its pause button pauses the run (the frame count stops advancing) until resumed.
#include <gtest/gtest.h>
#include <httplib.h>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <thread>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include "test_support.h"

using namespace crowdslam::test;
using namespace std::chrono_literals;

namespace {
bool have_chromium() { return std::system("command -v chromium >/dev/null 2>&1") == 0; }

// Starts headless Chromium on `url` in the background; it quits by itself after `seconds`.
// `extra` empty: a live page (runs in real time until `timeout` kills it); with --screenshot, Chromium's
// --timeout takes the picture (its timers are frozen then, so only for a picture).
void start_chromium(const std::string& url, const std::filesystem::path& profile, const std::string& extra, int seconds) {
  const std::string mode = extra.empty() ? std::string("--remote-debugging-port=0")
                                         : "--timeout=" + std::to_string(seconds * 1000) + " " + extra;
  const std::string command = "timeout " + std::to_string(seconds + 20) +
                              " chromium --headless=new --no-sandbox --disable-gpu --enable-unsafe-swiftshader "
                              "--use-angle=swiftshader --no-first-run --proxy-server=127.0.0.1:9 "  // no network (loopback is direct)
                              "--user-data-dir=" + profile.string() + " " + mode + " '" + url + "' >/dev/null 2>&1 &";
  ASSERT_EQ(std::system(command.c_str()), 0);
}

nlohmann::json state(int port) {
  httplib::Client client("127.0.0.1", port);
  client.set_read_timeout(5, 0);
  const auto r = client.Get("/state");
  if (!r || r->status != 200) return nullptr;
  return nlohmann::json::parse(r->body, nullptr, false);
}
}  // namespace

TEST(ViewerChromium, LiveRunIsDrawnAndThePauseButtonPausesIt) {
  if (!have_chromium()) GTEST_SKIP() << "chromium is not installed (scripts/setup.sh installs it)";
  TempDir dir;
  const auto seq = dir / "seq";
  ASSERT_EQ(run_cli({"-q", "synth", "--out", seq.string(), "--frames", "900", "--width", "320", "--height", "240",
                     "--trajectory", "line"}).exit_code,
            0);  // 30 s at the sensor rate: time for a browser to start on a loaded machine
  CliProcess run({"run", "--dataset", seq.string(), "--out", (dir / "out").string(), "--viewer", "--viewer-port", "0",
                  "--pace", "sensor"});
  const int port = wait_for_viewer_port(run);
  ASSERT_GT(port, 0) << run.current_stderr();
  const std::string url = "http://127.0.0.1:" + std::to_string(port) + "/";
  start_chromium(url + "?click=pause&after=12&points=101", dir / "profile1", "", 100);

  // The page reports back what it received; wait for it to have pressed pause.
  nlohmann::json s;
  const auto deadline = std::chrono::steady_clock::now() + 90s;
  while (std::chrono::steady_clock::now() < deadline) {
    s = state(port);
    if (s.is_object() && s["client"].is_object() && s["run"]["paused"] == true && s["client"]["paused"] == true) break;
    ASSERT_FALSE(run.exited()) << "the run ended before the page paused it: " << run.current_stderr();
    std::this_thread::sleep_for(200ms);
  }
  ASSERT_TRUE(s.is_object() && s["client"].is_object()) << s.dump();
  ASSERT_EQ(s["run"]["paused"], true) << s.dump();
  EXPECT_GE(s["client"]["updates"].get<int>(), 12);
  EXPECT_EQ(s["client"]["webgl"], "yes");
  EXPECT_GT(s["client"]["points"].get<int>(), 100);
  EXPECT_GT(s["client"]["images"].get<int>(), 0) << s.dump();  // the camera image drawn too
  EXPECT_GT(s["client"]["renders"].get<int>(), 0) << s.dump();
  // Paused: the run's frame count stops advancing.
  std::this_thread::sleep_for(500ms);
  const int frames = state(port)["run"]["frames"].get<int>();
  std::this_thread::sleep_for(1500ms);
  EXPECT_EQ(state(port)["run"]["frames"].get<int>(), frames);
  EXPECT_LT(frames, 900);

  // A screenshot of the paused page: the canvas is drawn (not blank).
  const auto shot = dir / "viewer.png";
  start_chromium(url, dir / "profile2", "--screenshot=" + shot.string() + " --window-size=1280,800", 15);
  for (int i = 0; i < 400 && !std::filesystem::exists(shot); ++i) std::this_thread::sleep_for(100ms);
  std::this_thread::sleep_for(500ms);
  const cv::Mat image = cv::imread(shot.string(), cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(image.empty()) << "no screenshot";
  cv::Scalar mean, stddev;
  cv::meanStdDev(image, mean, stddev);
  EXPECT_GT(stddev[0], 10.0) << "the page looks blank";
  // Still no JavaScript error after all that.
  s = state(port);
  EXPECT_EQ(s["client"]["errors"].get<int>(), 0) << s.dump();

  // Resume: the run goes on to the end and exits normally.
  httplib::Client client("127.0.0.1", port);
  ASSERT_TRUE(client.Post("/control/resume", "", "text/plain"));
  const auto result = run.wait(120);
  EXPECT_EQ(result.exit_code, 0) << result.err;
  if (const char* keep = std::getenv("CROWDSLAM_VIEWER_SCREENSHOT")) std::filesystem::copy_file(shot, keep, std::filesystem::copy_options::overwrite_existing);
}

// A page left open across runs: when the run it shows ends and the next starts on the same port, the page
// reconnects by itself (no reload), takes the new server's session and follows the new run from its start.
TEST(ViewerChromium, APageLeftOpenFollowsTheNextRunOnThePort) {
  if (!have_chromium()) GTEST_SKIP() << "chromium is not installed (scripts/setup.sh installs it)";
  TempDir dir;
  const auto seq = dir / "seq";
  ASSERT_EQ(run_cli({"-q", "synth", "--out", seq.string(), "--frames", "900", "--width", "320", "--height", "240",
                     "--trajectory", "line"}).exit_code,
            0);
  int port = 0;
  {  // a free port, released again before the runs bind it
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t length = sizeof address;
    ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
    ASSERT_EQ(::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length), 0);
    port = ntohs(address.sin_port);
    ::close(fd);
  }
  const auto start_run = [&](const std::string& name) {
    return std::make_unique<CliProcess>(std::vector<std::string>{"-q", "run", "--dataset", seq.string(), "--out",
                                                                 (dir / name).string(), "--viewer", "--viewer-port",
                                                                 std::to_string(port), "--pace", "sensor"});
  };
  // Waits until the page has reported to this run's server from this run's session, with frames of it.
  const auto page_follows = [&](CliProcess& run, int min_updates, nlohmann::json& s) {
    return run.wait_until(
        [&] {
          s = state(port);
          return s.is_object() && s["client"].is_object() && s["client"]["session"] == s["session"] &&
                 s["client"]["updates"].get<int>() >= min_updates && s["client"]["frame"].get<int>() >= 0;
        },
        90);
  };
  auto first = start_run("first");
  ASSERT_TRUE(first->wait_until([&] { return state(port).is_object(); }, 60)) << first->current_stderr();
  start_chromium("http://127.0.0.1:" + std::to_string(port) + "/", dir / "profile", "", 150);
  nlohmann::json s;
  ASSERT_TRUE(page_follows(*first, 5, s)) << s.dump() << first->current_stderr();
  const std::string first_session = s["session"];
  first->send_signal(SIGINT);
  EXPECT_EQ(first->wait(60).exit_code, 130);
  // A while with nothing on the port (the user starting the next run): the page keeps trying.
  std::this_thread::sleep_for(4s);

  auto second = start_run("second");
  ASSERT_TRUE(page_follows(*second, 5, s)) << s.dump() << second->current_stderr();
  EXPECT_NE(s["session"], first_session);
  // The page started afresh: the frames it shows are the new run's (which is still early on), and it
  // logged no JavaScript error through the switch.
  const int page_frame = s["client"]["frame"].get<int>();
  EXPECT_LE(page_frame, s["run"]["frames"].get<int>()) << s.dump();
  EXPECT_EQ(s["client"]["errors"].get<int>(), 0) << s.dump();
  second->send_signal(SIGINT);
  EXPECT_EQ(second->wait(60).exit_code, 130);
}

TEST(ViewerChromium, APortInUseFailsTheRunBeforeItStarts) {
  TempDir dir;
  const auto seq = dir / "seq";
  ASSERT_EQ(run_cli({"-q", "synth", "--out", seq.string(), "--frames", "5", "--width", "320", "--height", "240"}).exit_code, 0);
  httplib::Server blocker;
  const int port = blocker.bind_to_any_port("127.0.0.1");
  ASSERT_GT(port, 0);
  const auto r = run_cli({"run", "--dataset", seq.string(), "--out", (dir / "out").string(), "--viewer", "--viewer-port",
                          std::to_string(port)});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--viewer-port " + std::to_string(port)), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
}
