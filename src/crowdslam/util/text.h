#pragma once
// Small text helpers for the line-based dataset and trajectory formats.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace crowdslam {

// Splits on any run of spaces, tabs and (optionally) commas; drops empty fields and a trailing '\r'.
std::vector<std::string> split_fields(std::string_view line, bool commas_too = true);

// Strict number parsing: the whole string must be a finite or non-finite number; nullopt otherwise.
std::optional<double> parse_double(std::string_view text);
std::optional<long long> parse_int(std::string_view text);

// Reads a whole text file into lines (without '\n'); throws InputError naming the file if unreadable.
std::vector<std::string> read_lines(const std::string& path);

std::string trim(std::string_view text);

// `text` cut to at most `max_chars` characters for a message: the start and the end are kept with
// " ... " between them (paths keep their file name). Control characters become '?'.
std::string clip_text(std::string_view text, size_t max_chars = 300);

}  // namespace crowdslam
