#include "crowdslam/viewer/http_server.h"

#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>

#include "crowdslam/util/error.h"

namespace crowdslam::viewer {

namespace {
using Clock = std::chrono::steady_clock;

int remaining_ms(Clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
  return left <= 0 ? 0 : static_cast<int>(std::min<long long>(left, 1000));
}

std::string lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

std::string percent_decode(const std::string& text) {
  std::string out;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '+') {
      out += ' ';
    } else if (text[i] == '%' && i + 2 < text.size() && std::isxdigit(static_cast<unsigned char>(text[i + 1])) &&
               std::isxdigit(static_cast<unsigned char>(text[i + 2]))) {
      out += static_cast<char>(std::stoi(text.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += text[i];
    }
  }
  return out;
}

void parse_query(const std::string& query, std::map<std::string, std::string>& params) {
  size_t start = 0;
  while (start <= query.size()) {
    size_t end = query.find('&', start);
    if (end == std::string::npos) end = query.size();
    const std::string pair = query.substr(start, end - start);
    if (!pair.empty()) {
      const size_t eq = pair.find('=');
      params[percent_decode(pair.substr(0, eq))] = eq == std::string::npos ? "" : percent_decode(pair.substr(eq + 1));
    }
    start = end + 1;
  }
}

std::string status_line(int status) {
  return "HTTP/1.1 " + std::to_string(status) + " " + http_reason(status) + "\r\n";
}

// A short answer written without waiting (a refused connection must not hold the accept loop).
void refuse(int fd, int status, const std::string& message) {
  const std::string body = "{\"error\":\"" + message + "\"}";
  const std::string response = status_line(status) + "Content-Type: application/json\r\nContent-Length: " +
                               std::to_string(body.size()) + "\r\nRetry-After: 1\r\nConnection: close\r\n\r\n" + body;
  const ssize_t ignored = ::send(fd, response.data(), response.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
  (void)ignored;
  ::shutdown(fd, SHUT_WR);
  // Read what the client sent (briefly): closing with unread input would reset the connection, and the
  // client could lose the answer. A client usually sends its request at once; on a loaded machine it may
  // take longer (50 ms lost the answer in 1 of about 4 loaded test-suite runs), so up to 250 ms. Only a
  // connection that sends nothing waits that long.
  char buffer[4096];
  pollfd p{fd, POLLIN, 0};
  if (::poll(&p, 1, 250) > 0) {
    while (::recv(fd, buffer, sizeof buffer, MSG_DONTWAIT) > 0) {
    }
  }
}
}  // namespace

std::string HttpRequest::param(const std::string& name) const {
  const auto it = query.find(name);
  return it == query.end() ? std::string() : it->second;
}

const char* http_reason(int status) {
  switch (status) {
    case 200: return "OK";
    case 400: return "Bad Request";
    case 404: return "Not Found";
    case 405: return "Method Not Allowed";
    case 408: return "Request Timeout";
    case 409: return "Conflict";
    case 413: return "Payload Too Large";
    case 431: return "Request Header Fields Too Large";
    case 500: return "Internal Server Error";
    case 503: return "Service Unavailable";
    default: return "Status";
  }
}

HttpServer::HttpServer(HttpServerOptions options) : options_(options) {}

HttpServer::~HttpServer() { stop(); }

void HttpServer::route(const std::string& method, const std::string& path, HttpHandler handler) {
  routes_[{method, path}] = std::move(handler);
}

void HttpServer::set_logger(std::function<void(const std::string&, const std::string&, int)> logger) {
  logger_ = std::move(logger);
}

int HttpServer::bind(const std::string& host, int port) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  addrinfo* found = nullptr;
  const std::string service = std::to_string(port);
  if (::getaddrinfo(host.c_str(), service.c_str(), &hints, &found) != 0 || found == nullptr) {
    throw InputError("--viewer-host " + host + ": not an address of this machine");
  }
  int fd = -1;
  for (addrinfo* a = found; a != nullptr && fd < 0; a = a->ai_next) {
    fd = ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
    if (fd < 0) continue;
    int yes = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);  // not SO_REUSEPORT: a port in use fails
    if (::bind(fd, a->ai_addr, a->ai_addrlen) != 0 || ::listen(fd, 64) != 0) {
      ::close(fd);
      fd = -1;
    }
  }
  ::freeaddrinfo(found);
  if (fd < 0) {
    throw InputError("--viewer-port " + std::to_string(port) + ": cannot listen on " + host + ":" +
                     std::to_string(port) + " (in use, or not an address of this machine)");
  }
  sockaddr_storage address{};
  socklen_t length = sizeof address;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
  listen_fd_ = fd;
  if (address.ss_family == AF_INET6) return ntohs(reinterpret_cast<sockaddr_in6*>(&address)->sin6_port);
  return ntohs(reinterpret_cast<sockaddr_in*>(&address)->sin_port);
}

