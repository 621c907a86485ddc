"""plots/decoupling.py: the rule for "noticeable" on constructed chains, the claim rows' verdicts,
the summary numbers, and (with CB_CONTACTBENCH) a cached `chains` run of the demo scene."""
import json
import math
import os
import signal
import subprocess
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "plots"))

import pandas as pd  # noqa: E402

import decoupling  # noqa: E402

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")


def chains_frame(pen: dict, frames: int = 4, rows: int = 10) -> pd.DataFrame:
    """chains.csv rows: chain label -> its penetration_rel per frame (a list) or one value."""
    out = []
    for label, values in pen.items():
        values = values if isinstance(values, list) else [values] * frames
        for f, p in enumerate(values):
            dropped = 0 if label.startswith("exact") else 4
            out.append({"frame": f, "time_s": 0.01 * (f + 1), "chain": label, "solver": "x", "decouple": "x",
                        "status": "converged", "steps_not_solved": 0, "accuracy": 1e-8, "rows": rows,
                        "rows_solved": rows - dropped, "rows_dropped": dropped, "penetration": p,
                        "penetration_rel": p, "violation_rel": 0.0,
                        "rms_distance_rel": 0.0 if label == "exact" else 1e-3 * (f + 1),
                        "max_distance_rel": 0.0 if label == "exact" else 2e-3 * (f + 1),
                        "kinetic_energy": 1.0, "elastic_energy": 1.0, "blow_up": 0})
    return pd.DataFrame(out)


def summary(pen: dict, scene: str = "s") -> dict:
    return decoupling.summarize(chains_frame(pen), {"scene": scene, "h": 0.005, "frames": 4, "body_size": 1.0})


