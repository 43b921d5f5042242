// The live viewer against hostile clients (issue 37): open event streams and slowloris sockets never
// block the page, /state or the controls, and too many clients get a 503 (finding 5); the body POSTed
// to /client is parsed, so /state stays one valid document (11); a pause whose viewer went away resumes
// after a timeout (8); a pause stops a paced replay's clock too (2). Real sockets on 127.0.0.1.
#include <gtest/gtest.h>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "crowdslam/run/sensor_pacer.h"
#include "crowdslam/run/viewer_session.h"
#include "crowdslam/viewer/event_stream.h"
#include "crowdslam/viewer/run_control.h"
#include "crowdslam/viewer/viewer_server.h"

using namespace crowdslam;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

namespace {

// A raw TCP connection to 127.0.0.1:port.
class Socket {
 public:
  explicit Socket(int port) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(static_cast<uint16_t>(port));
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0;
  }
  ~Socket() { ::close(fd_); }
  Socket(const Socket&) = delete;
  Socket& operator=(const Socket&) = delete;
  [[nodiscard]] bool connected() const { return connected_; }
  bool send(const std::string& data) { return ::send(fd_, data.data(), data.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(data.size()); }
  // What arrives within `timeout` (until the peer closes, or `until` is seen).
  std::string receive(std::chrono::milliseconds timeout, const std::string& until = "") {
    std::string got;
    const auto deadline = Clock::now() + timeout;
    while (Clock::now() < deadline) {
      pollfd p{fd_, POLLIN, 0};
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
      if (::poll(&p, 1, static_cast<int>(std::max<long long>(left, 1))) <= 0) continue;
      char buffer[4096];
      const ssize_t n = ::recv(fd_, buffer, sizeof buffer, 0);
      if (n <= 0) break;
      got.append(buffer, static_cast<size_t>(n));
      if (!until.empty() && got.find(until) != std::string::npos) break;
    }
    return got;
  }

 private:
  int fd_ = -1;
  bool connected_ = false;
};

// A whole request on a fresh connection; the response (status line to end), or "" after `timeout`.
std::string request(int port, const std::string& method, const std::string& path, const std::string& body = "",
                    std::chrono::milliseconds timeout = 2000ms) {
  Socket s(port);
  if (!s.connected()) return "";
  s.send(method + " " + path + " HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: " + std::to_string(body.size()) +
         "\r\n\r\n" + body);
  return s.receive(timeout);
}

std::string body_of(const std::string& response) {
  const auto end = response.find("\r\n\r\n");
  return end == std::string::npos ? "" : response.substr(end + 4);
}

struct LiveServer {
  explicit LiveServer(viewer::HttpServerOptions http = {}) {
    viewer::ViewerServerOptions options;
    options.port = 0;
    options.http = http;
    server = std::make_unique<viewer::ViewerServer>(options, stream, &control, [this] {
      return std::string("{\"frames\":7,\"paused\":") + (control.paused() ? "true" : "false") + "}";
    });
    server->start();
  }
  viewer::EventStream stream;
  viewer::RunControl control;
  std::unique_ptr<viewer::ViewerServer> server;
};

}  // namespace

// Finding 11: the body was pasted raw into /state (a second "run" key, or an invalid document).
TEST(ViewerHostile, ClientReportIsParsedAndStateStaysOneValidDocument) {
  LiveServer live;
  const int port = live.server->port();
  for (const std::string& bad : {std::string("{\"x\":1},\"run\":{\"finished\":true,\"frames\":-1},\"zz\":{}"),
                                std::string("not json"), std::string("[1,2]"), std::string("{\"a\":"),
                                std::string("{}") + std::string(2000, ' ')}) {
    SCOPED_TRACE(bad.substr(0, 60));
    EXPECT_EQ(request(port, "POST", "/client", bad).rfind("HTTP/1.1 400", 0), 0u);
    const auto state = nlohmann::json::parse(body_of(request(port, "GET", "/state")));
    EXPECT_EQ(state["run"]["frames"], 7);
    EXPECT_TRUE(state["client"].is_null());
  }
  EXPECT_EQ(request(port, "POST", "/client", "{\"updates\": 3, \"note\": \"a \\\"quoted\\\" word\"}").rfind("HTTP/1.1 200", 0), 0u);
  const auto state = nlohmann::json::parse(body_of(request(port, "GET", "/state")));
  EXPECT_EQ(state["client"]["updates"], 3);
  EXPECT_EQ(state["client"]["note"], "a \"quoted\" word");
}

