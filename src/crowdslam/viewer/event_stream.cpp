#include "crowdslam/viewer/event_stream.h"

#include <algorithm>

namespace crowdslam::viewer {

void EventStream::publish(const std::string& event, const std::string& data, bool retain) {
  auto message = std::make_shared<const std::string>("event: " + event + "\ndata: " + data + "\n\n");
  {
    std::lock_guard lock(mutex_);
    if (closed_) return;
    ++sequence_;
    recent_.push_back({sequence_, event, message});
    while (recent_.size() > capacity_) recent_.pop_front();
    if (retain) newest_by_event_[event] = {sequence_, event, message};
  }
  cv_.notify_all();
}

std::vector<EventStream::Message> EventStream::wait(Cursor& cursor, std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  std::vector<Message> out;
  const auto wanted = [&](const Entry& entry) { return cursor.skip.count(entry.event) == 0; };
  if (!cursor.started) {
    // A new client: the newest message of each event, in publishing order, then everything after.
    cursor.started = true;
    std::vector<const Entry*> newest;
    for (const auto& [event, entry] : newest_by_event_) {
      if (wanted(entry)) newest.push_back(&entry);
    }
    std::sort(newest.begin(), newest.end(), [](const Entry* a, const Entry* b) { return a->sequence < b->sequence; });
    for (const Entry* entry : newest) out.push_back(entry->message);
    cursor.seen = sequence_;
    if (!out.empty() || closed_) return out;
  }
  cv_.wait_for(lock, timeout, [&] { return closed_ || sequence_ > cursor.seen; });
  if (cursor.gather.count() > 0 && sequence_ > cursor.seen && !closed_) {
    cv_.wait_for(lock, cursor.gather, [&] { return closed_; });
  }
  // Of a superseding event, only its newest message in this batch (the newest is never evicted first).
  std::map<std::string, uint64_t> newest;
  for (const auto& entry : recent_) {
    if (entry.sequence > cursor.seen && cursor.newest_only.count(entry.event)) newest[entry.event] = entry.sequence;
  }
  for (const auto& entry : recent_) {
    if (entry.sequence <= cursor.seen || !wanted(entry)) continue;
    const auto it = newest.find(entry.event);
    if (it != newest.end() && it->second != entry.sequence) continue;
    out.push_back(entry.message);
  }
  cursor.seen = std::max(cursor.seen, sequence_);
  return out;
}

std::shared_ptr<void> EventStream::register_client(const std::set<std::string>& skip, int image_width) {
  image_width = std::max(0, image_width);
  {
    std::lock_guard lock(mutex_);
    ++clients_;
    for (const auto& event : skip) ++skipping_[event];
    image_widths_.insert(image_width);
  }
  // The handle's deleter unregisters (the stream outlives the server and its clients).
  return std::shared_ptr<void>(nullptr, [this, skip, image_width](void*) {
    std::lock_guard lock(mutex_);
    --clients_;
    for (const auto& event : skip) --skipping_[event];
    image_widths_.erase(image_widths_.find(image_width));
  });
}

int EventStream::image_width() const {
  std::lock_guard lock(mutex_);
  if (image_widths_.empty() || *image_widths_.begin() == 0) return 0;
  return *image_widths_.rbegin();
}

bool EventStream::taken(const std::string& event) const {
  std::lock_guard lock(mutex_);
  const auto it = skipping_.find(event);
  return clients_ > (it == skipping_.end() ? 0 : it->second);
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

size_t EventStream::clients() const {
  std::lock_guard lock(mutex_);
  return clients_;
}

uint64_t EventStream::published() const {
  std::lock_guard lock(mutex_);
  return sequence_;
}

}  // namespace crowdslam::viewer
