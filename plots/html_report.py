#!/usr/bin/python3
"""One HTML page per results folder (issue 46): OUT/report/index.html, readable offline from disk.

The page holds the run's provenance; a table of every run (snapshot, solver, status, e, time with
setup, iterations, peak memory) that sorts and filters; per snapshot the convergence histories (e
against time and against iterations, the tolerance drawn); the performance profile and the shifted
geometric mean per solver (plots/profiles.py's numbers); for a reproduction the claims table with
intervals and links to each figure; every PNG figure of the folder, linked.

OUT may be a results folder (`contactbench run`, `stress`, a ladder's suite) or a reproduction
(`plots.reproduce`: runs/<suite>/ results folders and claims.json). The charts are drawn in the
browser by Debian's d3 (package libjs-d3, /usr/share/javascript/d3/d3.min.js), copied beside the
page with plots/html_report_assets/: no network is needed. Every string taken from a record is
HTML-escaped (server side) or set as text (browser side), and the embedded JSON cannot close its
<script> element.

usage: html_report.py OUT        (exit 2 on a folder that is not a results folder or reproduction)
"""
from __future__ import annotations

import argparse
import html
import json
import math
import os
import shutil
import sys
import tempfile
from typing import Dict, List, Optional

import numpy as np

from plots import figutil
from plots.loader import UNMEASURED_STATUSES, Results, history_time, load_results

#: where Debian's libjs-d3 puts d3 (copied beside the page)
D3_PATHS = ("/usr/share/javascript/d3/d3.min.js", "/usr/share/javascript/d3/d3.js")
ASSETS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "html_report_assets")
#: points kept per history (the page stays small; the last point is always kept)
MAX_POINTS = 300
#: snapshots drawn per results set (the table still lists every run)
MAX_SNAPSHOTS = 24
#: figures linked from the page at most
MAX_FIGURES = 300


class ReportError(Exception):
    """The folder cannot be reported on (exit status 2); the message names the folder."""


def _num(value) -> Optional[float]:
    """A finite float, or None (JSON null) for NaN, inf and non-numbers."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def _str(value) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return ""
    return str(value)


def safe_json(data) -> str:
    """JSON for a <script type="application/json"> element: '<', '>' and '&' as \\u escapes, so
    that no record string can end the element or open a comment (U+2028/9 escaped too)."""
    text = json.dumps(data, allow_nan=False, separators=(",", ":"))
    return (text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")
            .replace("\u2028", "\\u2028").replace("\u2029", "\\u2029"))


def results_sets(folder: str) -> Dict[str, str]:
    """name -> results folder: the folder itself, or a reproduction's runs/<suite>/ folders."""
    if os.path.isfile(os.path.join(folder, "summary.csv")) or (
            os.path.isdir(os.path.join(folder, "runs")) and
            any(n.endswith(".json") for n in os.listdir(os.path.join(folder, "runs")))):
        return {os.path.basename(os.path.normpath(folder)) or folder: folder}
    runs = os.path.join(folder, "runs")
    found = {}
    if os.path.isdir(runs):
        for name in sorted(os.listdir(runs)):
            sub = os.path.join(runs, name)
            if os.path.isfile(os.path.join(sub, "summary.csv")) or os.path.isdir(os.path.join(sub, "runs")):
                found[name] = sub
    return found


def _peak_memory(record: dict) -> Optional[float]:
    mem = (record or {}).get("memory") or {}
    return _num(mem.get("peak_rss_mb")) if isinstance(mem, dict) else None


def _thin(n: int) -> np.ndarray:
    """Indices of at most MAX_POINTS points of n, the first and last included."""
    if n <= MAX_POINTS:
        return np.arange(n)
    return np.unique(np.concatenate([np.linspace(0, n - 1, MAX_POINTS).round().astype(int), [n - 1]]))


