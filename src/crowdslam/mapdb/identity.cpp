// Which maps a system can use: identity comparison and the vocabulary's content hash.
#include <cmath>
#include <cstdio>
#include <sstream>

#include "crowdslam/mapdb/map_database.h"

namespace crowdslam::mapdb {

namespace {
class Fnv1a {
 public:
  void add(const void* data, size_t bytes) {
    const auto* p = static_cast<const uint8_t*>(data);
    for (size_t i = 0; i < bytes; ++i) {
      hash_ ^= p[i];
      hash_ *= 1099511628211ULL;
    }
  }
  template <typename T>
  void add(const T& value) {
    add(&value, sizeof(value));
  }
  [[nodiscard]] uint64_t value() const { return hash_; }

 private:
  uint64_t hash_ = 14695981039346656037ULL;
};

bool same(double a, double b) { return std::abs(a - b) <= 1e-9 * std::max(1.0, std::max(std::abs(a), std::abs(b))); }

std::string fmt(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.10g", value);
  return buffer;
}
}  // namespace

std::string vocabulary_hash(const bow::Vocabulary& vocabulary) {
  if (vocabulary.empty()) return "";
  Fnv1a h;
  h.add(static_cast<uint64_t>(vocabulary.num_nodes()));
  h.add(static_cast<uint64_t>(vocabulary.num_words()));
  for (bow::NodeId node = 0; node < vocabulary.num_nodes(); ++node) {
    h.add(vocabulary.parent(node));
    h.add(vocabulary.node_descriptor(node), 32);
  }
  for (bow::WordId word = 0; word < vocabulary.num_words(); ++word) {
    h.add(vocabulary.word_node(word));
    h.add(vocabulary.word_weight(word));
  }
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "fnv1a64:%016llx", static_cast<unsigned long long>(h.value()));
  return buffer;
}

std::string identity_mismatch(const MapIdentity& stored, const MapIdentity& current) {
  std::ostringstream out;
  const auto differ = [&](const std::string& what, const std::string& in_map, const std::string& here) {
    if (out.tellp() > 0) out << "; ";
    out << what << " " << in_map << " in the map, " << here << " here";
  };
  if (stored.sensor != current.sensor) differ("sensor", stored.sensor, current.sensor);
  const auto& a = stored.camera;
  const auto& b = current.camera;
  const std::pair<const char*, std::pair<double, double>> values[] = {
      {"camera fx", {a.fx, b.fx}},
      {"camera fy", {a.fy, b.fy}},
      {"camera cx", {a.cx, b.cx}},
      {"camera cy", {a.cy, b.cy}},
      {"camera k1", {a.distortion.k1, b.distortion.k1}},
      {"camera k2", {a.distortion.k2, b.distortion.k2}},
      {"camera p1", {a.distortion.p1, b.distortion.p1}},
      {"camera p2", {a.distortion.p2, b.distortion.p2}},
      {"camera k3", {a.distortion.k3, b.distortion.k3}},
      {"camera width", {a.width, b.width}},
      {"camera height", {a.height, b.height}},
      {"camera bf", {a.bf, b.bf}},
      {"DepthMapFactor", {stored.depth_map_factor, current.depth_map_factor}},
      {"ORBextractor.scaleFactor", {stored.orb_scale_factor, current.orb_scale_factor}},
      {"ORBextractor.nLevels", {stored.orb_levels, current.orb_levels}},
  };
  for (const auto& [what, pair] : values) {
    if (!same(pair.first, pair.second)) differ(what, fmt(pair.first), fmt(pair.second));
  }
  if (stored.vocabulary_hash != current.vocabulary_hash || stored.vocabulary_words != current.vocabulary_words) {
    const auto describe = [](const MapIdentity& id) {
      return id.vocabulary_hash.empty() ? std::string("none")
                                        : id.vocabulary_hash + " (" + std::to_string(id.vocabulary_words) + " words)";
    };
    differ("vocabulary", describe(stored), describe(current));
  }
  return out.str();
}

}  // namespace crowdslam::mapdb
