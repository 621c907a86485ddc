"""Which solver when: time to e <= tol on the original QP (setup included) and peak memory of every
solver along a ladder of snapshots, with the growth exponent of each solver's time.

    /usr/bin/python3 -m plots.which_solver RESULTS_DIR [--axis n|m] [--out DIR]

RESULTS_DIR is a folder written by `contactbench run` on a ladder suite (suites/ladder_*.json).
`--axis n` (the resolution ladder) fits time ~ n^p, `--axis m` (the contact-density ladder)
time ~ m^p, by least squares on log-log over the solver's converged runs (two or more), and prints
the exponents. A run that did not reach e <= tol on the original QP is not a time: it is shown at
the cap with its status (time_limit, solved_relaxation for decoupled mprgp, ...), never dropped; a
solver that refused the QP at its row cap (pgs, the dense-dual peers: not_applicable, "exceeds
max_rows") is marked as such in the table and the figure. Writes DIR/which_solver.{png,md} (DIR
defaults to RESULTS_DIR/figures).
"""
import argparse
import math
import os
import re
import sys

import numpy as np

from plots import figutil, loader

CONVERGED = "converged"
STEM = "which_solver"  # the figure's and the table's file name
ROW_CAP = re.compile(r"exceeds max_rows = (\d+)")  # pgs's and the dense-dual peers' refusal (not_applicable)


def ladder_table(results) -> list:
    """One row per (snapshot, label): n, m, status, time to tol (None when not reached), peak MiB."""
    rows = []
    for (snapshot, label), record in sorted(results.records.items()):
        snap = record.get("snapshot") or {}
        status = record.get("status", "")
        total = (record.get("time") or {}).get("total_s")
        memory = (record.get("memory") or {}).get("peak_rss_mb")
        cap = (record.get("settings") or {}).get("time_limit_s")
        row_cap = ROW_CAP.search(record.get("message") or "") if status == "not_applicable" else None
        prov = record.get("provenance") or {}
        load = prov.get("load_average") or [None]
        rows.append({"snapshot": snapshot, "label": label, "solver": record.get("solver", label),
                     "cpu": prov.get("cpu"), "cores": prov.get("cores"), "load": load[0],
                     "n": snap.get("n"), "m": snap.get("m"), "status": status,
                     "time_s": total if status == CONVERGED else None, "elapsed_s": total,
                     "peak_rss_mb": memory, "cap_s": cap,
                     "row_cap": int(row_cap.group(1)) if row_cap else None})
    return rows


def growth_exponent(xs, ys):
    """p of y ~ c x^p by least squares on logs; None with fewer than two distinct positive points."""
    pts = [(math.log(x), math.log(y)) for x, y in zip(xs, ys) if x and y and x > 0 and y > 0]
    if len({p[0] for p in pts}) < 2:
        return None
    lx, ly = np.array([p[0] for p in pts]), np.array([p[1] for p in pts])
    return float(np.polyfit(lx, ly, 1)[0])


def exponents(rows, axis: str) -> dict:
    by_label = {}
    for r in rows:
        by_label.setdefault(r["label"], []).append(r)
    out = {}
    for label, rs in by_label.items():
        done = [r for r in rs if r["time_s"] is not None]
        out[label] = {"exponent": growth_exponent([r[axis] for r in done], [r["time_s"] for r in done]),
                      "points": len(done), "runs": len(rs)}
    return out


def cell(r) -> str:
    if r["row_cap"] is not None:  # refused before any work: its time and memory say nothing
        return "row cap (m > %d)" % r["row_cap"]
    mem = "" if r["peak_rss_mb"] is None else " / %s MiB" % figutil.fmt(r["peak_rss_mb"])
    if r["time_s"] is not None:
        return "%s s%s" % (figutil.fmt(r["time_s"]), mem)
    elapsed = "" if r["elapsed_s"] is None else " after %s s" % figutil.fmt(r["elapsed_s"])
    return "%s%s%s" % (r["status"] or "missing", elapsed, mem)


def machine_line(rows) -> str:
    """The machine and the 1-minute load average at the runs' starts: timings mean little without them."""
    cpus = sorted({"%s, %s cores" % (r["cpu"], r["cores"]) for r in rows if r["cpu"]})
    loads = [r["load"] for r in rows if isinstance(r["load"], (int, float))]
    machine = "; ".join(cpus) if cpus else "not recorded"
    load = "%.1f to %.1f" % (min(loads), max(loads)) if loads else "not recorded"
    return "Machine: %s; load average (1 min) when the runs started: %s." % (machine, load)


def markdown(rows, fits, axis: str, source: str) -> str:
    # Rungs in the ladder's order: by its variable first (the density ladder's n varies a little).
    key = (lambda t: (t[1], t[0], t[2])) if axis == "m" else None
    snapshots = sorted({(r["n"] or 0, r["m"] or 0, r["snapshot"]) for r in rows}, key=key)
    labels = sorted({r["label"] for r in rows})
    at = {(r["snapshot"], r["label"]): r for r in rows}
    lines = ["# Which solver when: %s" % source, "",
             "Time to e <= tol on the original QP, setup included, and peak resident memory (MiB, the",
             "run's process plus its largest child). A cell without a time did not reach tol: its status",
             "and the time it ran are shown (time_limit: the suite's cap; row cap: the solver refuses a QP",
             "with more rows than its max_rows; solved_relaxation: decoupled mprgp solved a relaxation,",
             "not the QP in the file).", "", machine_line(rows), "",
             "| snapshot | n | m | " + " | ".join(labels) + " |",
             "|---|---|---|" + "---|" * len(labels)]
    for n, m, snap in snapshots:
        lines.append("| %s | %d | %d | " % (snap, n, m)
                     + " | ".join(cell(at[(snap, lb)]) if (snap, lb) in at else "-" for lb in labels) + " |")
    lines += ["", "Growth exponent p of time ~ %s^p (least squares on log-log over the converged runs):" % axis,
              "", "| solver | p | converged runs |", "|---|---|---|"]
    for label in labels:
        f = fits[label]
        p = "-" if f["exponent"] is None else "%.2f" % f["exponent"]
        lines.append("| %s | %s | %d of %d |" % (label, p, f["points"], f["runs"]))
    return "\n".join(lines) + "\n"