def run_rows(name: str, res: Results) -> List[dict]:
    """One table row per run of a results set."""
    rows = []
    for _, run in res.runs.iterrows():
        key = (run.get("snapshot"), run.get("label"))
        rows.append({"set": name, "snapshot": _str(run.get("snapshot")), "label": _str(run.get("label")),
                     "solver": _str(run.get("solver")), "status": _str(run.get("status")),
                     "e": _num(run.get("accuracy")), "tol": _num(run.get("accuracy_tol", run.get("tol"))),
                     "time_s": _num(run.get("time_s")), "setup_s": _num(run.get("setup_s")),
                     "iterations": _num(run.get("iterations")),
                     "peak_mb": _peak_memory(res.records.get(key, {})) if key in res.records
                     else _num(run.get("peak_rss_mb")),
                     "n": _num(run.get("n")), "m": _num(run.get("m")),
                     "message": _str(run.get("message"))[:500]})
    return rows


def histories(name: str, res: Results, styles: Dict[str, dict]) -> List[dict]:
    """Per snapshot: every run's e against time (setup included) and iterations, thinned."""
    out = []
    runs = res.runs
    tol = _num(np.nanmax(runs["accuracy_tol"])) if "accuracy_tol" in runs and runs["accuracy_tol"].notna().any() \
        else None
    for snap in res.snapshots()[:MAX_SNAPSHOTS]:
        series = []
        n = m = None
        for _, run in runs[runs["snapshot"] == snap].iterrows():
            n, m = _num(run.get("n")), _num(run.get("m"))
            if run.get("status") in UNMEASURED_STATUSES:
                continue
            label = _str(run.get("label"))
            h = res.history(snap, label)
            if h.empty or "accuracy" not in h:
                t, it, e = [run.get("time_s")], [run.get("iterations")], [run.get("accuracy")]
            else:
                idx = _thin(len(h))
                t = history_time(h, run, True)[idx]
                it = h["iteration"].to_numpy(dtype=float)[idx] if "iteration" in h else idx.astype(float)
                e = h["accuracy"].to_numpy(dtype=float)[idx]
            pts = [[_num(a), _num(b), _num(c) if _num(c) is not None and c > 0 else None] for a, b, c in zip(t, it, e)]
            style = styles.get(label, {})
            series.append({"label": label, "status": _str(run.get("status")), "colour": style.get("color", "#000"),
                           "dash": style.get("linestyle", "-") != "-", "points": pts})
        out.append({"set": name, "snapshot": _str(snap), "n": n, "m": m, "tol": tol, "series": series})
    return out


def profile_numbers(name: str, res: Results, styles: Dict[str, dict]) -> Optional[dict]:
    """plots/profiles.py's numbers at the tightest judged tier: each label's performance ratios
    (time to the tier, setup included), its denominator, and the shifted geometric means."""
    from plots import profiles
    try:
        numbers = profiles.compute(res)
    except (ValueError, KeyError) as err:
        return {"set": name, "error": f"{type(err).__name__}: {err}"}
    tiers = numbers["tier_values"]
    if not tiers or numbers["tiers"].empty:
        return None
    tier = tiers[-1]
    tt = numbers["tiers"]
    cost = profiles.cost_matrix(tt, tier)
    excluded = profiles.excluded_matrix(tt, tier)
    ratios = profiles.performance_ratios(cost)
    labels = []
    for label in numbers["labels"]:
        if label not in ratios:
            continue
        judged = int(len(ratios) - (excluded[label].fillna(False).astype(bool).sum() if label in excluded else 0))
        finite = sorted(float(r) for r in ratios[label] if math.isfinite(r))
        labels.append({"label": str(label), "colour": styles.get(label, {}).get("color", "#000"),
                       "ratios": finite, "judged": max(judged, 1)})
    sgm_rows = []
    for label in numbers["labels"]:
        row = {"label": str(label)}
        for t in tiers:
            row[f"{t:g}"] = {"success": _num(numbers["success"].loc[label, t]) if label in numbers["success"].index
                             else None,
                             "sgm": _num(numbers["sgm"].loc[label, t]) if label in numbers["sgm"].index else None,
                             "ratio": _num(numbers["sgm_ratio"].loc[label, t]) if label in numbers["sgm_ratio"].index
                             else None}
        sgm_rows.append(row)
    return {"set": name, "tier": tier, "tiers": [f"{t:g}" for t in tiers], "problems": int(len(ratios)),
            "shift_s": _num(numbers["shift_s"]), "penalty_s": _num(numbers["penalty_s"]), "labels": labels,
            "sgm": sgm_rows}


