#!/usr/bin/env bash
# Installs the person-detector models into <repo>/models/<folder>/ (git-ignored; weights are never
# committed). Idempotent: files already installed with the right checksum are left alone.
#   scripts/install_models.sh [MODELS_DIR]        (default <repo>/models; one folder per model below it)
# Folders (people/model_zoo.cpp names the models in them):
#   yolo-fastest-1.1/  body, coco (required: the SLAM default)
#   yolox-nano/        yolox      (optional)
#   bytetrack-nano/    bytetrack  (optional)
# Source, in order:
#   1. $CROWDSLAM_SHARED/models/<folder>, else ../shared/models/<folder> (copied)
#   2. Yolo-Fastest only: the upstream repository dog-qiuqiu/Yolo-Fastest (ModelZoo/yolo-fastest-1.1_body/
#      and ModelZoo/yolo-fastest-1.1_coco/), downloaded with curl or wget. The ONNX models have no
#      download source here: without ../shared they are skipped with a warning.
# Every model file is checked against the SHA-256 sums below (the same as the SHA256SUMS of each
# ../shared model folder); a mismatch stops with one error line and leaves no bad file installed.
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
target_root="${1:-$repo/models}"
shared_root="${CROWDSLAM_SHARED:-$repo/../shared}/models"
upstream="https://raw.githubusercontent.com/dog-qiuqiu/Yolo-Fastest/master"

# folder  name  sha256  source: upstream path, "-" = written locally, "?path" = optional download,
# "shared" = only from ../shared (optional model: a warning when absent), "shared?" = optional file of it
manifest=(
  "yolo-fastest-1.1 yolo-fastest-1.1_body.cfg 045b8e276ebe3924474da8c866b7e709159ea067137b5d66bf9dd560411b2c1a ModelZoo/yolo-fastest-1.1_body/yolo-fastest-1.1_body.cfg"
  "yolo-fastest-1.1 yolo-fastest-1.1_body.weights 5bbb6d878f6e2eb3deee39e91dc6f9b39700e99ec83fa94d258670a554949728 ModelZoo/yolo-fastest-1.1_body/yolo-fastest-1.1_body.weights"
  "yolo-fastest-1.1 yolo-fastest-1.1.cfg f6df5775c1e862998cf69046eba9265be3ae84dfe8b2caab7529823f0795bf70 ModelZoo/yolo-fastest-1.1_coco/yolo-fastest-1.1.cfg"
  "yolo-fastest-1.1 yolo-fastest-1.1.weights 1c445c42bbd6df63edea2cc69f99667b5650d663ca11e34b116240740cd42890 ModelZoo/yolo-fastest-1.1_coco/yolo-fastest-1.1.weights"
  "yolo-fastest-1.1 body.names 9e2ec912af5dff2a72300863864fc4da04e81999339d9fac5c7590ba8a3f4e11 -"
  "yolo-fastest-1.1 coco.names 634a1132eb33f8091d60f2c346ababe8b905ae08387037aed883953b7329af84 ?data/coco.names"
  "yolo-fastest-1.1 LICENSE 2021f0b8d6426fbf9a2f0126f1e8a7d3b1d7027c871b9979fa2543b9557000c4 ?LICENSE"
  "yolox-nano yolox_nano.onnx c789161ed43c8269fcd4e67c67eeeb4e80c622da2eb296a20bc6007bd18a0b7d shared"
  "yolox-nano LICENSE 0ec3668d3274bcf29e8a29e9576d5a2cd96fc78d3c5bec4387355a796e5d9088 shared?"
  "bytetrack-nano bytetrack_nano.onnx c16d43c3e067703d9327aee1f14305107c3d6bdc54a65789bdf0b7a0aca10ebf shared"
)

die() { echo "install_models: error: $*" >&2; exit 1; }
sha_of() { sha256sum "$1" | cut -d' ' -f1; }

fetch() {  # url output
  if command -v curl >/dev/null; then curl -fsSL --retry 2 -o "$2" "$1"
  elif command -v wget >/dev/null; then wget -q -O "$2" "$1"
  else return 1; fi
}

mkdir -p "$target_root"
tmp="$(mktemp -d "$target_root/.install.XXXXXX")"
trap 'rm -rf "$tmp"' EXIT
installed=0
declare -A skipped=()  # folders of optional models that are not available
for entry in "${manifest[@]}"; do
  read -r folder name sum source <<<"$entry"
  [[ -n "${skipped[$folder]:-}" ]] && continue
  target="$target_root/$folder"
  shared="$shared_root/$folder"
  dest="$target/$name"
  mkdir -p "$target"
  if [[ -f "$dest" && "$(sha_of "$dest")" == "$sum" ]]; then continue; fi
  optional=0
  if [[ "$source" == \?* ]]; then optional=1; source="${source#\?}"; fi
  if [[ -f "$shared/$name" ]]; then
    cp "$shared/$name" "$tmp/$name" && chmod 644 "$tmp/$name"
    from="$shared/$name"
  elif [[ "$source" == "shared" ]]; then
    echo "install_models: warning: optional model $folder/$name not in $shared (no download source): skipped" >&2
    skipped[$folder]=1
    rmdir "$target" 2>/dev/null || true
    continue
  elif [[ "$source" == "shared?" ]]; then
    continue
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
  [[ "$actual" == "$sum" ]] || die "$folder/$name: SHA-256 mismatch (from $from): expected $sum, got $actual"
  mv -f "$tmp/$name" "$dest"
  installed=$((installed + 1))
done

# Keep a SHA256SUMS beside the files of each folder and verify the whole set the standard way.
folders=()
for entry in "${manifest[@]}"; do
  read -r folder _ <<<"$entry"
  [[ " ${folders[*]} " == *" $folder "* || -n "${skipped[$folder]:-}" ]] || folders+=("$folder")
done
for folder in "${folders[@]}"; do
  (
    cd "$target_root/$folder"
    for entry in "${manifest[@]}"; do
      read -r f name sum _ <<<"$entry"
      if [[ "$f" == "$folder" && -f "$name" ]]; then echo "$sum  $name"; fi
    done >SHA256SUMS
    sha256sum -c --quiet SHA256SUMS
  ) || die "checksum verification failed in $target_root/$folder"
done
echo "install_models: $target_root ready (${folders[*]}; $installed file(s) installed)"