def figure(rows, fits, axis: str, folder: str, title: str):
    import matplotlib.pyplot as plt
    fig, (ax_t, ax_m) = plt.subplots(1, 2, figsize=(7.0, 3.0))  # a page column (plots/figure_checks.py)
    caps = [r["cap_s"] for r in rows if r["cap_s"]]
    cap = max(caps) if caps else None
    for label in sorted({r["label"] for r in rows}):
        rs = sorted((r for r in rows if r["label"] == label), key=lambda r: r[axis] or 0)
        style = figutil.solver_style(label, rs[0]["solver"])
        p = fits[label]["exponent"]
        name = label + ("" if p is None else " (p = %.2f)" % p)
        done = [r for r in rs if r["time_s"] is not None]
        if done:
            ax_t.plot([r[axis] for r in done], [r["time_s"] for r in done], label=name, **style)
        failed = [r for r in rs if r["time_s"] is None and r["row_cap"] is None and cap]
        if failed:
            ax_t.scatter([r[axis] for r in failed], [cap] * len(failed), marker="x", s=40, color=style.get("color"),
                         label=None if done else name)
        capped = [r for r in rs if r["row_cap"] is not None and cap]
        if capped:
            ax_t.scatter([r[axis] for r in capped], [cap] * len(capped), marker="s", s=40, facecolors="none",
                         edgecolors=style.get("color"), label=None if done or failed else name)
        mem = [r for r in rs if r["peak_rss_mb"] and r["row_cap"] is None]
        if mem:
            ax_m.plot([r[axis] for r in mem], [r["peak_rss_mb"] for r in mem], **style)
    if cap:
        ax_t.axhline(cap, color="0.6", lw=0.8, ls=":", label=f"cap {cap:g} s")
    unit = "unknowns n (count)" if axis == "n" else "rows m of J (count)"
    for ax in (ax_t, ax_m):
        ax.set_xlabel(unit)
        ax.grid(True, which="both", alpha=0.3)
        if ax.lines or ax.collections:  # log scales need a point; an empty panel says why instead
            ax.set_xscale("log")
            ax.set_yscale("log")
        else:
            ax.text(0.5, 0.5, "no data (records without `memory`?)", ha="center", va="center",
                    transform=ax.transAxes, fontsize=9)
    ax_t.set_ylabel("time to e <= tol, with setup [s]")
    ax_m.set_ylabel("peak resident memory [MiB]")
    ax_t.set_title("time (at the cap: x did not reach tol,\nsquare refused at its row cap)", fontsize=8)
    ax_m.set_title("peak memory, every run that started", fontsize=8)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    from matplotlib.lines import Line2D
    not_reached = Line2D([], [], color="black", marker="x", ls="none", label="did not reach tol (at the cap)")
    row_capped = Line2D([], [], color="black", marker="s", markerfacecolor="none", ls="none",
                        label="refused: more rows than its max_rows")
    figutil.legend_outside(fig, [ax_t], notes=[not_reached, row_capped])
    return figutil.save_figure_outside(fig, folder, STEM)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("results", help="a results folder of a ladder suite")
    ap.add_argument("--axis", choices=["n", "m"], default="n", help="the ladder's variable (default n)")
    ap.add_argument("--out", help="output folder (default RESULTS/figures)")
    args = ap.parse_args(argv)
    try:
        results = loader.load_results(args.results)
    except (FileNotFoundError, ValueError) as err:
        print("which_solver: %s" % err, file=sys.stderr)
        return 2
    rows = ladder_table(results)
    if not rows:
        print("which_solver: %s: no run records (runs/*.json)" % args.results, file=sys.stderr)
        return 2
    fits = exponents(rows, args.axis)
    out = args.out or os.path.join(args.results, "figures")
    os.makedirs(out, exist_ok=True)
    source = os.path.basename(os.path.normpath(args.results))
    paths = figure(rows, fits, args.axis, out, "Which solver when: " + source)  # STEM.png, STEM.pdf
    md = os.path.join(out, STEM + ".md")
    with open(md + ".tmp", "w", encoding="utf-8") as f:
        f.write(markdown(rows, fits, args.axis, source))
    os.replace(md + ".tmp", md)
    for label in sorted(fits):
        f = fits[label]
        p = "-" if f["exponent"] is None else "%.2f" % f["exponent"]
        print("which_solver: %s: time ~ %s^p, p = %s (%d of %d runs converged)" % (label, args.axis, p, f["points"],
                                                                                 f["runs"]))
    print("which_solver: wrote %s and %s" % (md, ", ".join(paths)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
