#pragma once
// The viewer's HTTP server (our own, http_server.h: a thread per connection, bounded requests, capped
// clients) in its own thread: the page, three.js (served from Debian's libjs-three, never a CDN), the
// Server-Sent Events stream, the run state and the pause/step/resume controls. It serves a fixed list of
// paths and nothing from the file system, binds to 127.0.0.1 unless told otherwise, and has no
// authentication (docs/VIEWER.md). Open event streams and slow clients never block the page, /state or
// the controls.
#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "crowdslam/viewer/event_stream.h"
#include "crowdslam/viewer/http_server.h"
#include "crowdslam/viewer/run_control.h"

namespace crowdslam::viewer {

struct ViewerServerOptions {
  std::string host = "127.0.0.1";
  int port = 8080;         // 0: any free port
  std::string three_dir;   // "" = $CROWDSLAM_THREE_DIR or the Debian path (/usr/share/javascript/three)
  HttpServerOptions http;  // connection and stream caps, request and write timeouts
  // stop(): how long open event streams get to write what is left (the end of the run) before the
  // connections are closed.
  std::chrono::milliseconds drain{2000};
  void check() const;      // throws InputError naming the bad option
};

class ViewerServer {
 public:
  // `control` may be null (a finished result: no pause/step). `state_json` gives GET /state.
  ViewerServer(ViewerServerOptions options, EventStream& stream, RunControl* control,
               std::function<std::string()> state_json);
  ~ViewerServer();
  ViewerServer(const ViewerServer&) = delete;
  ViewerServer& operator=(const ViewerServer&) = delete;

  // Reads the assets and binds the port (InputError when three.js is missing or the port is taken), then
  // serves on its own thread.
  void start();
  // Closes the event stream (clients see its end) and stops the server. Idempotent.
  void stop();
  [[nodiscard]] int port() const { return port_; }
  [[nodiscard]] std::string url() const;
  // The last status a page posted (POST /client: updates received, JavaScript errors, WebGL), "" if none.
  [[nodiscard]] std::string client_report() const;
  // Unique to this server (process and start time): every event stream begins with it, so that a page
  // left open across runs sees a new run when it reconnects and starts afresh. GET /state shows it.
  [[nodiscard]] const std::string& session() const { return session_; }
  // Connections open now (each counted until the server has finished with it); 0 before start().
  [[nodiscard]] size_t connections() const { return server_ ? server_->connections() : 0; }

 private:
  ViewerServerOptions options_;
  EventStream& stream_;
  RunControl* control_;
  std::function<std::string()> state_json_;
  std::unique_ptr<HttpServer> server_;
  int port_ = 0;
  std::string three_js_, orbit_controls_js_;
  std::string session_;
  mutable std::mutex client_mutex_;
  std::string client_report_;
};

// The page (viewer/page.cpp).
const std::string& viewer_page_html();

}  // namespace crowdslam::viewer
