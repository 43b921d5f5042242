#pragma once
// Checked access to the fields of a run's run.json: a missing key or a value of the wrong type is an
// InputError naming the file and the key path ("OUT/run.json: key 'summary.frames': missing").
#include <nlohmann/json.hpp>
#include <string>

namespace crowdslam::report {

class JsonFields {
 public:
  // `file` names the document in messages.
  JsonFields(const nlohmann::json& document, std::string file)
      : document_(document), file_(std::move(file)) {}

  // The value at a dotted key path ("summary.frames"); throws when a part is missing.
  [[nodiscard]] const nlohmann::json& at(const std::string& key_path) const;
  // The value at the path, or nullptr (a null json) when any part is missing or null.
  [[nodiscard]] const nlohmann::json& find(const std::string& key_path) const;
  [[nodiscard]] double number(const std::string& key_path) const;
  [[nodiscard]] std::string text(const std::string& key_path) const;
  [[nodiscard]] const nlohmann::json& array(const std::string& key_path) const;

  // The same checks for a member of an element of an array, named "frames[12].state" in messages.
  [[nodiscard]] double number_in(const nlohmann::json& element, const std::string& where,
                                 const std::string& key) const;
  [[nodiscard]] std::string text_in(const nlohmann::json& element, const std::string& where,
                                    const std::string& key) const;

  [[nodiscard]] const std::string& file() const { return file_; }
  [[noreturn]] void fail(const std::string& key_path, const std::string& reason) const;

 private:
  const nlohmann::json& document_;
  std::string file_;
};

}  // namespace crowdslam::report
