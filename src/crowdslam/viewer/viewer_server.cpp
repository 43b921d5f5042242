#include "crowdslam/viewer/viewer_server.h"

#include <httplib.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <thread>

#include <unistd.h>

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
int small_number(const httplib::Request& req, const char* name) {
  const std::string value = req.get_param_value(name);
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

  server_ = std::make_unique<httplib::Server>();
  auto& s = *server_;
  // SO_REUSEADDR only (httplib also sets SO_REUSEPORT, which would let a second server share a port in use).
  s.set_socket_options([](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
  });
  if (std::getenv("CROWDSLAM_VIEWER_LOG")) {
    s.set_logger([](const httplib::Request& req, const httplib::Response& res) {
      spdlog::info("viewer: {} {} -> {}", req.method, req.path, res.status);
    });
  }
  s.Get("/", [](const httplib::Request&, httplib::Response& res) {
    res.set_content(viewer_page_html(), "text/html; charset=utf-8");
  });
  s.Get("/three.min.js", [this](const httplib::Request&, httplib::Response& res) {
    res.set_content(three_js_, "text/javascript");
  });
  s.Get("/OrbitControls.js", [this](const httplib::Request&, httplib::Response& res) {
    res.set_content(orbit_controls_js_, "text/javascript");
  });
  s.Get("/state", [this](const httplib::Request&, httplib::Response& res) {
    const std::string client = client_report();
    res.set_content("{\"session\":\"" + session_ + "\",\"run\":" + (state_json_ ? state_json_() : std::string("{}")) +
                        ",\"client\":" + (client.empty() ? std::string("null") : client) + "}",
                    "application/json");
  });
  s.Post("/client", [this](const httplib::Request& req, httplib::Response& res) {
    // Only a small JSON object is kept (a page reporting its status; tests read it back).
    const bool plausible = req.body.size() < 1000 && !req.body.empty() && req.body.front() == '{' && req.body.back() == '}';
    if (!plausible) {
      res.status = 400;
      return;
    }
    std::lock_guard lock(client_mutex_);
    client_report_ = req.body;
    res.set_content("{}", "application/json");
  });
  s.Get("/events", [this](const httplib::Request& req, httplib::Response& res) {
    res.set_header("Cache-Control", "no-cache");
    auto cursor = std::make_shared<EventStream::Cursor>();
    if (req.get_param_value("image") == "0") cursor->skip.insert("image");  // a page that hides its image
    const int image_width = small_number(req, "image_width");  // the width the page shows the image at (0: any)
    // batch_ms: a page that redraws every N ms takes one batch per N ms, with only the newest map and image.
    if (const int batch = small_number(req, "batch_ms"); batch > 0) {
      cursor->gather = std::chrono::milliseconds(std::min(batch, 2000));
      cursor->newest_only = {"map", "image", "ground_truth", "trajectory"};
    }
    // Counted as connected while the response (and so this provider) lives.
    auto registration = stream_.register_client(cursor->skip, image_width);
    // First the reconnection delay (a page left open reconnects within a second when the next run starts)
    // and this server's session.
    auto hello = std::make_shared<std::string>("retry: 1000\n\nevent: session\ndata: {\"id\":\"" + session_ + "\"}\n\n");
    res.set_chunked_content_provider("text/event-stream", [this, cursor, registration, hello](size_t, httplib::DataSink& sink) {
      if (!hello->empty()) {
        if (!sink.write(hello->data(), hello->size())) return false;
        hello->clear();
      }
      const auto messages = stream_.wait(*cursor, std::chrono::milliseconds(500));
      for (const auto& m : messages) {
        if (!sink.write(m->data(), m->size())) return false;  // the client went away
      }
      if (messages.empty()) {
        if (stream_.closed()) {
          sink.done();
          return true;
        }
        static const std::string keepalive = ": keepalive\n\n";
        if (!sink.write(keepalive.data(), keepalive.size())) return false;
      }
      return true;
    });
  });
  const auto control = [this](const std::string& action) {
    return [this, action](const httplib::Request&, httplib::Response& res) {
      if (!control_) {
        res.status = 409;
        res.set_content("{\"error\":\"not a live run\"}", "application/json");
        return;
      }
      if (action == "pause") control_->pause();
      if (action == "resume") control_->resume();
      if (action == "step") control_->step();
      res.set_content(std::string("{\"paused\":") + (control_->paused() ? "true" : "false") + "}", "application/json");
    };
  };
  s.Post("/control/pause", control("pause"));
  s.Post("/control/resume", control("resume"));
  s.Post("/control/step", control("step"));

  if (options_.port == 0) {
    port_ = s.bind_to_any_port(options_.host);
    if (port_ <= 0) throw InputError("--viewer-host " + options_.host + ": cannot listen there");
  } else {
    if (!s.bind_to_port(options_.host, options_.port)) {
      throw InputError("--viewer-port " + std::to_string(options_.port) + ": cannot listen on " + options_.host + ":" +
                       std::to_string(options_.port) + " (in use, or not an address of this machine)");
    }
    port_ = options_.port;
  }
  auto returned = std::make_shared<std::atomic<bool>>(false);
  thread_ = std::thread([this, returned] {
    server_->listen_after_bind();
    *returned = true;
  });
  // httplib's stop() does nothing until listen has begun (it would leave the thread listening and
  // stop()'s join hanging), so start() returns only once the server runs.
  while (!server_->is_running() && !*returned) std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

void ViewerServer::stop() {
  stream_.close();
  if (server_) server_->stop();
  if (thread_.joinable()) thread_.join();
}

}  // namespace crowdslam::viewer
