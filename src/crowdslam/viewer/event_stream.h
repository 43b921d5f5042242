#pragma once
// The viewer's outgoing messages as Server-Sent Events: producers publish (event name, JSON data), each
// connected client reads everything after its cursor. Bounded: only the newest `capacity` messages are
// kept, and the newest message of each event name is retained for clients that connect late (they get
// the current map, image and status first). Thread-safe.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace crowdslam::viewer {

class EventStream {
 public:
  using Message = std::shared_ptr<const std::string>;  // "event: NAME\ndata: ...\n\n"

  explicit EventStream(size_t capacity = 64) : capacity_(capacity) {}

  void publish(const std::string& event, const std::string& data);
  // A client's position in the stream.
  struct Cursor {
    uint64_t seen = 0;     // sequence number of the last message it got
    bool started = false;  // a new client first gets the retained newest message of every event name
  };
  // Messages published after `cursor` (which is advanced), waiting up to `timeout` for one; empty on
  // timeout or once closed.
  std::vector<Message> wait(Cursor& cursor, std::chrono::milliseconds timeout);
  // Wakes every waiting client; later waits return at once.
  void close();
  [[nodiscard]] bool closed() const;
  [[nodiscard]] uint64_t published() const;

 private:
  const size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::pair<uint64_t, Message>> recent_;
  std::map<std::string, std::pair<uint64_t, Message>> newest_by_event_;
  uint64_t sequence_ = 0;
  bool closed_ = false;
};

}  // namespace crowdslam::viewer
