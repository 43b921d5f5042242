#pragma once
// The report every `crowdslam run` writes at the end (OUT/report.html), after its other outputs.
//
// A report that cannot be written (no Chart.js, a full disk, ...) never costs the run anything: the
// error is logged (spdlog::warn) and recorded in OUT/run.json as "report_error", and the run's exit
// code is unchanged (the trajectories and run.json are complete; `crowdslam report OUT` retries).
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

namespace crowdslam::report {

// Writes OUT/report.html from the run's files. On failure: the message, also stored in
// `run_document["report_error"]` and OUT/run.json rewritten with it (atomically; best effort).
std::optional<std::string> write_run_report(const std::filesystem::path& out_dir,
                                            nlohmann::json& run_document);

}  // namespace crowdslam::report
