#pragma once
// Helpers for error and warning messages about user input (paths, list lines, settings values).
#include <cstddef>
#include <string>
#include <string_view>

namespace crowdslam::io {

// Longest piece of user text (a path, a list line, a value) a message quotes.
constexpr std::size_t kMaxQuotedChars = 300;

// `text` itself when it has at most `max_chars` characters; otherwise its start and its end (where a
// path keeps its file name) joined by "...", `max_chars` characters in all, and the full length, e.g.
// "/very/long/dir...rgb/1.png (2097152 chars)".
std::string clipped(std::string_view text, std::size_t max_chars = kMaxQuotedChars);

// Levenshtein distance (insertions, deletions, substitutions of one character each).
std::size_t edit_distance(std::string_view a, std::string_view b);

}  // namespace crowdslam::io