// The end of a run reaches every open event stream: stop() lets them write what is left ("finish" after
// the last frames) before the connections close; one that does not read is cut off after the drain time.
TEST(ViewerHostile, StoppingDeliversTheLastEventsToOpenStreams) {
  LiveServer live;
  const int port = live.server->port();
  std::vector<std::unique_ptr<Socket>> streams;
  for (int i = 0; i < 3; ++i) {
    streams.push_back(std::make_unique<Socket>(port));
    streams.back()->send(std::string("GET /events?image=0") + (i == 2 ? "&batch_ms=500" : "") +
                         " HTTP/1.1\r\nHost: x\r\n\r\n");
    ASSERT_NE(streams.back()->receive(2000ms, "event: session").find("event: session"), std::string::npos);
  }
  Socket idle(port);  // never reads: its stream fills its socket buffer, then the drain time ends it
  idle.send("GET /events HTTP/1.1\r\nHost: x\r\n\r\n");
  for (int i = 0; i < 50; ++i) live.stream.publish("frame", "{\"index\":" + std::to_string(i) + "}");
  live.stream.publish("finish", "{\"end_state\":\"completed\"}");
  const auto start = Clock::now();
  live.server->stop();
  EXPECT_LT(Clock::now() - start, 3000ms);
  for (auto& s : streams) {
    const auto got = s->receive(2000ms);  // until the server closes the connection
    EXPECT_NE(got.find("event: finish"), std::string::npos) << got.substr(0, 300);
  }
}

// Finding 5: 8 open event streams took all 8 worker threads; slowloris sockets starved /state.
TEST(ViewerHostile, OpenStreamsAndSlowlorisNeverBlockTheControlsOrThePage) {
  viewer::HttpServerOptions http;
  http.request_timeout = 1500ms;
  LiveServer live(http);
  const int port = live.server->port();
  std::vector<std::unique_ptr<Socket>> streams, slow;
  for (int i = 0; i < 12; ++i) {
    streams.push_back(std::make_unique<Socket>(port));
    streams.back()->send("GET /events?image=0 HTTP/1.1\r\nHost: x\r\n\r\n");
    EXPECT_NE(streams.back()->receive(2000ms, "event: session").find("text/event-stream"), std::string::npos);
  }
  for (int i = 0; i < 10; ++i) {
    slow.push_back(std::make_unique<Socket>(port));
    slow.back()->send("GET /state HTTP/1.1\r\n");
  }
  std::atomic<bool> trickle{true};
  std::thread slowloris([&] {  // one header line a second... here every 200 ms
    for (int line = 0; trickle; ++line) {
      for (auto& s : slow) s->send("X-Slow-" + std::to_string(line) + ": 1\r\n");
      std::this_thread::sleep_for(200ms);
    }
  });
  for (int probe = 0; probe < 10; ++probe) {
    const auto start = Clock::now();
    const auto state = request(port, "GET", "/state", "", 1000ms);
    EXPECT_EQ(state.rfind("HTTP/1.1 200", 0), 0u) << "probe " << probe;
    EXPECT_LT(Clock::now() - start, 1000ms);
  }
  EXPECT_NE(request(port, "POST", "/control/pause", "", 1000ms).find("{\"paused\":true}"), std::string::npos);
  EXPECT_NE(request(port, "POST", "/control/resume", "", 1000ms).find("{\"paused\":false}"), std::string::npos);
  EXPECT_NE(request(port, "GET", "/", "", 1000ms).find("crowdslam viewer"), std::string::npos);
  // The slowloris sockets are cut off once their request takes longer than the request timeout.
  std::this_thread::sleep_for(1600ms);
  trickle = false;
  slowloris.join();
  for (auto& s : slow) {
    const auto answer = s->receive(1000ms);
    EXPECT_TRUE(answer.empty() || answer.rfind("HTTP/1.1 408", 0) == 0) << answer;
  }
  // The streams are still alive.
  live.stream.publish("status", "{\"still\":1}");
  for (auto& s : streams) EXPECT_NE(s->receive(2000ms, "still").find("still"), std::string::npos);
}

