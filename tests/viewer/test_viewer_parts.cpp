// The live viewer's parts (issue 13): the event stream, the pause control, the HTTP server's routes,
// refusals, a port in use and clients that go away.
#include <gtest/gtest.h>
// Before httplib.h: it includes <resolv.h>, whose _res macro breaks Eigen's headers.
#include "crowdslam/viewer/viewer_observer.h"

#include <httplib.h>

#include <opencv2/core.hpp>

#include <atomic>
#include <chrono>
#include <thread>

#include "crowdslam/util/error.h"
#include "crowdslam/viewer/event_stream.h"
#include "crowdslam/viewer/run_control.h"
#include "crowdslam/viewer/viewer_server.h"

using namespace crowdslam;
using namespace std::chrono_literals;

TEST(EventStream, NewClientGetsTheNewestOfEachEventThenEverythingLive) {
  viewer::EventStream stream(4);
  stream.publish("map", "{\"m\":1}");
  stream.publish("frame", "{\"f\":1}");
  stream.publish("map", "{\"m\":2}");
  viewer::EventStream::Cursor cursor;
  auto first = stream.wait(cursor, 10ms);
  ASSERT_EQ(first.size(), 2u);  // frame 1, map 2 (in publishing order), not map 1
  EXPECT_EQ(*first[0], "event: frame\ndata: {\"f\":1}\n\n");
  EXPECT_EQ(*first[1], "event: map\ndata: {\"m\":2}\n\n");
  EXPECT_TRUE(stream.wait(cursor, 10ms).empty());  // nothing new: times out
  for (int i = 0; i < 6; ++i) stream.publish("frame", std::to_string(i));
  const auto live = stream.wait(cursor, 10ms);
  ASSERT_EQ(live.size(), 4u);  // bounded: only the newest 4 are kept
  EXPECT_EQ(*live.back(), "event: frame\ndata: 5\n\n");
}

TEST(EventStream, AClientThatSkipsAnEventNeverGetsItAndPastResetsAreNotReplayed) {
  viewer::EventStream stream;
  stream.publish("image", "1");
  stream.publish("frame", "1");
  stream.publish("reset", "{}", false);  // not retained for late clients
  viewer::EventStream::Cursor no_images;
  no_images.skip = {"image"};
  auto first = stream.wait(no_images, 10ms);
  ASSERT_EQ(first.size(), 1u);  // the newest frame: no image, no past reset
  EXPECT_EQ(*first[0], "event: frame\ndata: 1\n\n");
  stream.publish("image", "2");
  stream.publish("frame", "2");
  const auto live = stream.wait(no_images, 10ms);
  ASSERT_EQ(live.size(), 1u);
  EXPECT_EQ(*live[0], "event: frame\ndata: 2\n\n");
  viewer::EventStream::Cursor everything;
  EXPECT_EQ(stream.wait(everything, 10ms).size(), 2u);  // newest image and frame
}

TEST(EventStream, AnEventIsTakenWhileARegisteredClientDoesNotSkipIt) {
  viewer::EventStream stream;
  EXPECT_FALSE(stream.taken("image"));  // nobody connected
  auto hides_image = stream.register_client({"image"});
  EXPECT_FALSE(stream.taken("image"));
  EXPECT_TRUE(stream.taken("frame"));
  {
    auto shows_image = stream.register_client({});
    EXPECT_TRUE(stream.taken("image"));
  }
  EXPECT_FALSE(stream.taken("image"));  // released with its handle
  hides_image.reset();
  EXPECT_FALSE(stream.taken("frame"));
}

TEST(ViewerObserver, EncodesImagesOnlyWhileAPageTakesThem) {
  viewer::EventStream stream;
  viewer::ViewerObserverOptions options;
  options.frame_interval_s = 0;  // every frame's status and image (no timing in the test)
  options.image_interval_s = 0;
  io::FrameImages images;
  images.colour = cv::Mat(48, 64, CV_8UC3, cv::Scalar(10, 20, 30));
  system::FrameReport report;
  {
    viewer::ViewerObserver observer(stream, nullptr, options);
    observer.on_frame(report, std::nullopt, images);  // no page connected
    auto hides_image = stream.register_client({"image"});
    report.index = 1;
    observer.on_frame(report, std::nullopt, images);
    auto shows_image = stream.register_client({});
    report.index = 2;
    observer.on_frame(report, std::nullopt, images);
    observer.stop();  // publishes what it queued
  }
  viewer::EventStream::Cursor all;
  all.started = true;  // everything from the start, not just the newest of each event
  size_t frames = 0, image_messages = 0;
  std::string image;
  for (const auto& m : stream.wait(all, 10ms)) {
    if (m->rfind("event: frame\n", 0) == 0) ++frames;
    if (m->rfind("event: image\n", 0) == 0) {
      ++image_messages;
      image = *m;
    }
  }
  EXPECT_EQ(frames, 3u);
  EXPECT_EQ(image_messages, 1u);
  EXPECT_NE(image.find("\"index\":2"), std::string::npos) << image.substr(0, 200);
}

