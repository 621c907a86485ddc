"""Figures a referee accepts (issue 46): plots/figure_checks.py's rules hold on the figures of the
demo's scripts (convergence, profiles, the stiff-family figure) drawn from fixture folders with 16
labels and on every figure of the quick reproduction (fig6, fig8, fig9, fig10, fig11), the checks
catch each broken rule on a figure built to break it, and every one of 16 labels gets a distinct,
deterministic (colour, marker) pair.

Run from tests/python: /usr/bin/python3 -m unittest test_figures
"""
import io
import itertools
import math
import os
import shutil
import subprocess
import sys
import tempfile
import unittest
from contextlib import redirect_stderr, redirect_stdout

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, ROOT)
sys.path.insert(0, os.path.join(HERE, "fixtures"))
os.environ.setdefault("MPLBACKEND", "Agg")

import make_fixture as mf  # noqa: E402
from plots import convergence, figure_checks, figutil, profiles  # noqa: E402
from plots.figutil import plt  # noqa: E402
from plots.loader import load_results  # noqa: E402

#: 13 registered solvers' labels would each have a fixed style; these are a user's own
USER_LABELS = ["my-qp", "ours-v2", "admm", "fista", "pdhg", "osqp-like", "newton", "sor",
               "gauss-seidel", "bb-projected", "lbfgsb", "apgd", "nesterov", "dual-cd", "ipm-x", "a"]


def _lab(hexcolour):
    rgb = [int(hexcolour.lstrip("#")[i:i + 2], 16) / 255 for i in (0, 2, 4)]
    lin = [c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4 for c in rgb]
    x = (0.4124 * lin[0] + 0.3576 * lin[1] + 0.1805 * lin[2]) / 0.95047
    y = 0.2126 * lin[0] + 0.7152 * lin[1] + 0.0722 * lin[2]
    z = (0.0193 * lin[0] + 0.1192 * lin[1] + 0.9505 * lin[2]) / 1.08883
    f = lambda v: v ** (1 / 3) if v > 0.008856 else 7.787 * v + 16 / 116  # noqa: E731
    return (116 * f(y) - 16, 500 * (f(x) - f(y)), 200 * (f(y) - f(z)))


class TestPalette(unittest.TestCase):
    def setUp(self):
        figutil._ASSIGNED.clear()

    def test_16_labels_get_distinct_pairs(self):
        for labels, solvers in (
                (USER_LABELS, {}),
                # fixed styles beside user labels (12 of the fixed ones, 4 users')
                (list(figutil.SOLVER_STYLES)[:12] + USER_LABELS[:4], {}),
                ([f"mprgp-v{k}" for k in range(7)] + USER_LABELS[:9], {f"mprgp-v{k}": "mprgp" for k in range(7)})):
            figutil._ASSIGNED.clear()
            styles = figutil.assign_styles(labels, solvers)
            pairs = [(styles[lab]["color"], styles[lab]["marker"]) for lab in labels]
            self.assertEqual(len(set(pairs)), len(labels), pairs)
            self.assertEqual(len(labels), 16)
            self.assertTrue(all(m != "x" for _, m in pairs))  # the not-converged mark stays free

    def test_deterministic_whatever_the_order(self):
        first = figutil.assign_styles(USER_LABELS)
        figutil._ASSIGNED.clear()
        again = figutil.assign_styles(list(reversed(USER_LABELS)))
        self.assertEqual(first, again)
        # and in another process
        code = ("import sys; sys.path.insert(0, %r); from plots import figutil; import json; "
                "print(json.dumps(figutil.assign_styles(%r)))" % (ROOT, USER_LABELS))
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                             env={**os.environ, "MPLBACKEND": "Agg"}).stdout
        import json
        self.assertEqual(json.loads(out), {k: {**v, "linestyle": v["linestyle"]} for k, v in first.items()})

    def test_colours_apart(self):
        fixed = [c for c, _ in figutil.SOLVER_STYLES.values()]
        for a, b in itertools.combinations(fixed, 2):
            self.assertGreater(math.dist(_lab(a), _lab(b)), 25.0, (a, b))  # siconos-lemke vs bullet-dantzig: 11
        for spare in figutil.SPARE_COLOURS:
            for c in fixed:
                self.assertGreater(math.dist(_lab(spare), _lab(c)), 20.0, (spare, c))  # #88CCEE vs #56B4E9: 14
        self.assertEqual(len(set(figutil.SPARE_COLOURS)), len(figutil.SPARE_COLOURS))


