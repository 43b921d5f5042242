#include "crowdslam/people/model_paths.h"

#include <cstdlib>
#include <filesystem>
#include <vector>

#include "crowdslam/util/error.h"
#include "crowdslam/util/project_paths.h"


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

std::vector<std::string> model_dir_candidates() {
  std::vector<std::string> candidates;
  if (const std::string models = env("CROWDSLAM_MODELS"); !models.empty()) candidates.push_back(models);
  candidates.push_back((util::source_dir() / "models").string());
  candidates.push_back((util::shared_dir() / "models").string());
  return candidates;
}

fs::path folder_of(const std::string& folder) {
  std::error_code ec;
  for (const std::string& dir : model_dir_candidates())
    if (fs::is_directory(fs::path(dir) / folder, ec)) return fs::path(dir) / folder;
  return fs::path(default_model_dir()) / folder;
}

}  // namespace

Backend resolved_backend(const ModelFiles& model) {
  if (model.backend != Backend::kAuto) return model.backend;
  return ends_with(model.config, ".onnx") ? Backend::kYoloOnnx : Backend::kDarknet;
}

std::string resolved_preprocess(const ModelFiles& model) {
  if (!model.preprocess.empty()) return model.preprocess;
  return resolved_backend(model) == Backend::kYolox ? "yolox" : "darknet";
}

std::string default_model_dir() {
  const std::vector<std::string> candidates = model_dir_candidates();
  std::error_code ec;
  for (const std::string& dir : candidates)
    if (fs::is_directory(dir, ec)) return dir;
  return candidates.front();
}

ModelFiles resolve_model(const std::string& spec) {
  if (const ZooModel* zoo = find_zoo_model(spec)) {
    const fs::path dir = folder_of(zoo->folder);
    ModelFiles m;
    m.config = (dir / zoo->config).string();
    m.weights = zoo->weights.empty() ? std::string() : (dir / zoo->weights).string();
    m.person_class = zoo->person_class;
    m.backend = zoo->backend;
    m.preprocess = zoo->preprocess;
    m.detect_input = zoo->detect_input;
    m.name = zoo->name;
    return m;
  }
  ModelFiles m;
  m.config = spec;
  if (ends_with(spec, ".cfg")) {
    m.weights = fs::path(spec).replace_extension(".weights").string();
    return m;
  }
  if (ends_with(spec, ".onnx")) return m;
  throw InputError("detector model: expected one of " + zoo_model_names() +
                   ", a Darknet .cfg (with the .weights beside it) or an .onnx file, got '" + spec + "'");
}

}  // namespace crowdslam::people
