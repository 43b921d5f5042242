#pragma once
// Shared by the report tests: short synthetic runs (sequential, reproducible) and a headless Chromium.
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <regex>
#include <string>

#include "crowdslam/run/run_sequence.h"
#include "crowdslam/synth/options.h"
#include "crowdslam/synth/writer.h"
#include "test_support.h"

namespace crowdslam::test {

// A synthetic RGB-D room with `people` walking people and their ground-truth boxes (people_gt.txt).
inline std::filesystem::path make_crowd_room(const TempDir& tmp, int people, int frames = 40) {
  synth::SynthOptions options;
  options.frames = frames;
  options.trajectory = synth::TrajectoryKind::kSweep;  // passes people (7 % of the image at most)
  options.people = people;
  options.seed = 5;
  const auto dir = tmp / ("room" + std::to_string(people) + "_" + std::to_string(frames));
  if (!std::filesystem::exists(dir)) synth::write_sequence(options, dir);
  return dir;
}

// A sequential run; with `filter` the people filter uses the ground-truth boxes (no detector network).
inline run::RunSummary run_room(const std::filesystem::path& dataset, const std::filesystem::path& out,
                                bool filter, size_t save_frames = 0) {
  run::RunOptions options;
  options.dataset = dataset.string();
  options.out_dir = out.string();
  options.sequential = true;
  options.progress = false;
  options.people_filter = filter;
  if (filter) options.detections_file = (dataset / "people_gt.txt").string();
  options.save_frames = save_frames;
  return run::run_sequence(options);
}

inline std::string chromium_binary() {
  for (const char* candidate : {"/usr/bin/chromium", "/usr/bin/chromium-browser"}) {
    if (std::filesystem::exists(candidate)) return candidate;
  }
  return "";
}

// Headless Chromium with networking disabled (every request goes to a dead proxy, loopback too) and a
// fresh profile in `work`. Returns the command's exit code (timeout 60 s).
inline int run_chromium(const std::filesystem::path& work, const std::string& arguments,
                        const std::filesystem::path& html) {
  static int call = 0;
  const auto profile = work / ("profile" + std::to_string(call++));
  const std::string command = "timeout 60 " + chromium_binary() +
                              " --headless=new --no-sandbox --disable-gpu --no-first-run"
                              " --disable-background-networking --disable-component-update"
                              " --proxy-server=127.0.0.1:9 --proxy-bypass-list='<-loopback>'"
                              " --user-data-dir='" +
                              profile.string() + "' " + arguments + " 'file://" +
                              std::filesystem::absolute(html).string() + "' 2>>'" +
                              (work / "chromium.log").string() + "'";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// The DOM after the page's scripts ran.
inline std::string dump_dom(const std::filesystem::path& work, const std::filesystem::path& html) {
  const auto dom_file = work / "dom.html";
  const int code = run_chromium(work, "--dump-dom > '" + dom_file.string() + "'", html);
  if (code != 0)
    return "chromium exited with " + std::to_string(code) + ": " + read_text(work / "chromium.log");
  return read_text(dom_file);
}

// The value of attribute `name` of <body> in a dumped DOM ("" when absent).
inline std::string body_attribute(const std::string& dom, const std::string& name) {
  std::smatch body;
  if (!std::regex_search(dom, body, std::regex("<body[^>]*>"))) return "";
  const std::string tag = body.str();
  std::smatch value;
  if (!std::regex_search(tag, value, std::regex(" " + name + "=\"([^\"]*)\""))) return "";
  return value[1].str();
}

}  // namespace crowdslam::test