void HttpServer::start() {
  if (listen_fd_ < 0 || accept_thread_.joinable()) return;
  accept_thread_ = std::thread([this] { accept_loop(); });
}

void HttpServer::accept_loop() {
  while (!stopping_) {
    pollfd p{listen_fd_, POLLIN, 0};
    if (::poll(&p, 1, 200) <= 0) {
      reap_finished();
      continue;
    }
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
    if (fd < 0) continue;
    reap_finished();
    if (stopping_ || connections_.load() >= options_.max_connections) {
      refuse(fd, 503, "too many connections to the viewer; try again later");
      ::close(fd);
      continue;
    }
    const int flags = ::fcntl(fd, F_GETFL, 0);
    ::fcntl(fd, F_SETFL, flags | O_NONBLOCK);
    std::lock_guard lock(mutex_);
    auto connection = std::make_unique<Connection>();
    connection->fd = fd;
    Connection& c = *connection;
    ++connections_;
    connections_list_.push_back(std::move(connection));
    c.thread = std::thread([this, &c] {
      try {
        serve(c);
      } catch (const std::exception&) {  // a failed stream ends its connection, never the process
      }
      {
        std::lock_guard guard(mutex_);
        ::close(c.fd);
        c.fd = -1;
      }
      --connections_;
      c.done = true;
    });
  }
}

void HttpServer::reap_finished() {
  std::list<std::unique_ptr<Connection>> finished;
  {
    std::lock_guard lock(mutex_);
    for (auto it = connections_list_.begin(); it != connections_list_.end();) {
      if ((*it)->done) {
        finished.push_back(std::move(*it));
        it = connections_list_.erase(it);
      } else {
        ++it;
      }
    }
  }
  for (auto& c : finished) c->thread.join();
}

void HttpServer::stop() {
  if (stopping_.exchange(true)) return;
  if (accept_thread_.joinable()) accept_thread_.join();
  if (listen_fd_ >= 0) ::close(listen_fd_);
  listen_fd_ = -1;
  {
    std::lock_guard lock(mutex_);  // wake every connection blocked in poll()
    for (auto& c : connections_list_) {
      if (c->fd >= 0) ::shutdown(c->fd, SHUT_RDWR);
    }
  }
  std::list<std::unique_ptr<Connection>> all;
  {
    std::lock_guard lock(mutex_);
    all.swap(connections_list_);
  }
  for (auto& c : all) c->thread.join();
}

bool HttpServer::read_request(int fd, HttpRequest& request, int& error_status) {
  const auto deadline = Clock::now() + options_.request_timeout;
  std::string data;
  size_t header_end = std::string::npos;
  size_t body_bytes = 0;
  char buffer[4096];
  while (true) {
    if (header_end == std::string::npos) {
      header_end = data.find("\r\n\r\n");
      if (header_end == std::string::npos && data.size() > options_.max_header_bytes) {
        error_status = 431;
        return false;
      }
      if (header_end != std::string::npos) {
        // Request line and headers.
        const std::string head = data.substr(0, header_end);
        size_t line_end = head.find("\r\n");
        const std::string line = head.substr(0, line_end);
        const size_t sp1 = line.find(' ');
        const size_t sp2 = sp1 == std::string::npos ? std::string::npos : line.find(' ', sp1 + 1);
        if (sp2 == std::string::npos || line.compare(sp2 + 1, 5, "HTTP/") != 0) {
          error_status = 400;
          return false;
        }
        request.method = line.substr(0, sp1);
        const std::string target = line.substr(sp1 + 1, sp2 - sp1 - 1);
        const size_t question = target.find('?');
        request.path = percent_decode(target.substr(0, question));
        if (question != std::string::npos) parse_query(target.substr(question + 1), request.query);
        while (line_end != std::string::npos && line_end < head.size()) {
          const size_t next = head.find("\r\n", line_end + 2);
          const std::string header = head.substr(line_end + 2, next == std::string::npos ? std::string::npos : next - line_end - 2);
          const size_t colon = header.find(':');
          if (colon != std::string::npos) {
            size_t value = colon + 1;
            while (value < header.size() && (header[value] == ' ' || header[value] == '\t')) ++value;
            request.headers[lower(header.substr(0, colon))] = header.substr(value);
          }
          line_end = next;
        }
        const auto length = request.headers.find("content-length");
        if (length != request.headers.end()) {
          const std::string& v = length->second;
          if (v.empty() || v.size() > 9 || v.find_first_not_of("0123456789") != std::string::npos) {
            error_status = 400;
            return false;
          }
          body_bytes = std::stoul(v);
          if (body_bytes > options_.max_body_bytes) {
            error_status = 413;
            return false;
          }
        }
        if (request.headers.count("transfer-encoding")) {  // chunked uploads are not needed by the page
          error_status = 400;
          return false;
        }
      }
    }
    if (header_end != std::string::npos && data.size() >= header_end + 4 + body_bytes) {
      request.body = data.substr(header_end + 4, body_bytes);
      return true;
    }
    const int wait = remaining_ms(deadline);
    if (wait == 0 || stopping_) {
      error_status = data.empty() ? 0 : 408;  // an idle connection just closes
      return false;
    }
    pollfd p{fd, POLLIN, 0};
    const int ready = ::poll(&p, 1, wait);
    if (ready < 0 && errno != EINTR) return false;
    if (ready <= 0) continue;
    const ssize_t got = ::recv(fd, buffer, sizeof buffer, 0);
    if (got == 0) return false;  // closed before a whole request
    if (got < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) continue;
      return false;
    }
    data.append(buffer, static_cast<size_t>(got));
  }
}

