// `crowdslam report OUT [--compare OUT2 ...] [--out FILE]`: report.html for a finished run, or several
// runs overlaid (one colour and one summary column per run). Default output OUT/report.html.
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "crowdslam/report/report.h"

namespace crowdslam::app {

namespace {
struct ReportArgs {
  std::string run_dir;
  std::vector<std::string> compare;
  std::string out;
  size_t max_frames = 24;
};
}  // namespace

void add_report_command(CLI::App& app, const GlobalOptions& global) {
  auto args = std::make_shared<ReportArgs>();
  auto* cmd = app.add_subcommand("report",
                                 "Write a self-contained HTML report of a run (charts, trajectory, frames)");
  cmd->add_option("run", args->run_dir, "Output directory of a finished `crowdslam run` (--out)")->required();
  cmd->add_option("--compare", args->compare, "Further run directories, overlaid on the first")
      ->expected(1, -1);
  cmd->add_option("--out", args->out, "HTML file to write (default RUN/report.html)");
  cmd->add_option("--max-frames", args->max_frames, "Saved frames (--save-frames) shown, shared by the runs")
      ->check(CLI::Range(0, 1000));
  cmd->callback([args, &global] {
    std::vector<std::filesystem::path> compare(args->compare.begin(), args->compare.end());
    const std::filesystem::path out = args->out.empty() ? std::filesystem::path(args->run_dir) / "report.html"
                                                        : std::filesystem::path(args->out);
    report::ReportOptions options;
    options.frames.max_frames = args->max_frames;
    const auto result = report::write_report(args->run_dir, compare, out, options);
    if (global.json) {
      print_json({{"report", result.path.string()},
                  {"bytes", result.bytes},
                  {"runs", result.runs},
                  {"frames_embedded", result.frames_embedded},
                  {"write_ms", result.write_ms}});
      return;
    }
    std::cout << "report            " << result.path.string() << " (" << result.bytes / 1024 << " KiB, "
              << result.runs << (result.runs > 1 ? " runs" : " run") << ")\n";
  });
}

}  // namespace crowdslam::app
