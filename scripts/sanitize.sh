#!/usr/bin/env bash
# Sanitizer builds of crowdslam and end-to-end runs under them (see docs/SANITIZERS.md).
#   scripts/sanitize.sh [address|thread|all] [--ctest]
#     address   ASan + UBSan (and LeakSanitizer) in build-asan/
#     thread    TSan in build-tsan/
#     all       both (default)
#     --ctest   also build the e2e test executables and run `ctest -L e2e` in the sanitizer build dir
# Every run uses the default threaded mode (tracking + detection worker + local mapping + loop closing +
# frame prefetcher + journal writer), on every sensor: RGB-D (synthetic, bonn_crowd), monocular
# (bonn_crowd --sensor mono, kitti07_head and its every-3rd/4th-frame and from-frame-30 variants), stereo
# (euroc_v101_micro, right-image thread), and a run interrupted by SIGINT mid-way (the fast-stop path),
# and saved maps (save, localise, continue, export), the live viewer with clients and under stress
# (scripts/fuzz_inputs.py --only viewer: many event streams, slowloris, hostile requests); under TSan also the Python API's thread test (a
# TSan-built module in Debian's python3, libtsan preloaded). Any sanitizer report fails the script
# (halt_on_error, non-zero exit, and the logs are also grepped for reports as a second check).
# Environment: CROWDSLAM_JOBS (default 2), CROWDSLAM_SANITIZE_OUT (default out/sanitize),
#   CROWDSLAM_SANITIZE_BUILD_TYPE (default RelWithDebInfo), CROWDSLAM_SHARED (default ../shared),
#   CROWDSLAM_SANITIZE_FRAMES (synthetic frames, default 120), CROWDSLAM_SANITIZE_BONN_FRAMES (default 150),
#   CROWDSLAM_SANITIZE_PYTHON_FRAMES (frames of the Python thread test, default 30).
set -euo pipefail
cd "$(dirname "$0")/.."
root="$(pwd)"

which="all"
run_ctest=0
for arg in "$@"; do
  case "$arg" in
    address | thread | all) which="$arg" ;;
    --ctest) run_ctest=1 ;;
    -h | --help)
      sed -n '2,18p' "$0"
      exit 0
      ;;
    *)
      echo "sanitize.sh: unknown argument '$arg' (expected address, thread, all or --ctest)" >&2
      exit 2
      ;;
  esac
done

jobs="${CROWDSLAM_JOBS:-2}"
out_root="${CROWDSLAM_SANITIZE_OUT:-$root/out/sanitize}"
build_type="${CROWDSLAM_SANITIZE_BUILD_TYPE:-RelWithDebInfo}"
shared="${CROWDSLAM_SHARED:-$root/../shared}"
synth_frames="${CROWDSLAM_SANITIZE_FRAMES:-120}"
bonn_frames="${CROWDSLAM_SANITIZE_BONN_FRAMES:-150}"
bonn="$shared/data/bonn_crowd"
euroc="$shared/data/euroc_v101_micro"
kitti="$shared/data/kitti07_head"

# Patterns of sanitizer reports (second line of defence besides the exit code).
report_pattern='ERROR: AddressSanitizer|ERROR: LeakSanitizer|WARNING: ThreadSanitizer|runtime error:|SUMMARY: (Address|Thread|UndefinedBehavior|Leak)Sanitizer'

failures=()
summary=()

log() { printf '[sanitize] %s\n' "$*"; }

# Runs one step with its output in LOG; fails (returns 1) on a non-zero exit or a sanitizer report.
run_step() {
  local name="$1" logfile="$2"
  shift 2
  local start end rc=0
  start=$(date +%s)
  log "$name: $*"
  "$@" >"$logfile" 2>&1 || rc=$?
  end=$(date +%s)
  if ((rc == 0)) && grep -Eq "$report_pattern" "$logfile"; then rc=99; fi
  if ((rc != 0)); then
    log "$name: FAILED (exit $rc, $((end - start)) s), log $logfile"
    grep -E -m1 -A60 "$report_pattern" "$logfile" || tail -n 40 "$logfile"
    failures+=("$name")
    summary+=("$name: FAILED exit $rc ($((end - start)) s)")
    return 1
  fi
  log "$name: ok ($((end - start)) s)"
  summary+=("$name: ok ($((end - start)) s)")
}

