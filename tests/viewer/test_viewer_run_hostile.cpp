// `crowdslam run --viewer` and `crowdslam view` against hostile use (issue 37): the URL is printed with
// --quiet and is the JSON document of `--json view` (finding 10, 9); a pause of a paced replay loses no
// frames (2); a paused run whose viewer went away resumes after --viewer-pause-timeout (8).
#include <gtest/gtest.h>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <csignal>
#include <string>
#include <thread>

#include "test_support.h"

using namespace crowdslam::test;
using namespace std::chrono_literals;

namespace {

// POST PATH with an empty body; true when the server answered 200.
bool post(int port, const std::string& path) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  bool ok = false;
  if (::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0) {
    const std::string request = "POST " + path + " HTTP/1.1\r\nHost: x\r\nContent-Length: 0\r\n\r\n";
    ::send(fd, request.data(), request.size(), MSG_NOSIGNAL);
    char buffer[512];
    const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
    ok = n > 12 && std::string(buffer, 12) == "HTTP/1.1 200";
  }
  ::close(fd);
  return ok;
}

std::filesystem::path synth(const TempDir& dir, int frames) {
  const auto seq = dir / "seq";
  const auto r = run_cli({"-q", "synth", "--out", seq.string(), "--frames", std::to_string(frames), "--width", "320",
                          "--height", "240"});
  if (r.exit_code != 0) throw std::runtime_error(r.err);
  return seq;
}

}  // namespace

// Findings 10 and 2: with -q the URL (here of a random port) is printed; a 2.5 s pause of a 1.3 s paced
// replay dropped every frame after it (7 of 40 processed); the sensor's clock now pauses too.
TEST(ViewerRunHostile, QuietPacedRunPrintsItsUrlAndAPauseDropsNoFrames) {
  TempDir dir;
  const auto seq = synth(dir, 40);
  CliProcess run({"-q", "--json", "run", "--dataset", seq.string(), "--out", (dir / "out").string(), "--pace", "sensor",
                  "--no-people-filter", "--vocabulary", "none", "--viewer", "--viewer-port", "0"});
  const int port = wait_for_viewer_port(run, 60);
  ASSERT_GT(port, 0) << run.current_stderr();
  ASSERT_TRUE(post(port, "/control/pause"));
  std::this_thread::sleep_for(2500ms);
  ASSERT_TRUE(post(port, "/control/resume"));
  const auto r = run.wait(120);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["end_state"], "completed");
  // The frames that "arrived" during the pause are not dropped for it (tracking may still drop a few).
  EXPECT_LT(doc["input"]["dropped_frames"].get<int>(), 15) << doc["input"].dump();
  EXPECT_GT(doc["summary"]["frames"].get<int>(), 25);
}

// Finding 8: a pause with no page connected resumes after --viewer-pause-timeout, with a warning.
TEST(ViewerRunHostile, APausedRunWithoutViewersResumesAfterTheTimeout) {
  TempDir dir;
  const auto seq = synth(dir, 20);
  CliProcess run({"-q", "run", "--dataset", seq.string(), "--out", (dir / "out").string(), "--no-people-filter",
                  "--vocabulary", "none", "--viewer", "--viewer-port", "0", "--viewer-pause-timeout", "1"});
  const int port = wait_for_viewer_port(run, 60);
  ASSERT_GT(port, 0) << run.current_stderr();
  ASSERT_TRUE(post(port, "/control/pause"));
  const auto r = run.wait(60);  // never resumed by anyone
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("resuming"), std::string::npos) << r.err;
}

// Findings 9 and 10: `--json view` prints one JSON document with the URL; a non-loopback host is warned
// about even with -q.
TEST(ViewerRunHostile, JsonViewPrintsTheUrlAsItsDocument) {
  TempDir dir;
  const auto seq = synth(dir, 20);
  const auto out = dir / "out";
  ASSERT_EQ(run_cli({"-q", "run", "--dataset", seq.string(), "--out", out.string(), "--no-people-filter", "--vocabulary",
                     "none"})
                .exit_code,
            0);
  CliProcess view({"-q", "--json", "view", out.string(), "--viewer-port", "0", "--viewer-host", "0.0.0.0"});
  std::string err;
  view.wait_until([&] { return view.current_stderr().find("viewer: http://0.0.0.0:") != std::string::npos; }, 30);
  view.send_signal(SIGINT);
  const auto r = view.wait(30);
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["url"].get<std::string>().rfind("http://0.0.0.0:", 0), 0u) << r.out;
  EXPECT_GT(doc["port"].get<int>(), 0);
  EXPECT_NE(r.err.find("not a loopback address"), std::string::npos) << r.err;
}
