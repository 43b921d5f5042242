#include "crowdslam/report/json_fields.h"

#include "crowdslam/util/error.h"

namespace crowdslam::report {

namespace {
const nlohmann::json& null_json() {
  static const nlohmann::json null_value = nullptr;
  return null_value;
}

const char* type_name(const nlohmann::json& value) { return value.type_name(); }
}  // namespace

void JsonFields::fail(const std::string& key_path, const std::string& reason) const {
  throw input_error(file_, "key '" + key_path + "': " + reason);
}

const nlohmann::json& JsonFields::find(const std::string& key_path) const {
  const nlohmann::json* node = &document_;
  size_t start = 0;
  while (start <= key_path.size()) {
    const size_t dot = key_path.find('.', start);
    const std::string key =
        key_path.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    if (!node->is_object()) return null_json();
    const auto it = node->find(key);
    if (it == node->end()) return null_json();
    node = &*it;
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  return *node;
}

const nlohmann::json& JsonFields::at(const std::string& key_path) const {
  const nlohmann::json* node = &document_;
  size_t start = 0;
  while (true) {
    const size_t dot = key_path.find('.', start);
    const std::string key =
        key_path.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    const std::string so_far = key_path.substr(0, dot);
    if (!node->is_object())
      fail(so_far, std::string("its parent is ") + type_name(*node) + ", not an object");
    const auto it = node->find(key);
    if (it == node->end()) fail(so_far, "missing");
    node = &*it;
    if (dot == std::string::npos) return *node;
    start = dot + 1;
  }
}

double JsonFields::number(const std::string& key_path) const {
  const auto& value = at(key_path);
  if (!value.is_number()) fail(key_path, std::string("expected a number, got ") + type_name(value));
  return value.get<double>();
}

std::string JsonFields::text(const std::string& key_path) const {
  const auto& value = at(key_path);
  if (!value.is_string()) fail(key_path, std::string("expected a string, got ") + type_name(value));
  return value.get<std::string>();
}

const nlohmann::json& JsonFields::array(const std::string& key_path) const {
  const auto& value = at(key_path);
  if (!value.is_array()) fail(key_path, std::string("expected an array, got ") + type_name(value));
  return value;
}

double JsonFields::number_in(const nlohmann::json& element, const std::string& where,
                             const std::string& key) const {
  if (!element.is_object()) fail(where, std::string("expected an object, got ") + type_name(element));
  const auto it = element.find(key);
  if (it == element.end()) fail(where + "." + key, "missing");
  if (!it->is_number()) fail(where + "." + key, std::string("expected a number, got ") + type_name(*it));
  return it->get<double>();
}

std::string JsonFields::text_in(const nlohmann::json& element, const std::string& where,
                                const std::string& key) const {
  if (!element.is_object()) fail(where, std::string("expected an object, got ") + type_name(element));
  const auto it = element.find(key);
  if (it == element.end()) fail(where + "." + key, "missing");
  if (!it->is_string()) fail(where + "." + key, std::string("expected a string, got ") + type_name(*it));
  return it->get<std::string>();
}

}  // namespace crowdslam::report
