#include "crowdslam/report/run_report.h"

#include <spdlog/spdlog.h>

#include "crowdslam/report/report.h"
#include "crowdslam/util/atomic_file.h"

namespace crowdslam::report {

std::optional<std::string> write_run_report(const std::filesystem::path& out_dir,
                                            nlohmann::json& run_document) {
  std::string error;
  try {
    write_report(out_dir, {}, out_dir / "report.html");
    return std::nullopt;
  } catch (const std::exception& e) {
    error = e.what();
  }
  spdlog::warn(
      "report.html not written (the run's other outputs are complete; `crowdslam report {}` retries): {}",
      out_dir.string(), error);
  run_document["report_error"] = error;
  try {
    write_file_atomic(out_dir / "run.json",
                      run_document.dump(1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
  } catch (const std::exception& e) {
    spdlog::warn("run.json not updated with the report error: {}", e.what());
  }
  return error;
}

}  // namespace crowdslam::report
