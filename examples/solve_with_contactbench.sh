#!/bin/sh
# A shell script around an existing command-line solver, run by contactbench's `command` solver
# (docs/INTERFACES.md "The command protocol"). The "existing tool" here is a contactbench binary
# solving with one of its own solvers, standing in for a simulator's or a colleague's solver
# binary: the script turns the tool's output into the protocol's files in {out}.
#
#   usage: solve_with_contactbench.sh TOOL SOLVER SNAPSHOT OUT
#   suite: "argv": ["/bin/sh", "examples/solve_with_contactbench.sh", "build/bin/contactbench", "pgs",
#                   "{snapshot}", "{out}"]
set -eu
if [ "$#" -ne 4 ]; then
    echo "usage: solve_with_contactbench.sh TOOL SOLVER SNAPSHOT OUT" >&2
    exit 2
fi
tool=$1
solver=$2
snapshot=$3
out=$4

# The tool writes x.mtx and lambda.mtx (both read by the harness as they are) and its own record.
"$tool" solve "$snapshot" --solver "$solver" --save-solution "$out" --json "$out/tool_run.json" >"$out/tool_log.txt"

# Its own status and iteration count, as the protocol's result.json (its judgement is redone by
# the harness on the original QP anyway).
status=$(sed -n 's/^ *"solver_status": *"\([a-z_]*\)".*/\1/p' "$out/tool_run.json")
iterations=$(sed -n 's/^ *"iterations": *\([0-9]*\).*/\1/p' "$out/tool_run.json" | head -n 1)
printf '{"status": "%s", "iterations": %s, "message": "%s via %s"}\n' "$status" "${iterations:-0}" "$solver" \
    "$(basename "$tool")" >"$out/result.json"
