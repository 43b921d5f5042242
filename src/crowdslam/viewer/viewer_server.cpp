#include "crowdslam/viewer/viewer_server.h"

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <thread>

#include <unistd.h>

#include "crowdslam/viewer/http_server.h"

#include "crowdslam/util/error.h"

#ifndef CROWDSLAM_THREE_DIR
#define CROWDSLAM_THREE_DIR "/usr/share/javascript/three"
#endif

namespace crowdslam::viewer {

namespace {
std::string read_asset(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw InputError(path + ": cannot read the viewer's three.js (install Debian's libjs-three, or point "
                            "CROWDSLAM_THREE_DIR at a three.js r111+ directory with three.min.js and "
                            "examples/js/controls/OrbitControls.js)");
  }
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}
// A query parameter of up to 5 digits; 0 when absent or anything else.
int small_number(const std::string& value) {
  if (value.empty() || value.size() > 5 || value.find_first_not_of("0123456789") != std::string::npos) return 0;
  return std::stoi(value);
}
}  // namespace

void ViewerServerOptions::check() const {
  if (host.empty()) throw InputError("--viewer-host: empty");
  if (port < 0 || port > 65535) throw InputError("--viewer-port: " + std::to_string(port) + " is not a port (0-65535)");
}

ViewerServer::ViewerServer(ViewerServerOptions options, EventStream& stream, RunControl* control,
                           std::function<std::string()> state_json)
    : options_(std::move(options)), stream_(stream), control_(control), state_json_(std::move(state_json)) {
  options_.check();
  static std::atomic<unsigned> servers{0};
  session_ = std::to_string(::getpid()) + "-" +
             std::to_string(std::chrono::system_clock::now().time_since_epoch() / std::chrono::milliseconds(1)) + "-" +
             std::to_string(servers++);
}

ViewerServer::~ViewerServer() { stop(); }

std::string ViewerServer::client_report() const {
  std::lock_guard lock(client_mutex_);
  return client_report_;
}

std::string ViewerServer::url() const { return "http://" + options_.host + ":" + std::to_string(port_) + "/"; }

void ViewerServer::start() {
  std::string dir = options_.three_dir;
  if (dir.empty()) {
    const char* env = std::getenv("CROWDSLAM_THREE_DIR");
    dir = env && *env ? env : CROWDSLAM_THREE_DIR;
  }
  three_js_ = read_asset(dir + "/three.min.js");
  orbit_controls_js_ = read_asset(dir + "/examples/js/controls/OrbitControls.js");

  server_ = std::make_unique<HttpServer>(options_.http);
  auto& s = *server_;
  if (std::getenv("CROWDSLAM_VIEWER_LOG")) {
    s.set_logger([](const std::string& method, const std::string& path, int status) {
      spdlog::info("viewer: {} {} -> {}", method, path, status);
    });
  }
  s.route("GET", "/", [](const HttpRequest&, HttpResponse& res) {
    res.content_type = "text/html; charset=utf-8";
    res.body = viewer_page_html();
  });
  s.route("GET", "/three.min.js", [this](const HttpRequest&, HttpResponse& res) {
    res.content_type = "text/javascript";
    res.body = three_js_;
  });
  s.route("GET", "/OrbitControls.js", [this](const HttpRequest&, HttpResponse& res) {
    res.content_type = "text/javascript";
    res.body = orbit_controls_js_;
  });
  s.route("GET", "/state", [this](const HttpRequest&, HttpResponse& res) {
    const std::string client = client_report();
    res.content_type = "application/json";
    res.body = "{\"session\":\"" + session_ + "\",\"run\":" + (state_json_ ? state_json_() : std::string("{}")) +
               ",\"client\":" + (client.empty() ? std::string("null") : client) + "}";
  });
  s.route("POST", "/client", [this](const HttpRequest& req, HttpResponse& res) {
    // Only a small JSON object is kept (a page reporting its status; tests read it back), parsed and
    // written again by us: GET /state embeds it, and must stay one valid document.
    const auto parsed = req.body.size() < 1000 ? nlohmann::json::parse(req.body, nullptr, false) : nlohmann::json();
    res.content_type = "application/json";
    if (!parsed.is_object()) {
      res.status = 400;
      res.body = "{\"error\":\"expected a JSON object of under 1000 bytes\"}";
      return;
    }
    std::lock_guard lock(client_mutex_);
    client_report_ = parsed.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    res.body = "{}";
  });
  s.route("GET", "/events", [this](const HttpRequest& req, HttpResponse& res) {
    res.content_type = "text/event-stream";
    res.headers.emplace_back("Cache-Control", "no-cache");
    auto cursor = std::make_shared<EventStream::Cursor>();
    if (req.param("image") == "0") cursor->skip.insert("image");  // a page that hides its image
    const int image_width = small_number(req.param("image_width"));  // the width the page shows the image at (0: any)
    // batch_ms: a page that redraws every N ms takes one batch per N ms, with only the newest map and image.
    if (const int batch = small_number(req.param("batch_ms")); batch > 0) {
      cursor->gather = std::chrono::milliseconds(std::min(batch, 2000));
      cursor->newest_only = {"map", "image", "ground_truth", "trajectory"};
    }
    // Counted as connected while the response (and so this stream function) lives.
    auto registration = stream_.register_client(cursor->skip, image_width);
    // First the reconnection delay (a page left open reconnects within a second when the next run starts)
    // and this server's session.
    auto hello = std::make_shared<std::string>("retry: 1000\n\nevent: session\ndata: {\"id\":\"" + session_ + "\"}\n\n");
    res.stream = [this, cursor, registration, hello](const std::function<bool(const std::string&)>& write) {
      if (!hello->empty()) {
        if (!write(*hello)) return false;
        hello->clear();
      }
      const auto messages = stream_.wait(*cursor, std::chrono::milliseconds(500));
      for (const auto& m : messages) {
        if (!write(*m)) return false;  // the client went away
      }
      if (messages.empty()) {
        if (stream_.closed()) return false;  // the end of the run: the connection closes
        static const std::string keepalive = ": keepalive\n\n";
        if (!write(keepalive)) return false;
      }
      return true;
    };
  });
  const auto control = [this](const std::string& action) {
    return [this, action](const HttpRequest&, HttpResponse& res) {
      res.content_type = "application/json";
      if (!control_) {
        res.status = 409;
        res.body = "{\"error\":\"not a live run\"}";
        return;
      }
      if (action == "pause") control_->pause();
      if (action == "resume") control_->resume();
      if (action == "step") control_->step();
      res.body = std::string("{\"paused\":") + (control_->paused() ? "true" : "false") + "}";
    };
  };
  s.route("POST", "/control/pause", control("pause"));
  s.route("POST", "/control/resume", control("resume"));
  s.route("POST", "/control/step", control("step"));

  if (options_.host.empty()) throw InputError("--viewer-host: empty");
  port_ = s.bind(options_.host, options_.port);
  s.start();
}

void ViewerServer::stop() {
  stream_.close();
  // The event streams write what is left (the final map, "finish") and close by themselves; a client
  // that does not read is cut off after the drain time.
  const auto deadline = std::chrono::steady_clock::now() + options_.drain;
  while (server_ && stream_.clients() > 0 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (server_) server_->stop();
}

}  // namespace crowdslam::viewer
