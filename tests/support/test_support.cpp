#include "test_support.h"

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <thread>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <random>
#include <regex>
#include <sstream>
#include <stdexcept>

namespace crowdslam::test {

std::filesystem::path shared_dir() {
  if (const char* env = std::getenv("CROWDSLAM_SHARED"); env != nullptr && *env != '\0') return env;
  return CROWDSLAM_DEFAULT_SHARED;
}

std::filesystem::path shared_data(const std::string& name) { return shared_dir() / "data" / name; }

bool shared_available(const std::string& name) { return std::filesystem::is_directory(shared_data(name)); }

std::filesystem::path source_dir() { return CROWDSLAM_SOURCE_DIR; }

TempDir::TempDir() {
  static std::atomic<int> counter{0};
  std::random_device rd;
  const auto base = std::filesystem::temp_directory_path();
  for (int attempt = 0; attempt < 100; ++attempt) {
    auto candidate = base / ("crowdslam_test_" + std::to_string(::getpid()) + "_" +
                             std::to_string(counter++) + "_" + std::to_string(rd() % 100000));
    if (std::filesystem::create_directory(candidate)) {
      path_ = candidate;
      return;
    }
  }
  throw std::runtime_error("cannot create temp dir");
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

void write_text(const std::filesystem::path& path, const std::string& content) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  out << content;
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<unsigned char> read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<unsigned char>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void write_bytes(const std::filesystem::path& path, const std::vector<unsigned char>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

namespace {
[[noreturn]] void exec_cli(const std::vector<std::string>& args) {
  std::vector<char*> argv;
  std::string program = CROWDSLAM_CLI_PATH;
  argv.push_back(program.data());
  std::vector<std::string> copy = args;
  for (auto& a : copy) argv.push_back(a.data());
  argv.push_back(nullptr);
  ::execv(program.c_str(), argv.data());
  _exit(127);
}
}  // namespace

CliProcess::CliProcess(const std::vector<std::string>& args, const ChildLimits& limits) {
  const auto out_path = tmp_ / "stdout";
  const auto err_path = tmp_ / "stderr";
  std::fflush(nullptr);
  pid_ = ::fork();
  if (pid_ < 0) throw std::runtime_error("fork failed");
  if (pid_ == 0) {
    if (!std::freopen(out_path.c_str(), "w", stdout) || !std::freopen(err_path.c_str(), "w", stderr)) _exit(127);
    if (limits.max_file_bytes >= 0) {
      std::signal(SIGXFSZ, SIG_IGN);  // the write fails with EFBIG instead of killing the process
      struct rlimit limit {};
      limit.rlim_cur = static_cast<rlim_t>(limits.max_file_bytes);
      limit.rlim_max = static_cast<rlim_t>(limits.max_file_bytes);
      if (::setrlimit(RLIMIT_FSIZE, &limit) != 0) _exit(126);
    }
    // The test runner may block or ignore signals; the child starts with the defaults.
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, nullptr);
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) std::signal(sig, SIG_DFL);
    exec_cli(args);
  }
}

CliProcess::~CliProcess() {
  if (pid_ > 0 && !reaped_) {
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, &status_, 0);
  }
}

void CliProcess::send_signal(int signal) const { ::kill(pid_, signal); }

void CliProcess::sleep_ms(int ms) { std::this_thread::sleep_for(std::chrono::milliseconds(ms)); }

bool CliProcess::exited() {
  if (reaped_) return true;
  if (::waitpid(pid_, &status_, WNOHANG) == pid_) reaped_ = true;
  return reaped_;
}

std::string CliProcess::current_stderr() const { return read_text(tmp_ / "stderr"); }

int wait_for_viewer_port(CliProcess& process, double timeout_s) {
  int port = 0;
  process.wait_until(
      [&] {
        std::smatch m;
        const std::string err = process.current_stderr();
        if (!std::regex_search(err, m, std::regex("viewer: http://127\\.0\\.0\\.1:([0-9]+)/"))) return false;
        port = std::stoi(m[1]);
        return true;
      },
      timeout_s);
  return port;
}

CliResult CliProcess::wait(double timeout_s) {
  CliResult result;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (!exited() && std::chrono::steady_clock::now() < deadline) sleep_ms(5);
  if (!reaped_) {
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, &status_, 0);
    reaped_ = true;
    result.exit_code = -1;
  } else {
    result.exit_code = WIFEXITED(status_) ? WEXITSTATUS(status_) : 128 + WTERMSIG(status_);
  }
  result.out = read_text(tmp_ / "stdout");
  result.err = read_text(tmp_ / "stderr");
  return result;
}

TwoBonnFrames copy_two_bonn_frames(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  const fs::path bonn = shared_data("bonn_crowd");
  fs::create_directories(dir / "rgb");
  fs::create_directories(dir / "depth");
  const char* rgb[] = {"1548339819.87426", "1548339819.90761"};
  const char* depth[] = {"1548339819.88851", "1548339819.92187"};
  TwoBonnFrames frames;
  std::string rgb_list, depth_list;
  for (int i = 0; i < 2; ++i) {
    frames.colour[i] = dir / "rgb" / (std::string(rgb[i]) + ".jpg");
    frames.depth[i] = dir / "depth" / (std::string(depth[i]) + ".png");
    fs::copy_file(bonn / "rgb" / frames.colour[i].filename(), frames.colour[i]);
    fs::copy_file(bonn / "depth" / frames.depth[i].filename(), frames.depth[i]);
    rgb_list += std::string(rgb[i]) + " rgb/" + rgb[i] + ".jpg\n";
    depth_list += std::string(depth[i]) + " depth/" + depth[i] + ".png\n";
  }
  write_text(dir / "rgb.txt", rgb_list);
  write_text(dir / "depth.txt", depth_list);
  return frames;
}

CliResult run_cli(const std::vector<std::string>& args) {
  CliProcess child(args);
  return child.wait(3600);
}

}  // namespace crowdslam::test
