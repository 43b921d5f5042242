#include "crowdslam/viewer/event_stream.h"

#include <algorithm>

namespace crowdslam::viewer {

void EventStream::publish(const std::string& event, const std::string& data) {
  auto message = std::make_shared<const std::string>("event: " + event + "\ndata: " + data + "\n\n");
  {
    std::lock_guard lock(mutex_);
    if (closed_) return;
    ++sequence_;
    recent_.emplace_back(sequence_, message);
    while (recent_.size() > capacity_) recent_.pop_front();
    newest_by_event_[event] = {sequence_, message};
  }
  cv_.notify_all();
}

std::vector<EventStream::Message> EventStream::wait(Cursor& cursor, std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  std::vector<Message> out;
  if (!cursor.started) {
    // A new client: the newest message of each event, in publishing order, then everything after.
    cursor.started = true;
    std::vector<std::pair<uint64_t, Message>> newest;
    for (const auto& entry : newest_by_event_) newest.push_back(entry.second);
    std::sort(newest.begin(), newest.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    for (auto& entry : newest) out.push_back(std::move(entry.second));
    cursor.seen = sequence_;
    if (!out.empty() || closed_) return out;
  }
  cv_.wait_for(lock, timeout, [&] { return closed_ || sequence_ > cursor.seen; });
  for (const auto& [seq, message] : recent_) {
    if (seq > cursor.seen) out.push_back(message);
  }
  cursor.seen = std::max(cursor.seen, sequence_);
  return out;
}

void EventStream::close() {
  {
    std::lock_guard lock(mutex_);
    closed_ = true;
  }
  cv_.notify_all();
}

bool EventStream::closed() const {
  std::lock_guard lock(mutex_);
  return closed_;
}

uint64_t EventStream::published() const {
  std::lock_guard lock(mutex_);
  return sequence_;
}

}  // namespace crowdslam::viewer