# Runs a command in the background, sends SIGINT once its trajectory journal (DIR/CameraTrajectory.txt)
# holds 40 poses, and succeeds when it exits with 130 and run.json says "interrupted".
run_interrupted() {
  local dir="$1"
  shift
  "$@" &
  local pid=$! i
  for ((i = 0; i < 6000; ++i)); do
    if [[ -f "$dir/CameraTrajectory.txt" ]] && (($(grep -vc '^#' "$dir/CameraTrajectory.txt") >= 40)); then break; fi
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.1
  done
  kill -INT "$pid" 2>/dev/null || true
  local rc=0
  wait "$pid" || rc=$?
  echo "exit code $rc"
  [[ $rc -eq 130 ]] && grep -q '"end_state": "interrupted"' "$dir/run.json"
}

# A run with the live viewer and three clients (viewer server threads, event stream, observer thread):
# one takes batches with images to the end, one takes every message without images and leaves after
# 2 s (mid-stream), one polls /state and posts /client. Succeeds when the run exits 0 and the first client
# saw its end ("finish").
run_with_viewer_clients() {
  local logfile="$1"
  shift
  "$@" --viewer --viewer-port 0 2>"$logfile.run" &
  local pid=$! port="" i
  for ((i = 0; i < 600; ++i)); do
    port=$(grep -oE 'viewer: http://127\.0\.0\.1:[0-9]+/' "$logfile.run" | grep -oE '[0-9]+/$' | tr -d / || true)
    [[ -n "$port" ]] && break
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.1
  done
  [[ -n "$port" ]] || { cat "$logfile.run"; wait "$pid"; return 1; }
  curl -s -N "http://127.0.0.1:$port/events?batch_ms=500&image_width=320" >"$logfile.batched" &
  local batched=$!
  timeout 2 curl -s -N "http://127.0.0.1:$port/events?image=0" >/dev/null || true
  for ((i = 0; i < 5; ++i)); do
    curl -s "http://127.0.0.1:$port/state" >/dev/null || true
    curl -s -X POST -d '{"updates":1}' "http://127.0.0.1:$port/client" >/dev/null || true
  done
  local rc=0
  wait "$pid" || rc=$?
  wait "$batched" || true
  cat "$logfile.run"
  echo "exit code $rc; batched client: $(grep -c '^event:' "$logfile.batched") events"
  [[ $rc -eq 0 ]] && grep -q '^event: finish' "$logfile.batched"
}

# TSan suppressions: third-party libraries only, each with the reason (docs/SANITIZERS.md).
write_tsan_suppressions() {
  cat >"$1" <<'EOF'
# libgdal (loaded by OpenCV's imgcodecs): a lock-order inversion between GDAL's global
# "create or acquire mutex" lock and the mutex it hands out, reported on the main thread inside
# CPLCreateOrAcquireMutexEx / CPLAcquireMutex during the first cv::imread. Both stacks are entirely in
# GDAL (uninstrumented) and GDAL runs single-threaded here; not our code.
deadlock:libgdal.so
# libcpp-httplib (Debian's compiled cpp-httplib, uninstrumented): only the tests' HTTP client uses it now
# (the viewer's server is our own, viewer/http_server.h). It raced between two of its connection threads
# (a memcmp reading a heap block another thread wrote with memcpy), inside the library; its own
# synchronisation is not visible to TSan. called_from_lib ignores only the interceptors (memcpy, memcmp,
# ...) called directly from the library; our code stays checked.
called_from_lib:libcpp-httplib.so
EOF
}