// Finding 5: caps on streams and connections, answered with a clear 503.
TEST(ViewerHostile, TooManyClientsGetA503) {
  viewer::HttpServerOptions http;
  http.max_streams = 3;
  http.max_connections = 6;
  LiveServer live(http);
  const int port = live.server->port();
  std::vector<std::unique_ptr<Socket>> streams;
  for (int i = 0; i < 3; ++i) {
    streams.push_back(std::make_unique<Socket>(port));
    streams.back()->send("GET /events HTTP/1.1\r\n\r\n");
    EXPECT_NE(streams.back()->receive(2000ms, "event: session").find("200 OK"), std::string::npos);
  }
  const auto fourth = request(port, "GET", "/events");
  EXPECT_EQ(fourth.rfind("HTTP/1.1 503", 0), 0u) << fourth;
  EXPECT_NE(fourth.find("too many viewers"), std::string::npos);
  // Three streams and three idle sockets fill the connections: the next gets a 503 at once. (The server
  // counts a connection until it has finished with it, a moment after the client saw its answer.)
  const auto wait_for_connections = [&](size_t n) {
    for (const auto until = Clock::now() + 3s; Clock::now() < until && live.server->connections() != n;)
      std::this_thread::sleep_for(10ms);
    return live.server->connections();
  };
  ASSERT_EQ(wait_for_connections(3), 3u);
  std::vector<std::unique_ptr<Socket>> idle;
  for (int i = 0; i < 3; ++i) idle.push_back(std::make_unique<Socket>(port));
  ASSERT_EQ(wait_for_connections(6), 6u);
  const auto full = request(port, "GET", "/state");
  EXPECT_EQ(full.rfind("HTTP/1.1 503", 0), 0u) << "[" << full << "]";
  idle.clear();  // they go away: served again
  ASSERT_EQ(wait_for_connections(3), 3u);
  EXPECT_EQ(request(port, "GET", "/state").rfind("HTTP/1.1 200", 0), 0u);
}

// Finding 8: a paused run whose page went away stayed paused for ever.
TEST(ViewerHostile, APauseWithoutClientsResumesAfterTheIdleTimeout) {
  viewer::RunControl control;
  control.pause();
  size_t clients = 1;
  std::atomic<bool> stop{false};
  // A client is connected: still paused after longer than the timeout.
  std::thread stopper([&] {
    std::this_thread::sleep_for(700ms);
    stop = true;
  });
  auto wait = control.wait_while_paused([&] { return stop.load(); }, [&] { return clients; }, 300ms);
  stopper.join();
  EXPECT_FALSE(wait.idle_resumed);
  EXPECT_TRUE(control.paused());
  EXPECT_GE(wait.paused, 600ms);
  // No client: resumes after the timeout.
  clients = 0;
  const auto start = Clock::now();
  wait = control.wait_while_paused([] { return false; }, [&] { return clients; }, 300ms);
  EXPECT_TRUE(wait.idle_resumed);
  EXPECT_FALSE(control.paused());
  EXPECT_GE(Clock::now() - start, 300ms);
  EXPECT_LT(Clock::now() - start, 1500ms);
  EXPECT_TRUE(run::is_loopback_host("127.0.0.1"));
  EXPECT_TRUE(run::is_loopback_host("localhost"));
  EXPECT_TRUE(run::is_loopback_host("::1"));
  EXPECT_FALSE(run::is_loopback_host("0.0.0.0"));
  EXPECT_FALSE(run::is_loopback_host("192.168.1.4"));
}

// Finding 2: a pause of a paced replay dropped every frame that "arrived" meanwhile.
TEST(ViewerHostile, APauseStopsTheSensorClock) {
  for (const bool shifted : {false, true}) {
    run::SensorPacer pacer;
    EXPECT_TRUE(pacer.admit(10.0));
    EXPECT_TRUE(pacer.admit(10.05));
    std::this_thread::sleep_for(400ms);  // paused
    if (shifted) pacer.shift(400ms);
    const bool admitted = pacer.admit(10.10);
    EXPECT_EQ(admitted, shifted);
    EXPECT_EQ(pacer.dropped(), shifted ? 0u : 1u);
  }
}
