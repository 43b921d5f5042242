#!/usr/bin/env bash
# Installs the person-detector models into <repo>/models/yolo-fastest-1.1/ (git-ignored; weights are
# never committed). Idempotent: files already installed with the right checksum are left alone.
#   scripts/install_models.sh [TARGET_DIR]
# Source, in order:
#   1. $CROWDSLAM_SHARED/models/yolo-fastest-1.1, else ../shared/models/yolo-fastest-1.1 (copied)
#   2. the upstream repository dog-qiuqiu/Yolo-Fastest (ModelZoo/yolo-fastest-1.1_body/ and
#      ModelZoo/yolo-fastest-1.1_coco/), downloaded with curl or wget
# Every model file is checked against the SHA-256 sums below (the same as ../shared's SHA256SUMS);
# a mismatch stops with one error line and leaves no bad file installed.
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
target="${1:-$repo/models/yolo-fastest-1.1}"
shared="${CROWDSLAM_SHARED:-$repo/../shared}/models/yolo-fastest-1.1"
upstream="https://raw.githubusercontent.com/dog-qiuqiu/Yolo-Fastest/master"

# name  sha256  upstream path ("-" = written locally, "?" = optional: skipped if it cannot be fetched)
manifest=(
  "yolo-fastest-1.1_body.cfg 045b8e276ebe3924474da8c866b7e709159ea067137b5d66bf9dd560411b2c1a ModelZoo/yolo-fastest-1.1_body/yolo-fastest-1.1_body.cfg"
  "yolo-fastest-1.1_body.weights 5bbb6d878f6e2eb3deee39e91dc6f9b39700e99ec83fa94d258670a554949728 ModelZoo/yolo-fastest-1.1_body/yolo-fastest-1.1_body.weights"
  "yolo-fastest-1.1.cfg f6df5775c1e862998cf69046eba9265be3ae84dfe8b2caab7529823f0795bf70 ModelZoo/yolo-fastest-1.1_coco/yolo-fastest-1.1.cfg"
  "yolo-fastest-1.1.weights 1c445c42bbd6df63edea2cc69f99667b5650d663ca11e34b116240740cd42890 ModelZoo/yolo-fastest-1.1_coco/yolo-fastest-1.1.weights"
  "body.names 9e2ec912af5dff2a72300863864fc4da04e81999339d9fac5c7590ba8a3f4e11 -"
  "coco.names 634a1132eb33f8091d60f2c346ababe8b905ae08387037aed883953b7329af84 ?data/coco.names"
  "LICENSE 2021f0b8d6426fbf9a2f0126f1e8a7d3b1d7027c871b9979fa2543b9557000c4 ?LICENSE"
)

die() { echo "install_models: error: $*" >&2; exit 1; }
sha_of() { sha256sum "$1" | cut -d' ' -f1; }

fetch() {  # url output
  if command -v curl >/dev/null; then curl -fsSL --retry 2 -o "$2" "$1"
  elif command -v wget >/dev/null; then wget -q -O "$2" "$1"
  else return 1; fi
}

mkdir -p "$target"
tmp="$(mktemp -d "$target/.install.XXXXXX")"
trap 'rm -rf "$tmp"' EXIT
installed=0
for entry in "${manifest[@]}"; do
  read -r name sum source <<<"$entry"
  dest="$target/$name"
  if [[ -f "$dest" && "$(sha_of "$dest")" == "$sum" ]]; then continue; fi
  optional=0
  if [[ "$source" == \?* ]]; then optional=1; source="${source#\?}"; fi
  if [[ -f "$shared/$name" ]]; then
    cp "$shared/$name" "$tmp/$name" && chmod 644 "$tmp/$name"
    from="$shared/$name"
  elif [[ "$source" == "-" ]]; then
    printf 'body\n' >"$tmp/$name"
    from="(written locally)"
  elif fetch "$upstream/$source" "$tmp/$name"; then
    from="$upstream/$source"
  elif ((optional)); then
    echo "install_models: warning: could not fetch optional $name from $upstream/$source" >&2
    continue
  else
    die "$name: not in $shared and the download from $upstream/$source failed"
  fi
  actual="$(sha_of "$tmp/$name")"
  [[ "$actual" == "$sum" ]] || die "$name: SHA-256 mismatch (from $from): expected $sum, got $actual"
  mv -f "$tmp/$name" "$dest"
  installed=$((installed + 1))
done

# Keep a SHA256SUMS beside the files and verify the whole set the standard way.
(
  cd "$target"
  for entry in "${manifest[@]}"; do
    read -r name sum _ <<<"$entry"
    [[ -f "$name" ]] && echo "$sum  $name"
  done >SHA256SUMS
  sha256sum -c --quiet SHA256SUMS
) || die "checksum verification failed in $target"
echo "install_models: $target ready ($installed file(s) installed)"