# Sanitizer runtime options for SANITIZER into the environment (OUT: where the suppression file goes).
set_sanitizer_env() {
  local sanitizer="$1" out="$2"
  unset ASAN_OPTIONS UBSAN_OPTIONS TSAN_OPTIONS LSAN_OPTIONS
  if [[ "$sanitizer" == address ]]; then
    # exitcode 86 (TSan's default is 66): a report is never mistaken for the CLI's own "exit 1" error
    # path, which the CLI tests expect (they capture the child's stderr, so only the code shows).
    export ASAN_OPTIONS="halt_on_error=1:detect_leaks=1:check_initialization_order=1:strict_init_order=1:detect_stack_use_after_return=1:exitcode=86"
    export LSAN_OPTIONS="exitcode=86"
    export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:exitcode=86"
  else
    write_tsan_suppressions "$out/tsan.supp"
    export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:history_size=4:suppressions=$out/tsan.supp"
    # OpenCV's parallel_for_ backend here is TBB (uninstrumented); our code never runs inside it, but one
    # OpenCV thread keeps every OpenCV call on the calling thread so TSan sees the whole picture.
    export OPENCV_FOR_THREADS_NUM=1
    # CHOLMOD (Ceres' sparse Schur backend, SuiteSparse 5) opens OpenMP regions with an explicit
    # num_threads clause; libgomp's barriers are invisible to TSan, which then reports the worker's
    # memset of a cholmod_malloc block as a race (false positive). OMP_NUM_THREADS does not override an
    # explicit num_threads clause, OMP_THREAD_LIMIT does: the regions run on the local mapping thread.
    export OMP_NUM_THREADS=1 OMP_THREAD_LIMIT=1
  fi
}

# The Python API's thread-safety test (tests/python/test_threads.py: one Python thread tracking, one
# reading map_points() repeatedly, threaded and sequential) against the TSan-built module. Debian's python3
# is not instrumented, so the TSan runtime is preloaded into it; the GIL is a pthread mutex/condvar pair,
# which TSan's interceptors see, so Python-level hand-offs are not reported as races.
run_python_threads() {
  local build_dir="$1" bin="$2" out="$3" t0
  t0=$(date +%s)
  if ! configure_and_build thread "$build_dir" crowdslam_python >"$out/python_build.log" 2>&1; then
    log "tsan python: module build failed, log $out/python_build.log"
    failures+=("tsan python build")
    summary+=("tsan python build: FAILED")
    return 1
  fi
  summary+=("tsan python build: $(($(date +%s) - t0)) s")
  run_step "tsan python threads (pytest tests/python/test_threads.py)" "$out/python_threads.log" \
    env LD_PRELOAD="$(gcc -print-file-name=libtsan.so)" PYTHONPATH="$build_dir/python" PYTHONDONTWRITEBYTECODE=1 \
    CROWDSLAM_CLI="$bin" CROWDSLAM_SOURCE_DIR="$root" CROWDSLAM_SHARED_DIR="$shared" \
    CROWDSLAM_PYTEST_THREAD_FRAMES="${CROWDSLAM_SANITIZE_PYTHON_FRAMES:-30}" \
    /usr/bin/python3 -m pytest -v -p no:cacheprovider "$root/tests/python/test_threads.py"
}

configure_and_build() {
  local sanitizer="$1" build_dir="$2"
  shift 2
  local configured=""
  if [[ -f "$build_dir/CMakeCache.txt" ]]; then
    configured=$(sed -n 's/^CROWDSLAM_SANITIZE:STRING=//p' "$build_dir/CMakeCache.txt")
  fi
  if [[ ! -f "$build_dir/build.ninja" || "$configured" != "$sanitizer" ]]; then
    cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE="$build_type" -DCROWDSLAM_SANITIZE="$sanitizer" \
      -DCROWDSLAM_BUILD_BENCH=OFF >/dev/null
  fi
  cmake --build "$build_dir" --target "$@" -j "$jobs"
}