TEST(EventStream, CloseWakesAWaitingClientAtOnce) {
  viewer::EventStream stream;
  viewer::EventStream::Cursor cursor;
  stream.wait(cursor, 1ms);
  std::atomic<bool> returned{false};
  std::thread client([&] {
    stream.wait(cursor, 10s);
    returned = true;
  });
  std::this_thread::sleep_for(50ms);
  EXPECT_FALSE(returned);
  const auto start = std::chrono::steady_clock::now();
  stream.close();
  client.join();
  EXPECT_TRUE(returned);
  EXPECT_LT(std::chrono::steady_clock::now() - start, 2s);
  EXPECT_TRUE(stream.closed());
  stream.publish("frame", "{}");  // ignored once closed
  EXPECT_EQ(stream.published(), 0u);
}

TEST(EventStream, ABatchingClientGetsOneBatchWithOnlyTheNewestMapAndEveryFrame) {
  viewer::EventStream stream;
  viewer::EventStream::Cursor cursor;
  cursor.gather = 300ms;
  cursor.newest_only = {"map"};
  stream.wait(cursor, 1ms);  // started: nothing retained yet
  std::vector<viewer::EventStream::Message> batch;
  std::thread client([&] { batch = stream.wait(cursor, 10s); });
  // Published while the client gathers: map 1, frame 1, map 2, frame 2, map 3.
  for (int k = 1; k <= 3; ++k) {
    stream.publish("map", "{\"m\":" + std::to_string(k) + "}");
    if (k < 3) stream.publish("frame", "{\"f\":" + std::to_string(k) + "}");
    std::this_thread::sleep_for(20ms);
  }
  client.join();
  std::vector<std::string> got;
  for (const auto& m : batch) got.push_back(*m);
  const std::vector<std::string> expected = {"event: frame\ndata: {\"f\":1}\n\n", "event: frame\ndata: {\"f\":2}\n\n",
                                             "event: map\ndata: {\"m\":3}\n\n"};
  EXPECT_EQ(got, expected);
  // A client that does not batch gets every message as it comes.
  viewer::EventStream::Cursor plain;
  stream.wait(plain, 1ms);
  stream.publish("map", "{\"m\":4}");
  stream.publish("map", "{\"m\":5}");
  EXPECT_EQ(stream.wait(plain, 1s).size(), 2u);
}

TEST(EventStream, ABatchingClientIsWokenAtOnceWhenTheStreamCloses) {
  viewer::EventStream stream;
  viewer::EventStream::Cursor cursor;
  cursor.gather = 5s;
  stream.wait(cursor, 1ms);
  stream.publish("frame", "{}");
  const auto start = std::chrono::steady_clock::now();
  std::thread closer([&] {
    std::this_thread::sleep_for(50ms);
    stream.close();
  });
  const auto batch = stream.wait(cursor, 10s);
  closer.join();
  EXPECT_LT(std::chrono::steady_clock::now() - start, 2s);
  EXPECT_EQ(batch.size(), 1u);  // what was published before closing still goes out
}

TEST(RunControl, PauseBlocksTheRunUntilStepLetsExactlyOneFrameThrough) {
  viewer::RunControl control;
  control.wait_while_paused(nullptr);  // running: returns at once
  control.pause();
  std::atomic<int> frames{0};
  std::atomic<bool> stop{false};
  std::thread run([&] {
    while (!stop) {
      control.wait_while_paused([&] { return stop.load(); });
      if (!stop) ++frames;
    }
  });
  std::this_thread::sleep_for(150ms);
  EXPECT_EQ(frames, 0);
  control.step();
  std::this_thread::sleep_for(250ms);
  EXPECT_EQ(frames, 1);
  control.resume();
  std::this_thread::sleep_for(50ms);
  EXPECT_GT(frames, 1);
  control.pause();
  stop = true;
  run.join();
  EXPECT_TRUE(control.paused());
}

namespace {
viewer::ViewerServerOptions any_port() {
  viewer::ViewerServerOptions options;
  options.port = 0;
  return options;
}
}  // namespace

