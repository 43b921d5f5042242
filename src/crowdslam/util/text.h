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

}  // namespace crowdslam
