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

// TUM list ("timestamp filename" per line, '#' comments, blank lines skipped). Throws InputError naming the
// file (missing/unreadable/empty) or file and line (too few fields, non-numeric or non-finite stamp).
std::vector<ListEntry> read_tum_list(const std::string& path);

// EuRoC camera csv ("timestamp_ns,filename", '#' header). Same errors as read_tum_list.
std::vector<ListEntry> read_euroc_list(const std::string& path);

// Plain timestamps, one per line (KITTI times.txt); `file` stays empty. Same errors.
std::vector<ListEntry> read_times_list(const std::string& path);

// Throws InputError "LIST:LINE: listed image FILE does not exist" unless `file` is a regular file.
void require_listed_file(const std::string& file, const std::string& list, int line);

bool is_comment_or_blank(const std::string& line);

}  // namespace crowdslam::io
