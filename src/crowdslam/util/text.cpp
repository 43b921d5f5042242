#include "crowdslam/util/text.h"

#include <ctime>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "crowdslam/util/error.h"

namespace crowdslam {

std::vector<std::string> split_fields(std::string_view line, bool commas_too) {
  std::vector<std::string> fields;
  std::string current;
  for (char c : line) {
    const bool separator = c == ' ' || c == '\t' || c == '\r' || c == '\n' || (commas_too && c == ',');
    if (separator) {
      if (!current.empty()) fields.push_back(std::move(current));
      current.clear();
    } else {
      current.push_back(c);
    }
  }
  if (!current.empty()) fields.push_back(std::move(current));
  return fields;
}

std::optional<double> parse_double(std::string_view text) {
  const std::string s(trim(text));
  if (s.empty()) return std::nullopt;
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(s.c_str(), &end);
  if (end != s.c_str() + s.size()) return std::nullopt;
  return value;
}

std::optional<long long> parse_int(std::string_view text) {
  const std::string s(trim(text));
  if (s.empty()) return std::nullopt;
  char* end = nullptr;
  errno = 0;
  const long long value = std::strtoll(s.c_str(), &end, 10);
  if (end != s.c_str() + s.size() || errno == ERANGE) return std::nullopt;
  return value;
}

void check_regular_file(const std::string& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (status.type() == std::filesystem::file_type::not_found) throw input_error(clip_text(path), "no such file");
  if (status.type() == std::filesystem::file_type::directory) throw input_error(clip_text(path), "is a directory, not a file");
  if (ec || status.type() != std::filesystem::file_type::regular) {
    throw input_error(clip_text(path), "not a regular file (a device, FIFO or socket is not read)");
  }
}

std::vector<std::string> read_lines(const std::string& path, size_t max_line_bytes) {
  check_regular_file(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw input_error(clip_text(path), std::string("cannot open file: ") + std::strerror(errno));
  std::vector<std::string> lines;
  std::string line;
  std::string chunk(1 << 16, '\0');
  // Read in blocks: a line longer than the limit (a file of zeros, a binary file) is refused before it
  // fills memory.
  while (in) {
    in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
    const auto got = static_cast<size_t>(in.gcount());
    size_t start = 0;
    for (size_t i = 0; i < got; ++i) {
      if (chunk[i] != '\n') continue;
      line.append(chunk, start, i - start);
      start = i + 1;
      if (line.size() > max_line_bytes) break;
      if (!line.empty() && line.back() == '\r') line.pop_back();
      lines.push_back(std::move(line));
      line.clear();
    }
    if (line.size() <= max_line_bytes) line.append(chunk, start, got - start);
    if (line.size() > max_line_bytes) {
      throw input_error(clip_text(path), static_cast<int>(lines.size() + 1),
                        "line longer than " + std::to_string(max_line_bytes) + " bytes (not a text file?)");
    }
  }
  if (in.bad()) throw input_error(clip_text(path), std::string("read error: ") + std::strerror(errno));
  if (!line.empty()) {
    if (line.back() == '\r') line.pop_back();
    lines.push_back(std::move(line));
  }
  return lines;
}

std::string trim(std::string_view text) {
  size_t begin = 0;
  size_t end = text.size();
  while (begin < end && (text[begin] == ' ' || text[begin] == '\t' || text[begin] == '\r' || text[begin] == '\n')) ++begin;
  while (end > begin && (text[end - 1] == ' ' || text[end - 1] == '\t' || text[end - 1] == '\r' || text[end - 1] == '\n')) --end;
  return std::string(text.substr(begin, end - begin));
}

std::string clip_text(std::string_view text, size_t max_chars) {
  std::string result;
  if (text.size() <= max_chars) {
    result.assign(text);
  } else {
    const std::string suffix = " (" + std::to_string(text.size()) + " chars)";
    const size_t room = max_chars > suffix.size() + 3 + 2 ? max_chars - suffix.size() - 3 : 2;
    const size_t tail = room / 3;
    const size_t head = room - tail;
    result = std::string(text.substr(0, head)) + "..." + std::string(text.substr(text.size() - tail)) + suffix;
  }
  for (char& c : result) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
  }
  return result;
}

std::string utc_now(const char* format) {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char text[64];
  const size_t n = std::strftime(text, sizeof text, format, &tm);
  return std::string(text, n);
}

}  // namespace crowdslam
