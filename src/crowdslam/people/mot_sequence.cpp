#include "crowdslam/people/mot_sequence.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>

#include "crowdslam/io/image_folder_dataset.h"
#include "crowdslam/io/input_text.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"

namespace crowdslam::people {
namespace fs = std::filesystem;
namespace {

std::map<std::string, std::string> read_ini(const std::string& path) {
  std::map<std::string, std::string> values;
  const std::vector<std::string> lines = read_lines(path);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::string line = trim(lines[i]);
    if (line.empty() || line[0] == '[' || line[0] == ';' || line[0] == '#') continue;
    const auto eq = line.find('=');
    if (eq == std::string::npos) throw input_error(path, static_cast<int>(i + 1), "expected key=value");
    values[trim(line.substr(0, eq))] = trim(line.substr(eq + 1));
  }
  return values;
}

double positive_number(const std::string& path, const std::string& key, const std::string& text) {
  const auto value = parse_double(text);
  if (!value || !(*value > 0))
    throw input_error(path, key + ": expected a positive number, got '" + text + "'");
  return *value;
}

std::vector<std::string> sorted_images(const std::string& directory) {
  std::vector<std::string> files;
  std::error_code ec;
  for (fs::directory_iterator it(directory, ec), end; !ec && it != end; it.increment(ec)) {
    if (!io::is_image_file_name(it->path().filename().string())) continue;
    std::error_code entry_ec;
    const fs::file_status status = fs::status(it->path(), entry_ec);
    if (entry_ec && status.type() != fs::file_type::not_found)
      throw input_error(clip_text(it->path().string()), "cannot read image entry: " + entry_ec.message());
    if (fs::is_regular_file(status)) files.push_back(it->path().string());
  }
  if (ec) throw input_error(clip_text(directory), "cannot list directory: " + ec.message());
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

bool looks_like_mot_sequence(const std::string& directory) {
  std::error_code ec;
  return fs::is_regular_file(fs::path(directory) / "seqinfo.ini", ec) ||
         fs::is_directory(fs::path(directory) / "img1", ec);
}

std::unique_ptr<io::Dataset> open_mot_sequence(const std::string& directory) {
  const std::string ini = (fs::path(directory) / "seqinfo.ini").string();
  std::error_code ec;
  std::map<std::string, std::string> info;
  if (fs::is_regular_file(ini, ec)) info = read_ini(ini);
  const std::string im_dir = (fs::path(directory) / (info.count("imDir") ? info["imDir"] : "img1")).string();
  if (!fs::is_directory(im_dir, ec)) throw input_error(im_dir, "no such image directory");
  io::DatasetContents c;
  c.directory = directory;
  c.layout = "mot";
  c.sensor = io::SensorKind::kMonocular;
  c.fps = info.count("frameRate") ? positive_number(ini, "frameRate", info["frameRate"]) : 30.0;
  std::vector<std::string> files;
  if (info.count("seqLength")) {
    const auto length = static_cast<std::size_t>(positive_number(ini, "seqLength", info["seqLength"]));
    const std::string ext = info.count("imExt") ? info["imExt"] : ".jpg";
    for (std::size_t i = 1; i <= length; ++i) {
      char name[32];
      std::snprintf(name, sizeof(name), "%06zu", i);
      const std::string file = (fs::path(im_dir) / (name + ext)).string();
      if (!fs::is_regular_file(file, ec))
        throw input_error(clip_text(file),
                          (ec && ec != std::errc::no_such_file_or_directory ? ec.message() + ": " : "") +
                              "missing image (" + clip_text(ini) +
                              " says seqLength=" + clip_text(info["seqLength"]) + ")");
      files.push_back(file);
    }
  } else {
    files = sorted_images(im_dir);
  }
  if (files.empty()) throw input_error(im_dir, "no image files in folder");
  for (std::size_t i = 0; i < files.size(); ++i)
    c.frames.push_back({i, static_cast<double>(i) / c.fps, files[i], {}, {}});
  c.colour_entries = files.size();
  return std::make_unique<io::Dataset>(std::move(c));
}

std::unique_ptr<io::FrameSource> open_detection_source(const std::string& spec) {
  std::error_code ec;
  if (fs::is_directory(spec, ec) && looks_like_mot_sequence(spec)) return open_mot_sequence(spec);
  return io::open_source(spec);
}

}  // namespace crowdslam::people
