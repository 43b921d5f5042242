#pragma once
// Helpers shared by the `crowdslam run` CLI tests: synthetic sequences, reading the outputs.
#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "test_support.h"

namespace crowdslam::test {

// A synthetic RGB-D sequence (TUM layout) of `frames` frames at 320x240 in DIR/name.
inline std::filesystem::path synth_small(const TempDir& dir, int frames, const std::string& name = "seq",
                                         const std::vector<std::string>& extra = {}) {
  const auto seq = dir / name;
  std::vector<std::string> args = {"-q", "synth", "--out", seq.string(), "--frames", std::to_string(frames)};
  if (std::find(extra.begin(), extra.end(), "--width") == extra.end()) {
    args.insert(args.end(), {"--width", "320", "--height", "240"});
  }
  args.insert(args.end(), extra.begin(), extra.end());
  const auto r = run_cli(args);
  if (r.exit_code != 0) throw std::runtime_error("synth failed: " + r.err);
  return seq;
}

inline nlohmann::json read_json(const std::filesystem::path& path) { return nlohmann::json::parse(read_text(path)); }

// Data lines (not comments) of a trajectory file.
inline std::vector<std::string> trajectory_lines(const std::filesystem::path& path) {
  std::vector<std::string> lines;
  const std::string text = read_text(path);
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(start, end - start);
    if (!line.empty() && line[0] != '#') lines.push_back(line);
    start = end + 1;
  }
  return lines;
}

// Names in `dir` containing ".tmp" (temporaries left behind).
inline std::vector<std::string> temporaries(const std::filesystem::path& dir) {
  std::vector<std::string> found;
  std::error_code ec;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir, ec)) {
    if (e.path().filename().string().find(".tmp") != std::string::npos) found.push_back(e.path().string());
  }
  return found;
}

inline size_t count_fields(const std::string& line) {
  size_t fields = 0;
  bool in_field = false;
  for (char c : line) {
    const bool space = c == ' ' || c == '\t' || c == ',';
    if (!space && !in_field) ++fields;
    in_field = !space;
  }
  return fields;
}

}  // namespace crowdslam::test
