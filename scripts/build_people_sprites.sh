#!/usr/bin/env bash
# Builds the person sprites of `crowdslam synth`, people_sprites/ (git-ignored; scripts/setup.sh runs this
# after the vocabulary), with `crowdslam synth-sprites`: people cut out with grabCut from the ground-truth
# boxes of the MOT sequences in $CROWDSLAM_SHARED/data/mot, else ../shared/data/mot (TUD-Campus,
# TUD-Stadtmitte; PETS09's people are too small). Nothing is committed.
#   scripts/build_people_sprites.sh [--force] [BUILD_DIR]     (BUILD_DIR default: build)
# Skipped when people_sprites/ is complete: sprites.json and every file listed in its SHA256SUMS are
# there and match. Without the MOT sequences nothing is built and `crowdslam synth` says once that its
# people are textured boxes. The extraction is deterministic (about a minute on 2 cores).
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
force=0
if [[ "${1:-}" == "--force" ]]; then force=1; shift; fi
build_dir="${1:-$repo/build}"
[[ "$build_dir" = /* ]] || build_dir="$PWD/$build_dir"

out="$repo/people_sprites"
# sprites.json of the reference build (../shared's MOT sequences, Debian 12's OpenCV 4.6 and libjpeg-turbo).
expected_sha256="3b91225e6a0189f6df7f8f566550aedd32c5e8ad5632759d5ab3738582727858"
mot="${CROWDSLAM_SHARED:-$repo/../shared}/data/mot"

if [[ $force -eq 0 && -f "$out/sprites.json" && -f "$out/SHA256SUMS" ]] &&
  (cd "$out" && sha256sum --quiet --strict -c SHA256SUMS >/dev/null 2>&1); then
  echo "build_people_sprites: $out is up to date ($(($(wc -l <"$out/SHA256SUMS") - 1)) sprites)"
  exit 0
fi
if [[ ! -d "$mot" ]]; then
  echo "build_people_sprites: no MOT sequences in $mot: synth people stay textured boxes" >&2
  exit 0
fi
crowdslam="$build_dir/apps/crowdslam/crowdslam"
[[ -x "$crowdslam" ]] || { echo "build_people_sprites: error: $crowdslam not built" >&2; exit 1; }

"$crowdslam" -q synth-sprites --out "$out" --mot "$mot" --force
(cd "$out" && sha256sum -- sprites.json ./*.png >SHA256SUMS.tmp && mv SHA256SUMS.tmp SHA256SUMS)
sha="$(sha256sum "$out/sprites.json" | cut -d' ' -f1)"
if [[ "$sha" != "$expected_sha256" ]]; then
  echo "build_people_sprites: warning: sprites.json SHA-256 $sha differs from the recorded $expected_sha256" \
    "(other MOT data or decoder versions?); the sprites are usable but not the reference ones" >&2
fi
echo "build_people_sprites: wrote $out ($(($(wc -l <"$out/SHA256SUMS") - 1)) sprites, sprites.json SHA-256 $sha)"
