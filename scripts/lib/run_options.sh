# Sourced by the measurement scripts (bench_run.sh, measure_localization.sh, measure_viewer.sh):
# parses "[-n RUNS] [-b BUILD_DIR] -- RUN_ARGS..." into $runs, $build, $bin and the array run_args.
# $runs keeps the caller's default when -n is not given; $script names the caller in messages.
parse_run_options() {
  build=build
  while [[ $# -gt 0 && "$1" != "--" ]]; do
    case "$1" in
      -n) runs="$2"; shift 2 ;;
      -b) build="$2"; shift 2 ;;
      *) echo "$script: unknown option $1" >&2; exit 2 ;;
    esac
  done
  [[ "${1:-}" == "--" ]] && shift
  run_args=("$@")
  bin="$build/apps/crowdslam/crowdslam"
  [[ -x "$bin" ]] || { echo "$script: $bin not built (run scripts/setup.sh)" >&2; exit 1; }
}
