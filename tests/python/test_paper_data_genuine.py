"""The authors' genuine tree through `make paper-data`'s fetcher (plots/paper_data.py): it extracts and
matches the manifest. Runs only when PAPER_DATA_SOURCE names a local copy of the tree (.tar.gz or
folder; CI names the tarball); elsewhere ctest reports it skipped (tests/python/unittest_runner.py)."""
import contextlib
import io
import os
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, ROOT)  # plots is a package of the repository root
from plots import paper_data  # noqa: E402


@unittest.skipUnless(os.path.exists(os.environ.get("PAPER_DATA_SOURCE", "")),
                     "PAPER_DATA_SOURCE does not name a local copy of the authors' tree (.tar.gz or folder)")
class GenuineTree(unittest.TestCase):
    def test_the_authors_tree_extracts_and_matches_the_manifest(self):
        manifest = paper_data.read_manifest(paper_data.MANIFEST)
        with tempfile.TemporaryDirectory() as tmp:
            dest = os.path.join(tmp, "paper-data")
            err = io.StringIO()
            with contextlib.redirect_stderr(err):
                status = paper_data.main(["--source", os.environ["PAPER_DATA_SOURCE"], "--dest", dest])
            self.assertEqual(status, 0, err.getvalue())
            for out, src in paper_data.COPIED.items():
                self.assertEqual(paper_data.sha256(os.path.join(dest, out)), manifest[src].sha256, out)
            with open(os.path.join(dest, "figures", "fig11_mprgp_vs_ica.csv")) as f:
                self.assertEqual(f.readline().rstrip("\n").split(","), paper_data.FIG11_COLUMNS)
            self.assertEqual(sorted(os.listdir(tmp)), ["paper-data"])


if __name__ == "__main__":
    unittest.main()