def figures(folder: str) -> List[str]:
    """Every PNG under the folder but the report's own, as paths relative to the folder."""
    found = []
    for top, dirs, files in os.walk(folder):
        dirs[:] = sorted(d for d in dirs if d not in ("report", "snapshots", "frames") and not d.startswith("."))
        for f in sorted(files):
            if f.endswith(".png"):
                found.append(os.path.relpath(os.path.join(top, f), folder))
    return found[:MAX_FIGURES]


def simulations(folder: str) -> List[str]:
    """Simulation folders (simulation.json beside a picture strip) under the folder, relative."""
    found = []
    for top, dirs, files in os.walk(folder):
        dirs[:] = sorted(d for d in dirs if d not in ("report", "snapshots", "frames", "runs") and not d.startswith("."))
        if "simulation.json" in files and any(f.endswith("_strip.png") for f in files):
            found.append(os.path.relpath(top, folder))
    return found[:50]


def write_strips(folder: str, sims: List[str], dest: str) -> List[tuple]:
    """Each simulation's strip with frame numbers, times and its largest penetration
    (plots/strip.py), written into the report folder: [(page-relative path, simulation folder)]."""
    from plots import strip
    out = []
    for k, rel in enumerate(sims):
        name = f"strip_{k}.png"
        try:
            if strip.annotate(os.path.join(folder, rel), os.path.join(dest, name)):
                out.append((name, rel))
        except (OSError, ValueError, KeyError) as err:  # a strip that cannot be read is only noted
            print(f"html_report: {os.path.join(folder, rel)}: strip not annotated: {err}", file=sys.stderr)
    return out


def claims(folder: str) -> List[dict]:
    path = os.path.join(folder, "claims.json")
    if not os.path.isfile(path):
        return []
    with open(path, encoding="utf-8") as f:
        try:
            data = json.load(f)
        except json.JSONDecodeError as err:
            raise ReportError(f"{path}: not valid JSON: {err}") from err
    return data if isinstance(data, list) else []


def collect(folder: str) -> dict:
    """Everything the page shows, as plain data (strings unescaped: the renderers escape)."""
    sets = results_sets(folder)
    if not sets:
        raise ReportError(f"{folder}: not a results folder (no runs/ and no summary.csv) nor a reproduction "
                          "(no runs/<suite>/ results folders)")
    model = {"title": os.path.basename(os.path.abspath(folder)), "rows": [], "histories": [], "profiles": [],
             "errors": [], "provenance": {}, "sets": list(sets)}
    loaded = {}
    for name, path in sets.items():
        try:
            loaded[name] = load_results(path)
        except (OSError, ValueError) as err:  # one bad suite folder must not hide the others
            if len(sets) == 1:
                raise ReportError(str(err)) from err
            model["errors"].append(f"{name}: {err}")
    labels = {}
    for res in loaded.values():
        if not res.runs.empty:
            labels.update(figutil.label_solvers(res.runs))
            for lab in res.labels():
                labels.setdefault(str(lab), str(lab))
    styles = figutil.assign_styles(list(labels), labels)
    for name, res in loaded.items():
        if not model["provenance"] and res.provenance:
            model["provenance"] = res.provenance
        if res.runs.empty:
            model["errors"].append(f"{name}: no runs")
            continue
        model["rows"] += run_rows(name, res)
        model["histories"] += histories(name, res, styles)
        prof = profile_numbers(name, res, styles)
        if prof:
            model["profiles"].append(prof)
        if len(res.snapshots()) > MAX_SNAPSHOTS:
            model["errors"].append(f"{name}: histories of the first {MAX_SNAPSHOTS} of {len(res.snapshots())} "
                                   "snapshots drawn (the table lists every run)")
    model["claims"] = claims(folder)
    model["figures"] = figures(folder)
    model["simulations"] = simulations(folder)
    model["strips"] = []
    return model


