#pragma once
// Parsing the list files of dataset layouts (internal to io; used by the layout readers).
#include <string>
#include <vector>

namespace crowdslam::io {

struct ListEntry {
  double timestamp_s = 0.0;
  long long timestamp_ns = 0;  // EuRoC lists only
  std::string file;            // as written in the list
  int line = 0;                // 1-based line in the list file
};

// Time stamps must be seconds in [0, kMaxTimestampS) (year 5138): anything else (1e300, negative) is
// an error naming the list and line, as are inf and nan.
constexpr double kMaxTimestampS = 1e11;

// TUM list ("timestamp filename" per line, '#' comments, blank lines skipped). Throws InputError naming the
// file (missing/unreadable/empty) or file and line (too few fields, non-numeric, non-finite or out-of-range
// stamp).
std::vector<ListEntry> read_tum_list(const std::string& path);

// EuRoC camera csv ("timestamp_ns,filename", '#' header). Same errors as read_tum_list.
std::vector<ListEntry> read_euroc_list(const std::string& path);

// Plain timestamps, one per line (KITTI times.txt); `file` stays empty. Same errors.
std::vector<ListEntry> read_times_list(const std::string& path);

// Throws InputError "LIST:LINE: listed image FILE does not exist" unless `file` is a regular file; a path
// that cannot be checked (too long, a symlink loop, no permission) is "LIST:LINE: listed image FILE:
// reason". FILE is clipped (input_text.h). With `missing_ok` a file that does not exist is accepted
// (counted in `missing`, warned about once).
void require_listed_file(const std::string& file, const std::string& list, int line, bool missing_ok = false);

// The entries kept when the list is read into a dict keyed by stamp (`by_ns`: timestamp_ns, else
// timestamp_s): of equal stamps the later entry wins, as in TUM's associate.py. Ascending by stamp.
// Duplicates are counted and warned about once (spdlog::warn) naming LIST:LINE of the first repeat.
std::vector<ListEntry> without_duplicate_stamps(const std::vector<ListEntry>& entries,
                                                const std::string& list, bool by_ns = false);

bool is_comment_or_blank(const std::string& line);

}  // namespace crowdslam::io