class Rule(unittest.TestCase):
    def test_numbers_of_a_run(self):
        s = summary({"exact": [0.0, 0.01, 0.002, 0.0], "exact-tol1e-6": 0.003, "authors": [0.0, 0.02, 0.03, 0.01]})
        self.assertAlmostEqual(s["exact_max_penetration_rel"], 0.01)
        a = s["chains"]["authors"]
        self.assertAlmostEqual(a["max_penetration_rel"], 0.03)
        self.assertAlmostEqual(a["mean_penetration_rel"], 0.015)
        self.assertAlmostEqual(a["rows_dropped_fraction"], 0.4)
        self.assertAlmostEqual(a["max_distance_rel"], 8e-3)
        self.assertAlmostEqual(s["noise_floor_rel"], 8e-3)

    def test_price_is_noticeable_only_when_visible_and_twice_the_exact_chains(self):
        self.assertEqual(decoupling.price(summary({"exact": 0.004, "exact-tol1e-6": 0.004, "authors": 0.0201})),
                         "noticeable")
        # visible but not decoupling's: the exact chain penetrates nearly as deep (the step's cause)
        self.assertEqual(decoupling.price(summary({"exact": 0.03, "exact-tol1e-6": 0.03, "authors": 0.036})), "none")
        # far above the exact chain but not visible
        self.assertEqual(decoupling.price(summary({"exact": 0.001, "exact-tol1e-6": 0.001, "authors": 0.0099})),
                         "none")
        # between 1.25x and 2x: no verdict
        self.assertEqual(decoupling.price(summary({"exact": 0.01, "exact-tol1e-6": 0.01, "authors": 0.015})),
                         decoupling.INCONCLUSIVE)
        # the noise chain's penetration counts as the exact chains' too
        self.assertEqual(decoupling.price(summary({"exact": 0.004, "exact-tol1e-6": 0.011, "authors": 0.02})),
                         decoupling.INCONCLUSIVE)

    def test_claim_rows(self):
        runs = {"dino_eight": {"h": summary({"exact": 0.004, "exact-tol1e-6": 0.004, "authors": 0.03,
                                             "depth": 0.012}, "dino_eight")},
                "long_cube": {"h": summary({"exact": 0.002, "exact-tol1e-6": 0.002, "authors": 0.003,
                                            "depth": 0.003}, "long_cube")}}
        rows = {r["key"]: r for r in decoupling.claim_rows(runs)}
        self.assertEqual(rows["sec6-decoupling-no-visual-artifacts"]["verdict"], decoupling.DOES_NOT_HOLD)
        self.assertIn("authors 3% vs exact 0.4%", rows["sec6-decoupling-no-visual-artifacts"]["ours"])
        self.assertEqual(rows["sec7-decoupling-no-noticeable-artifacts"]["verdict"], decoupling.DOES_NOT_HOLD)
        self.assertIn("1 of 2 scenes (dino_eight)", rows["sec7-decoupling-no-noticeable-artifacts"]["ours"])
        # depth: excess 0.8% against 2.6% on the one scene with a price: reduces it
        self.assertEqual(rows["sec5-depth-sorted-selection"]["verdict"], decoupling.HOLDS)
        # a scene whose decoupled chain keeps every row is no case of the claim
        kept_all = summary({"exact": 0.002, "exact-tol1e-6": 0.002, "authors": 0.05, "depth": 0.05}, "resting")
        for order in ("authors", "depth"):
            kept_all["chains"][order]["rows_dropped_fraction"] = 0.0
        self.assertEqual(decoupling.price(kept_all), decoupling.NOT_EXERCISED)
        rows = {r["key"]: r for r in decoupling.claim_rows({"long_cube": runs["long_cube"], "resting": {"h": kept_all}})}
        self.assertEqual(rows["sec7-decoupling-no-noticeable-artifacts"]["verdict"], decoupling.HOLDS)
        self.assertNotIn("resting", rows["sec7-decoupling-no-noticeable-artifacts"]["problem"])
        # ... nor of Sec. 5: its excess (5% - 0.2%) comes from the solver, not from dropped rows
        self.assertEqual(rows["sec5-depth-sorted-selection"]["verdict"], decoupling.NOT_MEASURED)
        quiet = {"long_cube": runs["long_cube"]}
        rows = {r["key"]: r for r in decoupling.claim_rows(quiet)}
        self.assertEqual(rows["sec6-decoupling-no-visual-artifacts"]["verdict"], decoupling.NOT_MEASURED)
        self.assertEqual(rows["sec7-decoupling-no-noticeable-artifacts"]["verdict"], decoupling.HOLDS)
        self.assertEqual(rows["sec5-depth-sorted-selection"]["verdict"], decoupling.NOT_MEASURED)  # no case
        self.assertEqual(rows["sec5-depth-sorted-selection"]["reason"],
                         "no scene's authors'-order excess penetration is > 0.5% of L: no case of the claim")

    def test_the_table_names_each_runs_exact_solver(self):
        record = {"scene": "s", "h": 0.005, "frames": 4, "body_size": 1.0,
                  "chains": [{"label": "exact", "solver": "mprgp-coupled"}, {"label": "authors", "solver": "mprgp"}]}
        s = decoupling.summarize(chains_frame({"exact": 0.01, "exact-tol1e-6": 0.01, "authors": 0.02}), record)
        self.assertEqual(s["exact_solver"], "mprgp-coupled")
        old = summary({"exact": 0.01, "exact-tol1e-6": 0.01, "authors": 0.02})  # a record without chains
        self.assertEqual(old["exact_solver"], "?")
        rows = decoupling.compact_table({"s": {"h": s}}).splitlines()
        self.assertTrue(rows[0].endswith("| vertices inside (exact / authors) | price (authors) | exact solver |"), rows[0])
        self.assertTrue(rows[2].endswith("| — / — | inconclusive | mprgp-coupled |"), rows[2])  # no count: version < 4


@unittest.skipUnless(os.environ.get("CB_CONTACTBENCH"), "needs CB_CONTACTBENCH (set by ctest)")
class BadOptions(unittest.TestCase):
    """Exit status 2, the option and what is wrong named, nothing written."""

    def check(self, args, message):
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "out")
            done = subprocess.run([os.environ["CB_CONTACTBENCH"]] + args + ["--out", out],
                                  capture_output=True, text=True)
            self.assertEqual(done.returncode, 2, done.stderr)
            self.assertIn(message, done.stderr)
            self.assertFalse(os.path.exists(out))

    def test_messages(self):
        demo = os.path.join(ROOT, "scenes", "demo.json")
        self.check(["simulate", demo, "--decouple", "sideways"],
                   "simulate: error: --decouple: expected auto, none, authors, random or depth, got 'sideways'")
        self.check(["simulate", demo, "--h", "0.003"],
                   "--h: the frame's duration 0.010000 s (scene step x steps per frame) is not a whole number of "
                   "steps of 0.003000 s")
        self.check(["simulate", demo, "--h", "-1"], "simulate: error: --h: must be > 0 seconds")
        self.check(["chains", demo, "--orders", "authors,deep"],
                   "chains: error: --orders: expected a comma-separated list of authors, random, depth; got 'deep'")
        self.check(["chains", demo, "--exact", "nosuch"], "chains: error: --exact: no solver named 'nosuch'")


