#!/usr/bin/env bash
# The checks that need no build: pyflakes on every Python file of the repository (unused imports,
# undefined names) and clang-format (.clang-format) on the C++ lines changed against a base
# revision (git clang-format formats only changed lines, so an old file's drift is not blamed on
# the change that touches it).
# usage: tools/lint.sh [BASE]      (`make lint`, default BASE main; CI runs it on its change)
# Exit status: 0 clean, 1 findings, 2 a tool is missing.
set -uo pipefail
base=${1:-main}
cd "$(dirname "$0")/.."
status=0

if ! /usr/bin/python3 -m pyflakes --version >/dev/null 2>&1; then
    echo "lint: pyflakes is not installed (apt-get install python3-pyflakes; make deps)" >&2
    exit 2
fi
mapfile -t py < <(git ls-files '*.py')
if ! /usr/bin/python3 -m pyflakes "${py[@]}"; then
    echo "lint: pyflakes found the problems above"
    status=1
fi

if ! command -v git-clang-format >/dev/null 2>&1; then
    echo "lint: git-clang-format is not installed (apt-get install clang-format)" >&2
    exit 2
fi
if git rev-parse -q --verify "$base^{commit}" >/dev/null; then
    diff=$(git clang-format --diff --extensions cpp,hpp,h "$base" -- . 2>&1)
    case "$diff" in
    "" | "no modified files to format" | "clang-format did not modify any files") ;;
    *)
        echo "$diff"
        echo "lint: C++ lines changed since $base are not formatted (.clang-format); run: git clang-format $base"
        status=1
        ;;
    esac
else
    echo "lint: no revision $base: C++ format check skipped"
fi
[ $status = 0 ] && echo "lint: clean (pyflakes on ${#py[@]} Python files; clang-format on C++ changed since $base)"
exit $status
