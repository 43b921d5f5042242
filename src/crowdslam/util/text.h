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

// Throws InputError "PATH: no such file / is a directory, not a file / not a regular file" unless `path`
// names a regular file (after links): a device (/dev/zero), FIFO or socket is never read.
void check_regular_file(const std::string& path);

// Reads a whole text file into lines (without '\n' and a trailing '\r'); throws InputError naming the
// file if it is not a regular file or unreadable, and naming the line if one is longer than
// `max_line_bytes`.
constexpr size_t kMaxLineBytes = 8 << 20;  // 8 MiB: no text line of ours comes near
std::vector<std::string> read_lines(const std::string& path, size_t max_line_bytes = kMaxLineBytes);

std::string trim(std::string_view text);

// The current time in UTC, formatted by strftime (default ISO 8601, e.g. "2026-12-02T16:20:00Z").
std::string utc_now(const char* format = "%Y-%m-%dT%H:%M:%SZ");

// User text quoted in a message: `text` itself when it has at most `max_chars` characters; otherwise its
// start and its end (where a path keeps its file name) joined by "...", `max_chars` characters in all,
// and the full length, e.g. "/very/long/dir...rgb/1.png (2097152 chars)". Control characters become '?'.
std::string clip_text(std::string_view text, size_t max_chars = 300);

}  // namespace crowdslam
