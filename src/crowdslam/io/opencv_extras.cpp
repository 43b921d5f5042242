#include "crowdslam/io/opencv_extras.h"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <stdexcept>

namespace crowdslam::io {
namespace {

constexpr const char* kModuleName = "libcrowdslam_opencv_extras.so";

// $CROWDSLAM_OPENCV_EXTRAS; else the module beside the binary or library this code is in (an installed
// Python package carries its own copy); else where the build wrote it.
std::string module_path() {
  const char* env = std::getenv("CROWDSLAM_OPENCV_EXTRAS");
  if (env != nullptr && *env != '\0') return env;
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&opencv_extras), &info) != 0 && info.dli_fname != nullptr) {
    std::error_code ec;
    const auto beside = std::filesystem::path(info.dli_fname).parent_path() / kModuleName;
    if (std::filesystem::is_regular_file(beside, ec)) return beside.string();
  }
  return CROWDSLAM_OPENCV_EXTRAS_PATH;  // set by src/crowdslam/io/CMakeLists.txt
}

const OpenCvExtras* load() {
  const std::string path = module_path();
  void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    const char* why = dlerror();
    throw std::runtime_error("cannot load OpenCV's image codecs and video input (" + path +
                             "): " + (why != nullptr ? why : "unknown error") +
                             "; set CROWDSLAM_OPENCV_EXTRAS to the built libcrowdslam_opencv_extras.so");
  }
  using Entry = const OpenCvExtras* (*)();
  auto entry = reinterpret_cast<Entry>(dlsym(handle, "crowdslam_opencv_extras"));
  if (entry == nullptr) throw std::runtime_error(path + " has no crowdslam_opencv_extras entry point");
  return entry();  // never unloaded: OpenCV's libraries keep threads and static state
}

}  // namespace

const OpenCvExtras& opencv_extras() {
  static const OpenCvExtras* extras = load();  // a failed load throws and is retried by the next call
  return *extras;
}

}  // namespace crowdslam::io
