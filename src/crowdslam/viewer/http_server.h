#pragma once
// A small HTTP/1.1 server for the viewer: a fixed table of routes, one request per connection
// ("Connection: close"), each connection on a thread of its own, so an open event stream or a slow
// client never holds up another request (the page, GET /state, POST /control/...).
//
// Bounds, so that no client can starve the others or the run:
//   - a request (request line, headers and body) must arrive within `request_timeout`, whatever pace
//     its bytes come at (a "slowloris" client that sends one header line a second is cut off), and
//     within `max_header_bytes` / `max_body_bytes`;
//   - at most `max_connections` connections at once, of which at most `max_streams` streaming responses
//     (event streams); a client beyond either gets "503 Service Unavailable" at once;
//   - a response the client does not read within `write_timeout` ends its connection.
// Thread-safe; handlers run on the connection's thread.
#include <atomic>
#include <chrono>
#include <functional>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace crowdslam::viewer {

struct HttpRequest {
  std::string method;                          // "GET", "POST"
  std::string path;                            // without the query
  std::map<std::string, std::string> query;    // decoded parameters
  std::map<std::string, std::string> headers;  // names in lower case
  std::string body;
  // A query parameter, "" when absent.
  [[nodiscard]] std::string param(const std::string& name) const;
};

struct HttpResponse {
  int status = 200;
  std::string content_type = "text/plain; charset=utf-8";
  std::string body;
  std::vector<std::pair<std::string, std::string>> headers;
  // A streaming response (Server-Sent Events) instead of `body`: after the headers it is called again and
  // again on the connection's thread with a writer (false once the client is gone) until it returns false
  // or the server stops. It should return within a second or so (the server checks for stop between calls).
  std::function<bool(const std::function<bool(const std::string&)>& write)> stream;
};

using HttpHandler = std::function<void(const HttpRequest&, HttpResponse&)>;

struct HttpServerOptions {
  size_t max_connections = 64;
  size_t max_streams = 16;
  std::chrono::milliseconds request_timeout{5000};
  std::chrono::milliseconds write_timeout{5000};
  size_t max_header_bytes = 16 * 1024;
  size_t max_body_bytes = 64 * 1024;
};

class HttpServer {
 public:
  explicit HttpServer(HttpServerOptions options = {});
  ~HttpServer();
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  void route(const std::string& method, const std::string& path, HttpHandler handler);
  // Optional: called after each request with its method, path and status (logging).
  void set_logger(std::function<void(const std::string&, const std::string&, int)> logger);
  // Binds host:port (0: any free port) and returns the port; InputError when it cannot.
  int bind(const std::string& host, int port);
  // Serves on a thread of its own (after bind()).
  void start();
  // Closes the listening socket and every connection, and joins all threads. Idempotent.
  void stop();
  [[nodiscard]] size_t connections() const { return connections_.load(); }
  [[nodiscard]] size_t streams() const { return streams_.load(); }

 private:
  struct Connection {
    int fd = -1;
    std::thread thread;
    std::atomic<bool> done{false};
  };
  void accept_loop();
  void serve(Connection& connection);
  void reap_finished();
  bool read_request(int fd, HttpRequest& request, int& error_status);
  bool write_all(int fd, const std::string& data);
  void respond(int fd, const HttpResponse& response);
  void stream_response(int fd, HttpResponse& response);

  const HttpServerOptions options_;
  std::map<std::pair<std::string, std::string>, HttpHandler> routes_;
  std::function<void(const std::string&, const std::string&, int)> logger_;
  int listen_fd_ = -1;
  std::thread accept_thread_;
  std::atomic<bool> stopping_{false};
  std::atomic<size_t> connections_{0};
  std::atomic<size_t> streams_{0};
  std::mutex mutex_;  // guards connections_list_ and each Connection's fd
  std::list<std::unique_ptr<Connection>> connections_list_;
};

// The reason phrase of a status code ("OK", "Not Found", ...).
const char* http_reason(int status);

}  // namespace crowdslam::viewer
