#pragma once
// The viewer's outgoing messages as Server-Sent Events: producers publish (event name, JSON data), each
// connected client reads everything after its cursor. Bounded: only the newest `capacity` messages are
// kept, and the newest message of each event name is retained for clients that connect late (they get
// the current map, image and status first). A client may refuse event names (a page that hides its image
// takes no "image"); producers ask whether any connected client takes an event before making it.
// A client may also take its messages in batches (a page that redraws twice a second): the stream then
// gathers for a while after the first new message and sends, of the events the client names as
// superseding (map, image), only the newest; every other message is kept. Fewer, larger writes: the
// browser, often on the same cores as the run, wakes once per batch instead of once per message.
// Thread-safe.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

namespace crowdslam::viewer {

class EventStream {
 public:
  using Message = std::shared_ptr<const std::string>;  // "event: NAME\ndata: ...\n\n"

  explicit EventStream(size_t capacity = 64) : capacity_(capacity) {}

  // `retain` false: not replayed to clients that connect later (a past event such as a map reset).
  void publish(const std::string& event, const std::string& data, bool retain = true);
  // A client's position in the stream.
  struct Cursor {
    uint64_t seen = 0;     // sequence number of the last message it got
    bool started = false;  // a new client first gets the retained newest message of every event name
    std::set<std::string> skip;  // event names it does not take
    std::chrono::milliseconds gather{0};  // batching: how long to gather after the first new message
    std::set<std::string> newest_only;    // in a batch, only the newest message of these event names
  };
  // Messages published after `cursor` (which is advanced), waiting up to `timeout` for one; empty on
  // timeout or once closed. With `cursor.gather`, waits that long after the first (less once closed)
  // and thins the batch as the cursor says.
  std::vector<Message> wait(Cursor& cursor, std::chrono::milliseconds timeout);
  // Counts a connected client (the events it skips, the image width it shows, 0: any) until the returned
  // handle is released.
  [[nodiscard]] std::shared_ptr<void> register_client(const std::set<std::string>& skip, int image_width = 0);
  // Whether a registered client takes `event`.
  [[nodiscard]] bool taken(const std::string& event) const;
  // The widest image a registered client shows; 0 when one takes any width (or none said).
  [[nodiscard]] int image_width() const;
  // Wakes every waiting client; later waits return at once.
  void close();
  [[nodiscard]] bool closed() const;
  [[nodiscard]] uint64_t published() const;
  // Clients registered now (connected event streams).
  [[nodiscard]] size_t clients() const;

 private:
  struct Entry {
    uint64_t sequence;
    std::string event;
    Message message;
  };
  const size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Entry> recent_;
  std::map<std::string, Entry> newest_by_event_;
  uint64_t sequence_ = 0;
  bool closed_ = false;
  size_t clients_ = 0;
  std::map<std::string, size_t> skipping_;  // registered clients that skip each event
  std::multiset<int> image_widths_;          // of registered clients (0: any width)
};

}  // namespace crowdslam::viewer