class TestChecksCatchBrokenFigures(unittest.TestCase):
    def test_each_rule(self):
        fig, axes = plt.subplots(1, 2, figsize=(9, 3))
        ax = axes[0]
        ax.plot([1e-3, 1e3], [1, 2])
        ax.set_xscale("symlog", linthresh=1e-4)  # the old convergence axis: a "0" tick
        ax.set_xlim(left=0)
        ax.set_xlabel("time")  # no unit
        ax.set_ylabel("value [1]")
        b = axes[1]
        b.plot([1, 2], [1, 2])
        b.set_xticks([1.0, 1.001])  # two labels on top of each other
        b.set_xlabel("x [m]")
        b.set_ylabel("y [m]")
        b.text(1.5, 1.5, "tiny", fontsize=5)
        found = "\n".join(figure_checks.problems(fig, tight=False))
        plt.close(fig)
        self.assertIn("more than a page column", found)
        self.assertIn("'0' tick on the log x axis", found)
        self.assertIn("the x axis label 'time' has no unit", found)
        self.assertRegex(found, r"panel 2: x tick labels '[0-9.]+' and '[0-9.]+' overlap")
        self.assertIn("text 'tiny' is 5 pt", found)

    def test_tidy_ticks_removes_crowded_minor_labels(self):
        # fig11's axis without the authors' data: a log axis over less than a decade labels its minor
        # ticks ("7.1x10^2 2x10^3 ..."), which overlapped
        fig, ax = plt.subplots(figsize=(1.2, 2.0))
        ax.plot([600, 900, 1300, 1900, 3000], [1, 2, 3, 4, 5])
        ax.set_xscale("log")
        ax.set_xlabel("vertices (count)")
        ax.set_ylabel("time [s]")
        fig.canvas.draw()
        before = figure_checks.problems(fig)
        figure_checks.tidy_ticks(fig)
        after = figure_checks.problems(fig)
        plt.close(fig)
        self.assertTrue(any("overlap" in p for p in before), before)
        self.assertEqual([p for p in after if "overlap" in p], [])


class TestDemoFigures(unittest.TestCase):
    """The demo's figure scripts on a suite of 3 snapshots x 16 labels, with the checks enforced."""

    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="cb_figures_")
        figutil._ASSIGNED.clear()
        os.environ["CB_FIGURE_CHECKS"] = "1"

    def tearDown(self):
        os.environ.pop("CB_FIGURE_CHECKS", None)
        shutil.rmtree(self.tmp, ignore_errors=True)

    def _folder(self):
        labels = list(figutil.SOLVER_STYLES)[:10] + USER_LABELS[:6]
        records = []
        for s in range(3):
            for k, label in enumerate(labels):
                records.append(mf.make_run(f"snap-{s}", label, solver=label if label in figutil.SOLVER_STYLES else "cg",
                                           iterations=10 + 7 * k, solve_s=0.01 * (k + 1) * (s + 1),
                                           setup_s=0.001 * (k + 1),
                                           status="converged" if k % 4 else "max_iterations",
                                           final_accuracy=1e-7 if k % 4 else 1e-3, n=300 + s, m=40))
        return mf.write_results(self.tmp, records), labels

    def test_convergence_and_profiles_pass(self):
        folder, labels = self._folder()
        res = load_results(folder)
        err = io.StringIO()
        with redirect_stderr(err):
            written = convergence.plot_convergence(res, os.path.join(folder, "figures"))
            written += profiles.plot_profiles(profiles.compute(res), os.path.join(folder, "figures"), res.runs)
        self.assertEqual(err.getvalue(), "")
        self.assertEqual(len([w for w in written if w.endswith(".png")]), 5)
        # the figure is a page column wide at 300 dpi (7 in, plus the tight box's few points)
        import matplotlib.image as mpimg
        height, width = mpimg.imread(os.path.join(folder, "figures", "convergence_time.png")).shape[:2]
        self.assertLessEqual(width, 7.3 * figutil.DPI)
        self.assertGreater(height, 4.5 * figutil.DPI)  # 3 panels in 2 rows of 2, the legend below

    def test_stiff_family_passes(self):
        import pandas as pd
        from plots import stability
        hist = {case: {lab: pd.DataFrame({"time_s": [0.01, 0.1, 1.0], "error": [1.0, 1e-4, 1e-9]})
                       for lab in ("cg", "cg:precond=ichol", "mprgp", "mprgp:precond=ichol")}
                for case in ("slab-stiff-1e4", "slab-stiff-1e8", "slab-stiff-1e12")}
        with redirect_stdout(io.StringIO()):
            written = stability.plot_stiff_family(hist, self.tmp, tol=1e-8)
        self.assertTrue(written[0].endswith(".png"))


