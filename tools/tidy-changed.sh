#!/usr/bin/env bash
# clang-tidy (checks in .clang-tidy) on the C++ sources changed against a base revision.
# usage: tools/tidy-changed.sh BUILD_DIR [BASE]     (`make tidy`; CI runs it on its change)
# Headers are checked through the sources that include them (HeaderFilterRegex in .clang-tidy).
set -euo pipefail
build=${1:-build}
base=${2:-main}
cd "$(dirname "$0")/.."
tidy=$(command -v clang-tidy || ls /usr/bin/clang-tidy-* 2>/dev/null | sort -V | tail -1 || true)
if [ -z "$tidy" ]; then
  echo "tidy: clang-tidy is not installed (apt-get install clang-tidy)" >&2
  exit 2
fi
# The build compiles most sources inside unity batches (CB_UNITY_BUILD), so its compile database names
# the batch files, not the sources: clang-tidy reads a per-file database configured (not built) beside
# it, without the GCC-only heap option that clang does not know.
db="$build-tidy"
cmake -S . -B "$db" -DCMAKE_BUILD_TYPE=Release -DCB_UNITY_BUILD=OFF -DCB_GCC_LARGE_HEAP=OFF \
      -DCMAKE_EXPORT_COMPILE_COMMANDS=ON >/dev/null
mapfile -t files < <( { git diff --name-only --diff-filter=ACMR "$base" -- '*.cpp'; \
                        git ls-files --others --exclude-standard -- '*.cpp'; } | sort -u)
# A changed header is checked through one source beside it that includes it.
mapfile -t headers < <(git diff --name-only --diff-filter=ACMR "$base" -- '*.hpp')
for h in "${headers[@]}"; do
  src=${h%.hpp}.cpp
  [ -f "$src" ] && files+=("$src")
done
mapfile -t files < <(printf '%s\n' "${files[@]}" | sort -u | grep -v -e '^tests/fuzz/' -e '^$' || true)
# A source this configuration does not compile (an optional peer whose package is absent or
# switched off) has no compile command: clang-tidy could not find its headers. Say so and skip it.
built=()
for f in "${files[@]}"; do
  if grep -q "\"file\": \"$(pwd)/$f\"" "$db/compile_commands.json" 2>/dev/null; then
    built+=("$f")
  else
    echo "tidy: $f is not compiled in this configuration ($db): skipped"
  fi
done
files=("${built[@]+"${built[@]}"}")
if [ ${#files[@]} -eq 0 ]; then
  echo "tidy: no compiled C++ source changed against $base"
  exit 0
fi
# A tree-wide change (the formatter, a rename) would take about 30 s per file: say so and skip.
max=${TIDY_MAX_FILES:-25}
if [ "$max" -gt 0 ] && [ ${#files[@]} -gt "$max" ]; then
  echo "tidy: ${#files[@]} files changed against $base (> TIDY_MAX_FILES=$max): skipped; run with TIDY_MAX_FILES=0 to check them all"
  exit 0
fi
echo "tidy: $tidy on ${#files[@]} file(s) changed against $base"
"$tidy" -p "$db" --quiet "${files[@]}"
