#!/usr/bin/env bash
# Installs what crowdslam needs from Debian 12 packages (only what is missing), then configures and
# builds it. Idempotent: a second run with nothing changed only runs the (no-op) incremental build.
#   scripts/setup.sh [--target T]... [BUILD_DIR] [extra cmake args...]
# --target builds only that CMake target and what it needs (scripts/demo.sh: --target crowdslam, the
# CLI); without it everything is built: libraries, CLI, tests, benchmarks and the Python module.
# Environment: CROWDSLAM_BUILD_TYPE (default Release), CROWDSLAM_JOBS (default: number of cores).
set -euo pipefail
cd "$(dirname "$0")/.."
targets=()
while [[ "${1:-}" == "--target" ]]; do
  [[ -n "${2:-}" ]] || { echo "setup: error: --target needs a target name" >&2; exit 1; }
  targets+=(--target "$2")
  shift 2
done
build_dir="${1:-build}"
shift || true

packages=(
  build-essential cmake ninja-build pkg-config git ca-certificates curl time python3
  libopencv-dev libeigen3-dev libceres-dev libcli11-dev libspdlog-dev nlohmann-json3-dev libjpeg62-turbo-dev
  libdeflate-dev   # fast inflate (and CRC-32) for the PNG decoder: depth maps, KITTI/TUM images
  libgtest-dev libgmock-dev libbenchmark-dev libsqlite3-dev
  opencv-doc   # sample photographs and videos: textures for `crowdslam synth`, vocabulary training
  libjs-chart.js chromium   # report.html inlines Chart.js; the report tests open it in headless Chromium
  libjs-three libcpp-httplib-dev   # the live viewer: three.js served by our own HTTP server
  pybind11-dev python3-dev python3-numpy python3-pytest   # the Python module (build/python) and its tests
  snakemake   # the evaluation workflow (workflows/) and its tests
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if ((${#missing[@]})); then
  echo "setup: installing ${#missing[@]} Debian packages: ${missing[*]}"
  sudo_cmd=()
  if [[ $(id -u) -ne 0 ]]; then sudo_cmd=(sudo); fi
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

jobs="${CROWDSLAM_JOBS:-$(nproc)}"
if [[ ! -f "$build_dir/build.ninja" ]]; then
  echo "setup: configuring $build_dir (cmake)"
  cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE="${CROWDSLAM_BUILD_TYPE:-Release}" "$@"
fi
if ((${#targets[@]})); then
  echo "setup: building ${targets[*]} with $jobs jobs (ninja shows [done/total])"
else
  echo "setup: building everything with $jobs jobs (ninja shows [done/total])"
fi
cmake --build "$build_dir" -j "$jobs" "${targets[@]}"
echo "setup: default vocabulary, person-detector models and person sprites"

# Default ORB vocabulary (vocabulary/crowdslam_orb.voc, never committed): trained from opencv-doc's
# sample images in about 10 s; skipped when present with the recorded SHA-256.
if ! bash scripts/build_vocabulary.sh "$build_dir" >/dev/null; then
  echo "setup: warning: default vocabulary not built (see the error above)" >&2
fi

# Person sprites for `crowdslam synth` (people_sprites/, never committed): people cut out of the MOT
# sequences in ../shared; skipped when complete. Without them synth's people are textured boxes.
if ! bash scripts/build_people_sprites.sh "$build_dir" >/dev/null; then
  echo "setup: warning: person sprites not built (see the error above)" >&2
fi

# Person-detector models (copied from ../shared or downloaded with a SHA-256 check; never committed).
# Without them `crowdslam run` needs --no-people-filter or --detections, and detector tests are skipped.
if ! bash scripts/install_models.sh >/dev/null; then
  echo "setup: warning: person-detector models not installed (see the error above)" >&2
fi
echo "setup: done ($build_dir/apps/crowdslam/crowdslam)"
