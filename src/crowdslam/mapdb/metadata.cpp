#include "crowdslam/mapdb/metadata.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"

namespace crowdslam::mapdb {

namespace {
std::string number(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  return buffer;
}

class Reader {
 public:
  Reader(const std::map<std::string, std::string>& rows, const std::string& path) : rows_(rows), path_(path) {}
  [[nodiscard]] const std::string& text(const std::string& key) const {
    const auto it = rows_.find(key);
    if (it == rows_.end()) fail(key, "missing");
    return it->second;
  }
  // A finite number within [low, high].
  [[nodiscard]] double real(const std::string& key, double low = -1e300, double high = 1e300) const {
    const std::string& value = text(key);
    char* end = nullptr;
    const double parsed = std::strtod(value.c_str(), &end);
    if (value.empty() || std::isspace(static_cast<unsigned char>(value.front())) || *end != '\0' ||
        !std::isfinite(parsed)) {
      fail(key, "is not a finite number: " + clip_text(value, 60));
    }
    if (parsed < low || parsed > high) fail(key, "is out of range: " + clip_text(value, 60));
    return parsed;
  }
  [[nodiscard]] int integer(const std::string& key, int low, int high) const {
    const double value = real(key, low, high);
    if (value != std::floor(value)) fail(key, "is not an integer: " + clip_text(text(key), 60));
    return static_cast<int>(value);
  }

 private:
  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    throw InputError(path_ + ": corrupt map: metadata " + key + " " + what);
  }
  const std::map<std::string, std::string>& rows_;
  const std::string& path_;
};
}  // namespace

std::map<std::string, std::string> header_to_metadata(const MapHeader& header) {
  const MapIdentity& id = header.identity;
  const auto& c = id.camera;
  return {
      {"sensor", id.sensor},
      {"camera.fx", number(c.fx)},
      {"camera.fy", number(c.fy)},
      {"camera.cx", number(c.cx)},
      {"camera.cy", number(c.cy)},
      {"camera.k1", number(c.distortion.k1)},
      {"camera.k2", number(c.distortion.k2)},
      {"camera.p1", number(c.distortion.p1)},
      {"camera.p2", number(c.distortion.p2)},
      {"camera.k3", number(c.distortion.k3)},
      {"camera.width", std::to_string(c.width)},
      {"camera.height", std::to_string(c.height)},
      {"camera.bf", number(c.bf)},
      {"depth_map_factor", number(id.depth_map_factor)},
      {"orb.features", std::to_string(id.orb_features)},
      {"orb.scale_factor", number(id.orb_scale_factor)},
      {"orb.levels", std::to_string(id.orb_levels)},
      {"vocabulary.hash", id.vocabulary_hash},
      {"vocabulary.words", std::to_string(id.vocabulary_words)},
      {"origin.dataset", header.origin.dataset},
      {"origin.created_utc", header.origin.created_utc},
      {"origin.crowdslam_version", header.origin.crowdslam_version},
      {"origin.end_state", header.origin.end_state},
  };
}

MapHeader header_from_metadata(const std::map<std::string, std::string>& rows, const std::string& path) {
  const Reader r(rows, path);
  MapHeader header;
  MapIdentity& id = header.identity;
  id.sensor = r.text("sensor");
  auto& c = id.camera;
  c.fx = r.real("camera.fx");
  c.fy = r.real("camera.fy");
  c.cx = r.real("camera.cx");
  c.cy = r.real("camera.cy");
  c.distortion.k1 = r.real("camera.k1");
  c.distortion.k2 = r.real("camera.k2");
  c.distortion.p1 = r.real("camera.p1");
  c.distortion.p2 = r.real("camera.p2");
  c.distortion.k3 = r.real("camera.k3");
  c.width = r.integer("camera.width", 1, 1 << 16);
  c.height = r.integer("camera.height", 1, 1 << 16);
  c.bf = r.real("camera.bf");
  id.depth_map_factor = r.real("depth_map_factor");
  id.orb_features = r.integer("orb.features", 0, 1 << 24);
  id.orb_scale_factor = r.real("orb.scale_factor", 1.0, 10.0);
  id.orb_levels = r.integer("orb.levels", 1, 32);
  id.vocabulary_hash = r.text("vocabulary.hash");
  id.vocabulary_words = static_cast<uint64_t>(r.integer("vocabulary.words", 0, 1 << 30));
  header.origin.dataset = r.text("origin.dataset");
  header.origin.created_utc = r.text("origin.created_utc");
  header.origin.crowdslam_version = r.text("origin.crowdslam_version");
  header.origin.end_state = r.text("origin.end_state");
  return header;
}

}  // namespace crowdslam::mapdb