TEST(ViewerServer, ServesItsAssetsOnlyAndNoFileSystemPath) {
  viewer::EventStream stream;
  viewer::ViewerServer server(any_port(), stream, nullptr, [] { return std::string("{\"frames\":3}"); });
  server.start();
  httplib::Client client("127.0.0.1", server.port());
  const auto page = client.Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("crowdslam viewer"), std::string::npos);
  EXPECT_NE(page->body.find("/three.min.js"), std::string::npos);
  EXPECT_EQ(page->body.find("http://"), std::string::npos);  // nothing from the network
  EXPECT_EQ(page->body.find("https://"), std::string::npos);
  const auto three = client.Get("/three.min.js");
  ASSERT_TRUE(three);
  EXPECT_EQ(three->status, 200);
  EXPECT_GT(three->body.size(), 100000u);
  const auto controls = client.Get("/OrbitControls.js");
  ASSERT_TRUE(controls);
  EXPECT_NE(controls->body.find("OrbitControls"), std::string::npos);
  for (const char* path : {"/../../../../etc/passwd", "/etc/passwd", "/usr/share/javascript/three/three.min.js",
                           "/%2e%2e/%2e%2e/etc/passwd", "/three.min.js/../../etc/passwd", "/index.html~"}) {
    const auto r = client.Get(path);
    ASSERT_TRUE(r) << path;
    EXPECT_EQ(r->status, 404) << path;
  }
  const auto state = client.Get("/state");
  ASSERT_TRUE(state);
  EXPECT_EQ(state->body, "{\"session\":\"" + server.session() + "\",\"run\":{\"frames\":3},\"client\":null}");
  // Another server (the next run on this port) has another session.
  viewer::EventStream other_stream;
  viewer::ViewerServer other(any_port(), other_stream, nullptr, [] { return std::string("{}"); });
  EXPECT_NE(other.session(), server.session());
  const auto pause = client.Post("/control/pause", "", "text/plain");
  ASSERT_TRUE(pause);
  EXPECT_EQ(pause->status, 409);  // a finished result cannot be paused
  const auto report = client.Post("/client", "{\"updates\":4}", "application/json");
  ASSERT_TRUE(report);
  EXPECT_EQ(server.client_report(), "{\"updates\":4}");
  EXPECT_EQ(client.Post("/client", std::string(5000, 'x'), "application/json")->status, 400);
}

TEST(ViewerServer, APortInUseIsAClearErrorBeforeAnythingRuns) {
  viewer::EventStream a, b;
  viewer::ViewerServer first(any_port(), a, nullptr, nullptr);
  first.start();
  viewer::ViewerServerOptions same;
  same.port = first.port();
  viewer::ViewerServer second(same, b, nullptr, nullptr);
  try {
    second.start();
    FAIL() << "a second server on port " << same.port << " must fail";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--viewer-port " + std::to_string(same.port)), std::string::npos) << e.what();
  }
  viewer::ViewerServerOptions bad;
  bad.port = 70000;
  EXPECT_THROW(viewer::ViewerServer(bad, b, nullptr, nullptr), InputError);
}

TEST(ViewerServer, AClientLeavingMidStreamDoesNotDisturbTheOthers) {
  viewer::EventStream stream;
  viewer::RunControl control;
  viewer::ViewerServer server(any_port(), stream, &control, nullptr);
  server.start();
  std::atomic<bool> publishing{true};
  std::thread producer([&] {
    for (int i = 0; publishing; ++i) {
      stream.publish("frame", "{\"index\":" + std::to_string(i) + "}");
      std::this_thread::sleep_for(5ms);
    }
  });
  // A client that reads a little of the stream and hangs up.
  {
    httplib::Client client("127.0.0.1", server.port());
    size_t received = 0;
    const auto r = client.Get("/events", [&](const char*, size_t n) {
      received += n;
      return received < 200;  // false: abort the download
    });
    EXPECT_GE(received, 200u);
  }
  // Others are still served, and the controls work.
  httplib::Client other("127.0.0.1", server.port());
  size_t received = 0;
  other.Get("/events", [&](const char*, size_t n) {
    received += n;
    return received < 500;
  });
  EXPECT_GE(received, 500u);
  const auto pause = other.Post("/control/pause", "", "text/plain");
  ASSERT_TRUE(pause);
  EXPECT_EQ(pause->body, "{\"paused\":true}");
  EXPECT_TRUE(control.paused());
  publishing = false;
  producer.join();
  const auto start = std::chrono::steady_clock::now();
  server.stop();
  EXPECT_LT(std::chrono::steady_clock::now() - start, 3s);
}