bool HttpServer::write_all(int fd, const std::string& data) {
  const auto deadline = Clock::now() + options_.write_timeout;
  size_t sent = 0;
  while (sent < data.size()) {
    if (stopping_) return false;
    const ssize_t n = ::send(fd, data.data() + sent, data.size() - sent, MSG_NOSIGNAL);
    if (n > 0) {
      sent += static_cast<size_t>(n);
      continue;
    }
    if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) return false;
    const int wait = remaining_ms(deadline);
    if (wait == 0) return false;  // the client does not read: give up on it
    pollfd p{fd, POLLOUT, 0};
    if (::poll(&p, 1, wait) < 0 && errno != EINTR) return false;
  }
  return true;
}

void HttpServer::respond(int fd, const HttpResponse& response) {
  std::string head = status_line(response.status) + "Content-Type: " + response.content_type +
                     "\r\nContent-Length: " + std::to_string(response.body.size()) + "\r\nConnection: close\r\n";
  for (const auto& [name, value] : response.headers) head += name + ": " + value + "\r\n";
  head += "\r\n";
  if (write_all(fd, head)) write_all(fd, response.body);
  ::shutdown(fd, SHUT_WR);
}

void HttpServer::stream_response(int fd, HttpResponse& response) {
  std::string head = status_line(200) + "Content-Type: " + response.content_type + "\r\nConnection: close\r\n";
  for (const auto& [name, value] : response.headers) head += name + ": " + value + "\r\n";
  head += "\r\n";
  if (!write_all(fd, head)) return;
  const auto write = [this, fd](const std::string& data) { return write_all(fd, data); };
  while (!stopping_ && response.stream(write)) {
  }
}

void HttpServer::serve(Connection& connection) {
  const int fd = connection.fd;
  HttpRequest request;
  int error_status = 0;
  if (!read_request(fd, request, error_status)) {
    if (error_status != 0) {
      HttpResponse response;
      response.status = error_status;
      response.content_type = "application/json";
      response.body = std::string("{\"error\":\"") + http_reason(error_status) + "\"}";
      respond(fd, response);
      char buffer[4096];  // what is left of the request, briefly (unread input would reset the connection)
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, 100) > 0) {
        while (::recv(fd, buffer, sizeof buffer, MSG_DONTWAIT) > 0) {
        }
      }
    }
    return;
  }
  HttpResponse response;
  const auto route = routes_.find({request.method, request.path});
  if (route != routes_.end()) {
    try {
      route->second(request, response);
    } catch (const std::exception& e) {  // never out of the connection's thread (that would terminate)
      response = HttpResponse();
      response.status = 500;
      response.content_type = "application/json";
      response.body = "{\"error\":\"internal error\"}";
    }
  } else {
    const bool other_method = std::any_of(routes_.begin(), routes_.end(),
                                          [&](const auto& r) { return r.first.second == request.path; });
    response.status = other_method ? 405 : 404;
    response.body = other_method ? "method not allowed\n" : "not found\n";
  }
  if (response.stream && ++streams_ > options_.max_streams) {
    --streams_;
    response = HttpResponse();
    response.status = 503;
    response.content_type = "application/json";
    response.headers.emplace_back("Retry-After", "5");
    response.body = "{\"error\":\"too many viewers connected; try again later\"}";
  }
  if (logger_) logger_(request.method, request.path, response.status);
  if (response.stream) {
    stream_response(fd, response);
    --streams_;
  } else {
    respond(fd, response);
  }
}

}  // namespace crowdslam::viewer