def _claim_rows(model: dict) -> str:
    """The claims table as escaped HTML, each row linking the figures its source produced."""
    if not model["claims"]:
        return ""
    out = ['<section id="claims"><h2>Claims</h2><table class="claims"><thead><tr><th>claim</th><th>judged on</th>'
           '<th>paper</th><th>authors\' data</th><th>ours (interval)</th><th>verdict</th><th>figures</th></tr></thead>'
           '<tbody>']
    esc = html.escape
    try:  # the figure each expected claim is measured by (plots/report.py)
        from plots.report import EXPECTED_CLAIMS
        figure_of = {key: fig for key, fig, _ in EXPECTED_CLAIMS}
    except ImportError:
        figure_of = {}
    for c in model["claims"]:
        if not isinstance(c, dict):
            continue
        source = _str(c.get("source"))
        key = _str(c.get("key"))
        stem = figure_of.get(key, key.split("-")[0]).replace("_claims", "")
        interval = c.get("interval")
        ours = _str(c.get("ours"))
        if isinstance(interval, list) and len(interval) == 2 and all(_num(v) is not None for v in interval):
            cov = _num(c.get("coverage"))
            ours += f" — interval [{float(interval[0]):.3g}, {float(interval[1]):.3g}]" + \
                (f" ({100 * cov:.1f}%)" if cov else "")
        links = [f for f in model["figures"] if stem and os.path.basename(f).startswith(stem)]
        link_html = " ".join(f'<a href="../{esc(f, quote=True)}">{esc(os.path.basename(f))}</a>' for f in links) \
            or "—"
        reason = _str(c.get("reason"))
        out.append(f'<tr><td>{esc(_str(c.get("claim")))} ({esc(source)})</td><td>{esc(_str(c.get("judged_on")))}</td>'
                   f'<td>{esc(_str(c.get("paper")))}</td><td>{esc(_str(c.get("authors")))}</td><td>{esc(ours)}</td>'
                   f'<td class="verdict">{esc(_str(c.get("verdict")))}'
                   + (f'<div class="reason">{esc(reason)}</div>' if reason else "") +
                   f'</td><td>{link_html}</td></tr>')
    out.append("</tbody></table></section>")
    return "".join(out)


def _provenance(model: dict) -> str:
    prov = model["provenance"] or {}
    keys = ("git_commit", "git_dirty", "build_type", "compiler", "cpu", "cores", "date", "hostname", "blas",
            "eigen", "suitesparse")
    items = [(k, prov[k]) for k in keys if k in prov] + \
        [(k, v) for k, v in prov.items() if k not in keys and isinstance(v, (str, int, float, bool))]
    if not items:
        return "<p>No provenance.json in this folder.</p>"
    return '<table class="prov">' + "".join(
        f"<tr><th>{html.escape(str(k))}</th><td>{html.escape(_str(v))}</td></tr>" for k, v in items) + "</table>"


def _which_solver(model: dict) -> str:
    """A ladder's which-solver map (plots/which_solver.py), shown whole above the gallery."""
    maps = [f for f in model["figures"] if os.path.basename(f) == "which_solver.png"]
    esc = html.escape
    return "".join(f'<section id="which-solver"><h2>Which solver when</h2><a href="../{esc(f, quote=True)}">'
                   f'<img class="map" src="../{esc(f, quote=True)}" alt="which solver when"></a></section>'
                   for f in maps[:1])