@unittest.skipUnless(os.environ.get("CB_CONTACTBENCH"), "needs CB_CONTACTBENCH (set by ctest)")
class DemoChains(unittest.TestCase):
    def test_run_is_cached_and_reported(self):
        cb = os.environ["CB_CONTACTBENCH"]
        scene = os.path.join(ROOT, "scenes", "demo.json")
        with tempfile.TemporaryDirectory() as out:
            folder = os.path.join(out, "chains", "demo", "h")
            ok, what = decoupling.run_chains(cb, scene, folder, 8)
            self.assertTrue(ok, what)
            self.assertTrue(what.startswith("ran"))
            ok, what = decoupling.run_chains(cb, scene, folder, 8)
            self.assertTrue(what.startswith("cached"), what)
            ok, what = decoupling.run_chains(cb, scene, folder, 7)  # another input: run again
            self.assertTrue(what.startswith("ran"), what)
            df, record = decoupling.load(folder)
            self.assertEqual(list(df["chain"].unique()), ["exact", "exact-tol1e-6", "authors", "random", "depth"])
            s = decoupling.summarize(df, record)
            # the boxes touch at frame 6: the decoupled chains drop rows there, the exact ones none
            self.assertGreater(s["chains"]["authors"]["rows_dropped_fraction"], 0)
            self.assertEqual(s["chains"]["exact"]["rows_dropped_fraction"], 0)
            self.assertEqual(s["exact_solver"], "mprgp-coupled")  # the default exact solver
            self.assertGreater(s["chains"]["authors"]["max_vertices_inside"], 0)  # decoupled boxes interpenetrate
            self.assertLess(s["noise_floor_rel"], 1e-4)
            self.assertGreater(s["chains"]["authors"]["max_distance_rel"], 10 * s["noise_floor_rel"])
            claims = decoupling.report(out)
            self.assertEqual(len(claims), 3)
            with open(os.path.join(out, "decoupling_claims.json")) as f:
                self.assertEqual(len(json.load(f)["claims"]), 3)
            self.assertTrue(os.path.isfile(os.path.join(out, "figures", "decoupling_demo_h.png")))
            self.assertFalse(math.isnan(s["exact_max_penetration_rel"]))

    def test_interrupted_run_is_resumed(self):
        """A chains folder interrupted after run_chains started it (key.pending.json and chains.state)
        is resumed, and its table equals an uninterrupted run's bit for bit."""
        cb = os.environ["CB_CONTACTBENCH"]
        scene = os.path.join(ROOT, "scenes", "demo.json")
        with tempfile.TemporaryDirectory() as out:
            whole, folder = os.path.join(out, "whole"), os.path.join(out, "cut")
            ok, what = decoupling.run_chains(cb, scene, whole, 60)
            self.assertTrue(ok, what)
            os.makedirs(folder)
            with open(os.path.join(folder, "key.pending.json"), "w", encoding="utf-8") as f:
                json.dump(decoupling.chains_key(cb, scene, 60, None, None), f)
            # The run as run_chains starts it, stopped by SIGINT once three frames are whole.
            first = subprocess.Popen([cb, "chains", scene, "--frames", "60", "--out", folder],
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            state = os.path.join(folder, "chains.state")
            try:
                deadline = time.time() + 120
                while time.time() < deadline and first.poll() is None:
                    try:
                        with open(state, "rb") as f:
                            if json.loads(f.read().split(b"\n")[1])["frames_done"] >= 3:
                                break
                    except (OSError, ValueError, IndexError):
                        pass
                    time.sleep(0.002)
            finally:
                first.send_signal(signal.SIGINT)
                first.wait()
            self.assertEqual(first.returncode, 130)
            self.assertFalse(os.path.exists(os.path.join(folder, "chains.json")))
            ok, what = decoupling.run_chains(cb, scene, folder, 60)
            self.assertTrue(ok, what)
            self.assertEqual(what, f"resumed ({folder})")
            for name in ("chains.csv", "chains.json"):
                with open(os.path.join(whole, name), "rb") as a, open(os.path.join(folder, name), "rb") as b:
                    self.assertEqual(a.read(), b.read(), name)
            self.assertFalse(os.path.exists(os.path.join(folder, "key.pending.json")))
            self.assertTrue(decoupling.run_chains(cb, scene, folder, 60)[1].startswith("cached"))


if __name__ == "__main__":
    unittest.main()