class TestPaperFigures(unittest.TestCase):
    """The quick reproduction's figures with the checks enforced, on the stand-in contactbench
    (tests/python/fixtures/fake_contactbench.py): fig6, fig8, fig9, fig10, fig11 and every profile
    pass, each at most a page column wide; fig8 and fig11 pass again with the authors' data drawn
    beside ours (more legend entries, fig11's DOF axis over more than a decade)."""

    STEMS = ("fig6_decoupling_time", "fig8_mprgp_vs_cg", "fig9_preconditioning", "fig10_mprgp_vs_ica",
             "fig11_scaling")

    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="cb_paper_figures_")
        os.environ["CB_FIGURE_CHECKS"] = "1"

    def tearDown(self):
        os.environ.pop("CB_FIGURE_CHECKS", None)
        shutil.rmtree(self.tmp, ignore_errors=True)

    def _width_in(self, png):
        import matplotlib.image as mpimg
        return mpimg.imread(png).shape[1] / figutil.DPI

    def _authors_data(self):
        """Made-up authors' files in the columns `make paper-data` writes (plots/paper_data.py)."""
        from plots import paper_data
        data = os.path.join(self.tmp, "paper-data")
        os.makedirs(os.path.join(data, "figures"))
        with open(os.path.join(data, "figures", "fig8_objective_history.csv"), "w") as f:
            f.write("iteration,mprgp_objective,cg_objective\n")
            for k in range(60):
                f.write(f"{k},{-10 - 5 * (1 - 0.8 ** k)!r},{(-10 - 5.5 * (1 - 0.7 ** k)) if k < 45 else ''}\n")
        with open(os.path.join(data, "figures", "fig11_mprgp_vs_ica.csv"), "w") as f:
            f.write(",".join(paper_data.FIG11_COLUMNS) + "\n")
            for k, dofs in enumerate((7818, 15000, 24000, 45000, 81000)):
                row = {c: 1 for c in paper_data.FIG11_COLUMNS}
                row.update(snapshot=f"s{k}", dofs=dofs, rows_decoupled=100 + 10 * k, power_iterations=700 + 60 * k,
                           mprgp_iterations=45 + 5 * k, mprgp_time_s=0.2 * dofs / 7818,
                           ica_time_s=0.5 * (dofs / 7818) ** 1.5, ica_iterations=2000 + 400 * k)
                f.write(",".join(str(row[c]) for c in paper_data.FIG11_COLUMNS) + "\n")
        return data

    def test_every_paper_figure_passes(self):
        from plots import fig8, fig11, reproduce
        from plots.paper_context import standalone_context
        scenes = os.path.join(self.tmp, "scenes")
        os.makedirs(scenes)
        for name in ("two_dinos_1303", "two_dinos_1493", "longcube"):
            with open(os.path.join(scenes, name + ".json"), "w") as f:
                f.write("{}")
        out = os.path.join(self.tmp, "out")
        fake = os.path.join(HERE, "fixtures", "fake_contactbench.py")
        with redirect_stdout(io.StringIO()) as log, redirect_stderr(io.StringIO()):
            self.assertEqual(reproduce.main(["--contactbench", fake, "--out", out, "--scenes", scenes,
                                             "--quick", "--data", os.path.join(self.tmp, "no-data")]), 0)
        broken = [line for line in log.getvalue().splitlines() if "FigureCheckError" in line]
        self.assertEqual(broken, [])  # every figure script and the profiles
        for stem in self.STEMS:
            png = os.path.join(out, "figures", stem + ".png")
            self.assertTrue(os.path.isfile(png), log.getvalue()[-3000:])
            self.assertLessEqual(self._width_in(png), 7.3, stem)  # 7 in plus the tight box's few points
        data = self._authors_data()
        for module, suite, stem, authors in ((fig8, "fig8", "fig8_mprgp_vs_cg", "fig8_objective_history.csv"),
                                             (fig11, "fig11", "fig11_scaling", "fig11_mprgp_vs_ica.csv")):
            ctx = standalone_context([os.path.join(out, "runs", suite), "--data", data,
                                      "--out", os.path.join(self.tmp, "with-data")], suite, suite)
            self.assertIsNotNone(ctx.authors_csv(authors))  # the authors' series are drawn
            figutil._ASSIGNED.clear()
            with redirect_stdout(io.StringIO()), redirect_stderr(io.StringIO()):
                files = module.produce(ctx).files  # raises FigureCheckError on a broken rule
            png = [f for f in files if f.endswith(".png")]
            self.assertEqual([os.path.basename(f) for f in png], [stem + ".png"])
            self.assertLessEqual(self._width_in(png[0]), 7.3, stem)


if __name__ == "__main__":
    unittest.main()
