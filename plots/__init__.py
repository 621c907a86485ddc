"""contactbench's Python side: read results with pandas, draw figures, reproduce the paper.

Run the scripts as modules from the repository root (no path set-up needed):

    /usr/bin/python3 -m plots.convergence results/demo
    /usr/bin/python3 -m plots.profiles results/demo
    /usr/bin/python3 -m plots.reproduce --contactbench build/bin/contactbench --quick
    /usr/bin/python3 -m plots.paper_data                      # `make paper-data`

The pandas entry point is :mod:`plots.loader`::

    from plots.loader import load_results, load_simulation
    res = load_results("results/demo")
    res.summary                          # summary.csv, one row per run (units: docs/INTERFACES.md)
    res.runs                             # every run JSON flattened to one row (settings, counters ...)
    res.history("plane-s1", "mprgp")     # one run's per-iteration history
    res.histories                        # every history in long form (snapshot, label, columns)
    sim = load_simulation("results/demo/sim")   # {"steps", "frames", "snapshots"} DataFrames

Modules: loader (results, snapshot headers and simulation folders -> DataFrames), qpsnap (whole
.qpsnap files with numpy), figutil, claims, paper_context, the figure scripts fig6 ... fig11 and
table1, profiles, convergence, stability, report, reproduce, paper_data (with safe_extract and
atomic_folder: untrusted sources, all-or-nothing output folders).
"""
