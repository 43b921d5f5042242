#pragma once
// Helpers for error and warning messages about user input (paths, list lines, settings values).
#include <cstddef>
#include <string>
#include <string_view>

#include "crowdslam/util/text.h"

namespace crowdslam::io {

// Longest piece of user text (a path, a list line, a value) a message quotes.
constexpr std::size_t kMaxQuotedChars = 300;

// Quoting user text: crowdslam::clip_text (util/text.h), with kMaxQuotedChars by default.

// Levenshtein distance (insertions, deletions, substitutions of one character each).
std::size_t edit_distance(std::string_view a, std::string_view b);

}  // namespace crowdslam::io
