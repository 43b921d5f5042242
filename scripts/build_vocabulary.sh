#!/usr/bin/env bash
# Builds the default ORB vocabulary, vocabulary/crowdslam_orb.voc (git-ignored; scripts/setup.sh runs
# this after the build), with `crowdslam vocab train` from the sample photographs and videos of the
# Debian package opencv-doc. No evaluation sequence (../shared) is used.
#   scripts/build_vocabulary.sh [--force] [BUILD_DIR]     (BUILD_DIR default: build)
# Skipped when the file exists with the SHA-256 below; --force retrains anyway. Training is
# deterministic: the same package files, decoders and seed give the same bytes (about 10 s here).
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
force=0
if [[ "${1:-}" == "--force" ]]; then force=1; shift; fi
build_dir="${1:-$repo/build}"
[[ "$build_dir" = /* ]] || build_dir="$PWD/$build_dir"

out="$repo/vocabulary/crowdslam_orb.voc"
expected_sha256="f1732294fcceb24f12b5b7820893ee4fdc40168bd5022bc92dd7c3b78d49e669"
data=/usr/share/doc/opencv-doc/examples/data  # package opencv-doc 4.6.0+dfsg-12 (Debian 12)
# Real photographs of the package (drawings, text, logos, charts and calibration boards left out) ...
photos=(aero1.jpg aero3.jpg aloeL.jpg aloeR.jpg apple.jpg baboon.jpg basketball1.png basketball2.png
  board.jpg box.png box_in_scene.png building.jpg butterfly.jpg chicky_512.png ela_original.jpg fruits.jpg
  graf1.png graf3.png home.jpg left.jpg right.jpg leuvenA.jpg leuvenB.jpg licenseplate_motion.jpg
  messi5.jpg orange.jpg rubberwhale1.png rubberwhale2.png smarties.png squirrel_cls.jpg stuff.jpg sudoku.png)
# ... and every 5th frame of its videos (pedestrians in a square, a tree, an animated film).
videos=(vtest.avi tree.avi Megamind.avi)

sha_of() { sha256sum "$1" | cut -d' ' -f1; }

if [[ -f "$out" && $force -eq 0 && "$(sha_of "$out")" == "$expected_sha256" ]]; then
  echo "build_vocabulary: $out is up to date"
  exit 0
fi
crowdslam="$build_dir/apps/crowdslam/crowdslam"
[[ -x "$crowdslam" ]] || { echo "build_vocabulary: error: $crowdslam not built" >&2; exit 1; }
[[ -d "$data" ]] || { echo "build_vocabulary: error: $data missing (apt-get install opencv-doc)" >&2; exit 1; }

mkdir -p "$(dirname "$out")"
cd "$data"  # relative input names, so the log is short
"$crowdslam" vocab train --out "$out" --force --k 10 --levels 5 --seed 1 --features 1000 --every 5 \
  "${photos[@]}" "${videos[@]}"
sha="$(sha_of "$out")"
if [[ "$sha" != "$expected_sha256" ]]; then
  echo "build_vocabulary: warning: SHA-256 $sha differs from the recorded $expected_sha256" \
    "(other image decoder versions?); the vocabulary is usable but not the reference one" >&2
fi
echo "build_vocabulary: wrote $out (SHA-256 $sha)"
