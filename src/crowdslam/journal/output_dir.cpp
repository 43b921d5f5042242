#include "crowdslam/journal/output_dir.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>

#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"

namespace crowdslam::journal {

namespace fs = std::filesystem;

namespace {

const char* const kOutputNames[] = {"CameraTrajectory.txt", "KeyFrameTrajectory.txt", "BridgedTrajectory.txt",
                                    "run.json", "frames", "report.html"};

std::string where(const fs::path& path) { return clip_text(path.string(), 200); }

// "NAME.tmp.PID" of one of our outputs (left behind by a process killed while writing it).
bool is_temporary_of_output(const std::string& name) {
  const auto pos = name.rfind(".tmp.");
  if (pos == std::string::npos || pos + 5 >= name.size()) return false;
  for (size_t i = pos + 5; i < name.size(); ++i) {
    if (name[i] < '0' || name[i] > '9') return false;
  }
  return is_run_output_name(name.substr(0, pos));
}

// The nearest existing ancestor of `path` (itself when it exists).
fs::path existing_ancestor(const fs::path& path) {
  fs::path p = fs::absolute(path).lexically_normal();
  std::error_code ec;
  while (!p.empty() && !fs::exists(p, ec)) {
    if (ec && ec != std::errc::not_a_directory && ec != std::errc::no_such_file_or_directory) return p;
    const fs::path parent = p.parent_path();
    if (parent == p) break;
    p = parent;
  }
  return p;
}

}  // namespace

bool is_run_output_name(const std::string& name) {
  for (const char* known : kOutputNames) {
    if (name == known) return true;
  }
  return is_temporary_of_output(name);
}

void check_output_dir(const fs::path& out, bool overwrite) {
  if (out.empty()) throw InputError("--out: output directory required");
  std::error_code ec;
  const auto status = fs::status(out, ec);
  if (ec && ec != std::errc::no_such_file_or_directory && ec != std::errc::not_a_directory) {
    throw input_error(where(out), "--out: cannot use this path: " + ec.message());
  }
  if (!fs::exists(status)) {
    const fs::path ancestor = existing_ancestor(out);
    if (!fs::is_directory(ancestor, ec)) {
      throw input_error(where(out), "--out: cannot create it: " + where(ancestor) + " is not a directory");
    }
    if (::access(ancestor.c_str(), W_OK | X_OK) != 0) {
      throw input_error(where(out), "--out: cannot create it in " + where(ancestor) + ": " + std::strerror(errno));
    }
    return;
  }
  if (!fs::is_directory(status)) throw input_error(where(out), "--out: exists and is not a directory");
  if (::access(out.c_str(), W_OK | X_OK) != 0) {
    throw input_error(where(out), std::string("--out: not writable: ") + std::strerror(errno));
  }
  bool earlier_run = false;
  for (fs::directory_iterator it(out, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (!is_run_output_name(name)) {
      throw input_error(where(out), "--out: holds files crowdslam did not write (e.g. '" + clip_text(name, 80) +
                                        "'); choose an empty or new directory");
    }
    earlier_run = true;
  }
  if (ec) throw input_error(where(out), "--out: cannot list: " + ec.message());
  if (earlier_run && !overwrite) {
    throw input_error(where(out), "--out: holds an earlier run; pass --overwrite to replace it, or choose another "
                                  "directory");
  }
}

std::vector<std::string> prepare_output_dir(const fs::path& out, bool overwrite) {
  check_output_dir(out, overwrite);
  std::error_code ec;
  std::vector<std::string> removed;
  if (!fs::exists(out, ec)) {
    fs::create_directories(out, ec);
    if (ec) throw input_error(where(out), "--out: cannot create: " + ec.message());
  } else {
    for (fs::directory_iterator it(out, ec), end; !ec && it != end; it.increment(ec)) {
      removed.push_back(it->path().filename().string());
    }
    for (const auto& name : removed) {
      fs::remove_all(out / name, ec);
      if (ec) throw input_error(where(out / name), "--out: cannot remove the earlier run's file: " + ec.message());
    }
  }
  // A probe, so a directory we cannot write into fails now and not after the whole run.
  const fs::path probe = out / (".write-probe." + std::to_string(::getpid()));
  {
    std::ofstream file(probe);
    file << "probe\n";
    file.flush();
    if (!file) {
      const int saved = errno;
      fs::remove(probe, ec);
      throw input_error(where(out), std::string("--out: cannot write into it: ") + std::strerror(saved));
    }
  }
  fs::remove(probe, ec);
  return removed;
}

}  // namespace crowdslam::journal