run_sanitizer() {
  local sanitizer="$1" build_dir tag
  if [[ "$sanitizer" == address ]]; then tag=asan; else tag=tsan; fi
  build_dir="$root/build-$tag"
  local out="$out_root/$tag"
  rm -rf "$out"
  mkdir -p "$out"
  log "== $sanitizer: build in $build_dir, outputs in $out"
  local t0
  t0=$(date +%s)
  configure_and_build "$sanitizer" "$build_dir" crowdslam
  summary+=("$tag build: $(($(date +%s) - t0)) s")
  local bin="$build_dir/apps/crowdslam/crowdslam"
  set_sanitizer_env "$sanitizer" "$out"
  local seq="$out/sequence"

  run_step "$tag synth" "$out/synth.log" \
    "$bin" synth --out "$seq" --frames "$synth_frames" --people 3 --trajectory handheld \
    --width 640 --height 480 --force || return 0
  run_step "$tag run synth (gt boxes)" "$out/run_gt.log" \
    "$bin" run --dataset "$seq" --out "$out/run_gt" --overwrite --detections "$seq/people_gt.txt" || true
  run_step "$tag run synth (detector)" "$out/run_detector.log" \
    "$bin" run --dataset "$seq" --out "$out/run_detector" --overwrite || true
  # Box keypoints with depth (PeopleFilter.static_in_boxes "always"; the RGB-D default leaves them out).
  { cat "$seq/settings.yaml"; printf '\nPeopleFilter.static_in_boxes: "always"\n'; } >"$out/always.yaml"
  run_step "$tag run synth (detector, box keypoints always)" "$out/run_boxes.log" \
    "$bin" run --dataset "$seq" --settings "$out/always.yaml" --out "$out/run_boxes" --overwrite || true
  run_step "$tag run synth (no people filter)" "$out/run_nofilter.log" \
    "$bin" run --dataset "$seq" --out "$out/run_nofilter" --overwrite --no-people-filter || true
  run_step "$tag run synth with the live viewer and three clients" "$out/run_viewer.log" \
    run_with_viewer_clients "$out/run_viewer.log" "$bin" run --dataset "$seq" --out "$out/run_viewer" --overwrite || true
  # The viewer under stress (issue 37): 40 event streams at once (16 served, the rest 503), 10 slowloris
  # sockets, and hostile requests (garbage, bad bodies, huge headers) while /state is probed after each.
  run_step "$tag viewer stress (many clients, slowloris, hostile requests)" "$out/viewer_stress.log" \
    python3 "$root/scripts/fuzz_inputs.py" --bin "$bin" --only viewer --cases 120 --time-budget 300 --timeout 120 \
    --seed 5 || true
  # Two laps with noisy depth: a loop is closed, so loop correction and the global-BA thread run.
  run_step "$tag synth (two laps)" "$out/synth_loop.log" \
    "$bin" synth --out "$out/loop_sequence" --frames 600 --noise-depth 0.05 --width 480 --height 360 --force ||
    return 0
  run_step "$tag run synth two laps (loop closing)" "$out/run_loop.log" \
    "$bin" run --dataset "$out/loop_sequence" --out "$out/run_loop" --overwrite --no-people-filter || true
  if [[ -f "$bonn/rgb.txt" ]]; then
    run_step "$tag run bonn_crowd ($bonn_frames frames, depth filter, --save-map)" "$out/run_bonn.log" \
      "$bin" run --dataset "$bonn" --settings config/Bonn.yaml --frames "$bonn_frames" --filter-mode depth \
      --out "$out/run_bonn" --save-map "$out/bonn.db" || true
    # Saved maps: localisation in the map just saved, and continue mapping from it.
    run_step "$tag run bonn_crowd --load-map --localization" "$out/run_bonn_loc.log" \
      "$bin" run --dataset "$bonn" --settings config/Bonn.yaml --frames "$bonn_frames" --filter-mode depth \
      --out "$out/run_bonn_loc" --load-map "$out/bonn.db" --localization || true
    run_step "$tag run bonn_crowd --load-map (continue mapping)" "$out/run_bonn_continue.log" \
      "$bin" run --dataset "$bonn" --settings config/Bonn.yaml --frames "$bonn_frames" --filter-mode depth \
      --out "$out/run_bonn_continue" --load-map "$out/bonn.db" --save-map "$out/bonn2.db" || true
    run_step "$tag map info/export" "$out/map_export.log" \
      "$bin" map export "$out/bonn2.db" --ply "$out/bonn2.ply" --keyframes "$out/bonn2_kf.ply" \
      --trajectory "$out/bonn2_kf.txt" || true
    run_step "$tag map optimise" "$out/map_optimise.log" \
      "$bin" map optimise "$out/bonn2.db" --out "$out/bonn2_opt.db" --iterations 5 --overwrite || true
    # The detector decoupled from tracking (YOLOX ONNX, boxes moved by optical flow between detections,
    # the box tracker): the detection worker takes the newest frame while tracking goes on.
    if [[ -f "$shared/models/yolox-nano/yolox_nano.onnx" ]]; then
      run_step "$tag run bonn_crowd yolox latest + box tracker ($bonn_frames frames)" "$out/run_bonn_latest.log" \
        "$bin" run --dataset "$bonn" --settings config/Bonn.yaml --frames "$bonn_frames" --detector yolox \
        --detector-mode latest --box-tracker on --out "$out/run_bonn_latest" || true
    fi
    # Monocular on the same frames (two-view initialisation, monocular keyframe policy).
    run_step "$tag run bonn_crowd mono ($bonn_frames frames)" "$out/run_bonn_mono.log" \
      "$bin" run --dataset "$bonn" --settings config/Bonn.yaml --frames "$bonn_frames" --sensor mono \
      --allow-untracked --out "$out/run_bonn_mono" || true
    # Interrupted mid-run: the signal path stops every thread at once and writes the outputs.
    run_step "$tag run bonn_crowd interrupted (SIGINT)" "$out/run_interrupt.log" \
      run_interrupted "$out/run_interrupt" "$bin" run --dataset "$bonn" --settings config/Bonn.yaml \
      --out "$out/run_interrupt" || true
  else
    log "$tag: $bonn not found, skipping the Bonn runs"
    summary+=("$tag run bonn_crowd: skipped (no data)")
  fi
  if [[ -d "$euroc/mav0" ]]; then
    # Stereo: right-image ORB on its own thread, rectification from EuRoC's sensor.yaml.
    run_step "$tag run euroc_v101_micro (stereo)" "$out/run_euroc.log" \
      "$bin" run --dataset "$euroc" --settings config/EuRoC.yaml --out "$out/run_euroc" || true
  else
    summary+=("$tag run euroc stereo: skipped (no data)")
  fi
  if [[ -f "$kitti/times.txt" ]]; then
    run_step "$tag run kitti07_head (mono)" "$out/run_kitti.log" \
      "$bin" run --dataset "$kitti" --settings config/KITTI04-12.yaml --sensor mono --no-people-filter \
      --allow-untracked --out "$out/run_kitti" || true
    # Every 3rd frame (weak tracking: keyframes the next frame waits for), every 4th (waits for every due
    # keyframe, the last frame's keyframe points read by the motion model) and from frame 30 (frames before
    # the initialisation retried once the map has grown).
    local variant
    for variant in "stride3:--stride 3" "stride4:--stride 4" "from30:--start 30"; do
      rm -rf "$out/kitti_${variant%%:*}"
      # shellcheck disable=SC2086  # the options are two words on purpose
      python3 scripts/make_variant.py "$kitti" "$out/kitti_${variant%%:*}" ${variant#*:} >/dev/null
      run_step "$tag run kitti07_head ${variant#*:} (mono)" "$out/run_kitti_${variant%%:*}.log" \
        "$bin" run --dataset "$out/kitti_${variant%%:*}" --settings config/KITTI04-12.yaml --sensor mono \
        --no-people-filter --allow-untracked --out "$out/run_kitti_${variant%%:*}" || true
    done
  else
    summary+=("$tag run kitti07_head mono: skipped (no data)")
  fi

  if [[ "$sanitizer" == thread ]]; then run_python_threads "$build_dir" "$bin" "$out" || true; fi

  if ((run_ctest)); then
    local t1
    t1=$(date +%s)
    configure_and_build "$sanitizer" "$build_dir" test_cli test_system
    summary+=("$tag test build: $(($(date +%s) - t1)) s")
    # The e2e tests carry the labels "cli" / "system" (and "e2e" once gtest_discover_tests keeps both
    # labels, see docs/SANITIZERS.md), so select by all three.
    run_step "$tag ctest e2e" "$out/ctest.log" \
      ctest --test-dir "$build_dir" -L '^(e2e|cli|system)$' --output-on-failure --timeout 1800 || true
  fi
  unset OPENCV_FOR_THREADS_NUM OMP_NUM_THREADS OMP_THREAD_LIMIT
}

case "$which" in
  all) sanitizers=(address thread) ;;
  *) sanitizers=("$which") ;;
esac
for s in "${sanitizers[@]}"; do run_sanitizer "$s"; done

log "== summary"
printf '  %s\n' "${summary[@]}"
if ((${#failures[@]})); then
  log "FAILED: ${failures[*]}"
  exit 1
fi
log "all clean"
