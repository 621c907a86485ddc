"""plots/html_report.py (issue 46) without a browser: the page of a results folder and of a
reproduction, every record string escaped, the embedded JSON unable to close its element, the
page whole or not at all, and a clear exit 2 on a folder that is no results folder.
(tests/browser/test_report_browser.py opens the page in Chromium.)

Run from tests/python: /usr/bin/python3 -m unittest test_html_report
"""
import io
import json
import os
import re
import shutil
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
from plots import html_report  # noqa: E402

EVIL = "<script>alert(1)</script>"


def embedded(page):
    """The JSON of the page's data element."""
    m = re.search(r'<script type="application/json" id="report-data">(.*?)</script>', page, re.S)
    return json.loads(m.group(1))


class TestHtmlReport(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="cb_html_")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def _results(self, folder):
        recs = [mf.make_run("p1", "mprgp", iterations=20, solve_s=0.5, setup_s=0.01),
                mf.make_run("p1", "pgs", status="max_iterations", final_accuracy=1e-3, iterations=50, solve_s=2.0),
                mf.make_run("p2", "mprgp", iterations=10, solve_s=0.2),
                mf.make_run("p2", "evil", solver="cg", iterations=900)]
        recs[0]["memory"] = {"peak_rss_mb": 12.5}
        mf.write_results(folder, recs)
        path = os.path.join(folder, "runs", "p2__evil.json")
        with open(path) as f:
            rec = json.load(f)
        rec["label"], rec["message"] = EVIL, "</script><img src=x onerror=alert(2)>&amp;"
        with open(path, "w") as f:
            json.dump(rec, f)
        with open(os.path.join(folder, "provenance.json"), "w") as f:
            json.dump({**mf.PROVENANCE, "hostname": EVIL}, f)
        return folder

    def test_results_folder_page(self):
        folder = self._results(os.path.join(self.tmp, "demo"))
        with redirect_stdout(io.StringIO()) as out:
            self.assertEqual(html_report.main([folder]), 0)
        index = os.path.join(folder, "report", "index.html")
        self.assertEqual(out.getvalue().strip(), f"report: {os.path.abspath(index)}")
        self.assertEqual(sorted(os.listdir(os.path.join(folder, "report"))),
                         ["d3.min.js", "index.html", "report.css", "report.js"])
        with open(index, encoding="utf-8") as f:
            page = f.read()
        # one element of executable script per file beside the page, none inline; the record's strings
        # appear only escaped
        self.assertEqual(re.findall(r"<script[^>]*>", page),
                         ['<script type="application/json" id="report-data">', '<script src="d3.min.js">',
                          '<script src="report.js">'])
        self.assertEqual(page.count("</script>"), 3)
        self.assertNotIn("<img src=x", page)
        self.assertIn("&lt;script&gt;alert(1)&lt;/script&gt;", page)  # the provenance's hostname, escaped
        self.assertNotRegex(page, r"https?://")  # nothing from the network
        data = embedded(page)
        self.assertEqual(len(data["rows"]), 4)
        row = {r["label"]: r for r in data["rows"]}
        self.assertEqual(row[EVIL]["message"], "</script><img src=x onerror=alert(2)>&amp;")
        self.assertEqual([r["peak_mb"] for r in data["rows"] if r["label"] == "mprgp"], [12.5, None])
        self.assertEqual(row["pgs"]["status"], "max_iterations")
        self.assertAlmostEqual(row["pgs"]["e"], 1e-3)
        self.assertEqual(row["pgs"]["iterations"], 50)
        # two snapshots drawn, the tolerance with them; the profile at the tightest tier (1e-6)
        self.assertEqual([h["snapshot"] for h in data["histories"]], ["p1", "p2"])
        self.assertEqual(data["histories"][0]["tol"], 1e-6)
        prof = data["profiles"][0]
        self.assertEqual(prof["tier"], 1e-6)
        self.assertEqual(prof["problems"], 2)
        ratios = {p["label"]: p["ratios"] for p in prof["labels"]}
        self.assertEqual(ratios["mprgp"], [1.0, 1.0])
        self.assertEqual(ratios["pgs"], [])  # never reached 1e-6 on p1; no run on p2

    def test_histories_thinned_with_the_last_point(self):
        folder = self._results(os.path.join(self.tmp, "demo"))
        data = html_report.collect(folder)
        evil = [s for h in data["histories"] for s in h["series"] if s["label"] == EVIL][0]
        self.assertLessEqual(len(evil["points"]), html_report.MAX_POINTS + 1)
        self.assertEqual(evil["points"][-1][1], 900)  # the final iteration kept

    def test_safe_json_cannot_close_the_element(self):
        text = html_report.safe_json({"a": "</script><!-- & \u2028"})
        self.assertNotIn("<", text)
        self.assertNotIn(">", text)
        self.assertNotIn("&", text)
        self.assertEqual(json.loads(text), {"a": "</script><!-- & \u2028"})

    def test_reproduction_claims_link_their_figures(self):
        out = os.path.join(self.tmp, "paper")
        self._results(os.path.join(out, "runs", "fig10"))
        os.makedirs(os.path.join(out, "figures"))
        for name in ("fig10_mprgp_vs_ica.png", "fig6_decoupling_time.png"):
            with open(os.path.join(out, "figures", name), "wb") as f:
                f.write(b"\x89PNG\r\n\x1a\n")
        with open(os.path.join(out, "claims.json"), "w") as f:
            json.dump([{"key": "fig10-ica-10x", "claim": "MPRGP <b>10x</b>", "source": "Sec. 6.2, Fig. 10",
                        "paper": "10x", "authors": "—", "ours": "12.1", "verdict": "holds", "interval": [11.0, 13.5],
                        "coverage": 0.9375, "reason": "", "judged_on": "e"}], f)
        path = html_report.write_report(out)
        with open(path, encoding="utf-8") as f:
            page = f.read()
        self.assertIn("MPRGP &lt;b&gt;10x&lt;/b&gt;", page)
        self.assertIn("12.1 — interval [11, 13.5] (93.8%)", page)
        self.assertIn('<a href="../figures/fig10_mprgp_vs_ica.png">fig10_mprgp_vs_ica.png</a></td>', page)
        self.assertEqual(page.count('href="../figures/fig6_decoupling_time.png"'), 1)  # the gallery's only
        self.assertEqual(len(embedded(page)["rows"]), 4)

    def test_not_a_results_folder(self):
        err = io.StringIO()
        with redirect_stderr(err):
            self.assertEqual(html_report.main([self.tmp]), 2)
        self.assertEqual(err.getvalue().strip(),
                         f"html_report: error: {self.tmp}: not a results folder (no runs/ and no summary.csv) nor a "
                         "reproduction (no runs/<suite>/ results folders)")
        self.assertEqual(os.listdir(self.tmp), [])  # nothing written

    def test_strip_frames_and_caption(self):
        import pandas as pd
        from plots import strip
        self.assertEqual(strip.strip_frames(20, 5), [0, 5, 10, 14, 19])  # sim/simulator.cpp's rule
        self.assertEqual(strip.strip_frames(3, 6), [0, 1, 2])
        frames = pd.DataFrame({"frame": [0, 1, 2, 3, 4, 5, 6], "time_s": [0.1 * k for k in range(7)],
                               "max_penetration_rel": [0, 0.02, 0.5, 0.01, 0, 0.03, 0.11]})
        # frame 2's 50% is not pictured: the caption states what the strip shows
        self.assertEqual(strip.largest_penetration(frames, [0, 3, 6]), (0.11, 6))
        sim = os.path.join(self.tmp, "sim")
        os.makedirs(sim)
        frames.to_csv(os.path.join(sim, "frames.csv"), index=False)
        with open(os.path.join(sim, "simulation.json"), "w") as f:
            json.dump({"scene": "cubes", "frames": 7, "frames_done": 7, "solver": "mprgp", "decouple": "auto"}, f)
        from plots.figutil import plt
        import numpy as np
        plt.imsave(os.path.join(sim, "cubes_strip.png"), np.ones((20, 120, 3)))  # six 20x20 tiles
        out = os.path.join(self.tmp, "demo")
        self._results(out)
        os.rename(sim, os.path.join(out, "sim"))
        path = html_report.write_report(out)
        with open(path, encoding="utf-8") as f:
            page = f.read()
        self.assertIn('<img src="strip_0.png" alt="sim">', page)
        self.assertTrue(os.path.isfile(os.path.join(out, "report", "strip_0.png")))

    def test_ladder_shows_the_which_solver_map(self):
        folder = self._results(os.path.join(self.tmp, "resolution"))
        os.makedirs(os.path.join(folder, "figures"))
        with open(os.path.join(folder, "figures", "which_solver.png"), "wb") as f:
            f.write(b"\x89PNG\r\n\x1a\n")
        with open(html_report.write_report(folder), encoding="utf-8") as f:
            page = f.read()
        self.assertIn('<section id="which-solver"><h2>Which solver when</h2><a href="../figures/which_solver.png">'
                      '<img class="map" src="../figures/which_solver.png"', page)

    def test_rewrite_replaces_the_page_whole(self):
        folder = self._results(os.path.join(self.tmp, "demo"))
        html_report.write_report(folder)
        with open(os.path.join(folder, "report", "stale.txt"), "w") as f:
            f.write("old")
        html_report.write_report(folder)
        self.assertNotIn("stale.txt", os.listdir(os.path.join(folder, "report")))
        self.assertEqual([n for n in os.listdir(folder) if n.startswith(".report")], [])


if __name__ == "__main__":
    unittest.main()
