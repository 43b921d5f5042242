#include "crowdslam/people/model_paths.h"

#include <cstdlib>
#include <filesystem>
#include <vector>

#include "crowdslam/util/error.h"

#ifndef CROWDSLAM_DEFAULT_SHARED
#define CROWDSLAM_DEFAULT_SHARED "../shared"
#endif
#ifndef CROWDSLAM_SOURCE_DIR
#define CROWDSLAM_SOURCE_DIR "."
#endif

namespace crowdslam::people {
namespace fs = std::filesystem;
namespace {

std::string env(const char* name) {
  const char* value = std::getenv(name);
  return value ? std::string(value) : std::string();
}

bool ends_with(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

std::string default_model_dir() {
  std::vector<std::string> candidates;
  if (const std::string models = env("CROWDSLAM_MODELS"); !models.empty()) candidates.push_back(models);
  candidates.push_back((fs::path(CROWDSLAM_SOURCE_DIR) / "models").string());
  const std::string shared = env("CROWDSLAM_SHARED");
  candidates.push_back((fs::path(shared.empty() ? CROWDSLAM_DEFAULT_SHARED : shared) / "models").string());
  std::error_code ec;
  for (const std::string& dir : candidates)
    if (fs::is_directory(dir, ec)) return dir;
  return candidates.front();
}

ModelFiles resolve_model(const std::string& spec) {
  const fs::path dir = fs::path(default_model_dir()) / "yolo-fastest-1.1";
  if (spec == "body")
    return {(dir / "yolo-fastest-1.1_body.cfg").string(), (dir / "yolo-fastest-1.1_body.weights").string(),
            0};
  if (spec == "coco")
    return {(dir / "yolo-fastest-1.1.cfg").string(), (dir / "yolo-fastest-1.1.weights").string(), 0};
  if (ends_with(spec, ".cfg")) {
    return {spec, fs::path(spec).replace_extension(".weights").string(), 0};
  }
  if (ends_with(spec, ".onnx")) return {spec, {}, 0};
  throw InputError(
      "--model: expected 'body', 'coco', a Darknet .cfg (with the .weights beside it) or an "
      ".onnx file, got '" +
      spec + "'");
}

}  // namespace crowdslam::people