def render(model: dict) -> str:
    """The page: static sections rendered here (escaped), the interactive ones drawn by report.js
    from the embedded JSON."""
    esc = html.escape
    figs = "".join(f'<figure><a href="../{esc(f, quote=True)}"><img src="../{esc(f, quote=True)}" alt="{esc(f)}" '
                   f'loading="lazy"></a><figcaption>{esc(f)}</figcaption></figure>' for f in model["figures"])
    notes = "".join(f"<li>{esc(e)}</li>" for e in model["errors"])
    strips = "".join(f'<figure class="strip"><img src="{esc(name, quote=True)}" alt="{esc(rel)}">'
                     f'<figcaption>{esc(rel)}</figcaption></figure>' for name, rel in model.get("strips", []))
    data = {k: model[k] for k in ("rows", "histories", "profiles", "sets")}
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta http-equiv="Content-Security-Policy" content="default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data:">
<title>contactbench report: {esc(model['title'])}</title>
<link rel="stylesheet" href="report.css">
</head><body>
<h1>contactbench report: {esc(model['title'])}</h1>
<nav><a href="#runs">runs</a> · <a href="#histories">convergence</a> · <a href="#profiles">profiles</a>
{'· <a href="#claims">claims</a>' if model['claims'] else ''} · <a href="#figures">figures</a> · <a href="#provenance">provenance</a></nav>
{f'<ul class="notes">{notes}</ul>' if notes else ''}
<section id="provenance"><h2>Provenance</h2>{_provenance(model)}</section>
{_claim_rows(model)}
<section id="runs"><h2>Runs</h2>
<p>Every run of the folder: click a column header to sort, type to filter (any column). e: the accuracy error
on the original QP (docs/accuracy.md); time: setup + solve; peak memory: resident set of the run.</p>
<p><label>filter <input id="filter" type="search" placeholder="snapshot, solver, status..."></label>
<span id="count"></span></p>
<table id="runs-table"><thead></thead><tbody></tbody></table></section>
<section id="histories"><h2>Convergence histories</h2>
<p>e on the original QP against time (setup included) and against iterations, one line per label; the dashed
line is the tolerance; an x marks the final point of a run whose status is not <code>converged</code>.
Click a legend entry to hide or show a line; hover a line for its label.</p><div id="history-plots"></div></section>
<section id="profiles"><h2>Performance profiles and shifted geometric means</h2>
<p>Dolan-Moré profile of the time to the tightest tier (setup included; rules: docs/work.md "Profiles"):
the share of the problems a solver reaches the tier on within tau times the best solver's time. Shifted
geometric mean of the time to each tier (a run that never reaches it counts at the penalty time).</p>
<div id="profile-plots"></div></section>
{_which_solver(model)}
{f'<section id="strips"><h2>Scenes simulated</h2>{strips}</section>' if strips else ''}
<section id="figures"><h2>Figures</h2><div class="gallery">{figs or '<p>No figures in this folder.</p>'}</div></section>
<script type="application/json" id="report-data">{safe_json(data)}</script>
<script src="d3.min.js"></script>
<script src="report.js"></script>
</body></html>
"""


def find_d3() -> str:
    for path in D3_PATHS:
        if os.path.isfile(path):
            return path
    raise ReportError("d3 not found (" + ", ".join(D3_PATHS) + "): install Debian's libjs-d3 "
                      "(`make deps`, or as root: apt-get install -y libjs-d3)")


def write_report(folder: str) -> str:
    """Writes FOLDER/report/ whole (a temporary sibling renamed into place); returns index.html's path."""
    if not os.path.isdir(folder):
        raise ReportError(f"{folder}: not a folder")
    d3 = find_d3()
    model = collect(folder)
    dest = os.path.join(folder, "report")
    if os.path.lexists(dest) and (os.path.islink(dest) or not os.path.isdir(dest)):
        raise ReportError(f"{dest}: exists and is not a folder; remove it or report another folder")
    tmp = tempfile.mkdtemp(prefix=".report-", dir=folder)
    try:
        model["strips"] = write_strips(folder, model["simulations"], tmp)
        with open(os.path.join(tmp, "index.html"), "w", encoding="utf-8") as f:
            f.write(render(model))
        shutil.copyfile(d3, os.path.join(tmp, "d3.min.js"))
        for name in ("report.js", "report.css"):
            shutil.copyfile(os.path.join(ASSETS, name), os.path.join(tmp, name))
        os.chmod(tmp, 0o755)
        if os.path.isdir(dest):
            old = tempfile.mkdtemp(prefix=".report-old-", dir=folder)
            os.rename(dest, os.path.join(old, "report"))
            os.rename(tmp, dest)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.rename(tmp, dest)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return os.path.join(dest, "index.html")


def report_at_end(folder: str, say=print) -> Optional[str]:
    """The end of a command (`plots.reproduce`, tools/ladder.sh): writes the page and says where, or
    why not and how to write it later; never raises."""
    try:
        path = write_report(folder)
    except (ReportError, OSError, ValueError, ImportError) as err:
        say(f"report: not written: {err}; then: /usr/bin/python3 -m plots.html_report {folder}")
        return None
    say(f"report: {os.path.abspath(path)} (open it in a browser; it needs no network)")
    return path


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", help="a results folder or a reproduction folder")
    args = parser.parse_args(argv)
    try:
        path = write_report(args.folder)
    except (ReportError, OSError) as err:
        print(f"html_report: error: {err}", file=sys.stderr)
        return 2
    print(f"report: {os.path.abspath(path)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
