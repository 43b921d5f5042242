#!/usr/bin/env bash
# The README's commands run scripts/*.sh directly: each must be executable, start with a bash
# shebang and parse (bash -n). scripts/lib/ holds sourced files, which need only parse.
# A lost executable bit once made CI fail with "Permission denied" (exit 126).
set -uo pipefail
root="${1:?usage: check_scripts.sh SOURCE_DIR}"
failures=0
for f in "$root"/scripts/*.sh "$root"/.ci/run; do
  [[ -e "$f" ]] || continue
  if [[ ! -x "$f" ]]; then echo "not executable: $f"; failures=$((failures + 1)); fi
  if [[ "$(head -c 19 "$f")" != "#!/usr/bin/env bash" ]]; then echo "no bash shebang: $f"; failures=$((failures + 1)); fi
  if ! bash -n "$f"; then echo "does not parse: $f"; failures=$((failures + 1)); fi
done
for f in "$root"/scripts/lib/*.sh; do
  [[ -e "$f" ]] || continue
  if ! bash -n "$f"; then echo "does not parse: $f"; failures=$((failures + 1)); fi
done
echo "checked scripts under $root: $failures problem(s)"
exit $((failures > 0))
