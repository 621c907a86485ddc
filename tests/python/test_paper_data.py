"""Tests of plots/paper_data.py (`make paper-data`): the conversion of the authors' raw files into
the figure tables, on small raw files written for this test (fixtures/paper_data/), and the
fetch-verify-extract path on a made-up tree: altered and missing files are refused by name."""
import contextlib
import csv
import io
import os
import sys
import tarfile
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, ROOT)  # plots is a package of the repository root
from plots import paper_data  # noqa: E402

FIXTURES = os.path.join(HERE, "fixtures", "paper_data")


def read_fixture(key):
    with open(os.path.join(FIXTURES, os.path.basename(paper_data.RAW[key]))) as f:
        return f.read()


def rows(text):
    return list(csv.reader(io.StringIO(text)))


class Conversion(unittest.TestCase):
    def setUp(self):
        self.tables = paper_data.convert_figures(read_fixture)

    def test_fig8_objective_per_iteration_with_empty_cells_past_a_series_end(self):
        self.assertEqual(rows(self.tables["figures/fig8_objective_history.csv"]),
                         [["iteration", "mprgp_objective", "cg_objective"],
                          ["0", "-10.5", "-10.5"], ["1", "-11.25", "-12.0"], ["2", "-11.5", "-12.25"],
                          ["3", "", "-12.375"]])

    def test_fig6_seconds_per_frame(self):
        self.assertEqual(rows(self.tables["figures/fig6_decoupling_time.csv"]),
                         [["frame", "decoupled_time_s", "coupled_time_s"],
                          ["0", "1.5", "3.0"], ["1", "2.25", "4.5"], ["2", "", "900.125"]])

    def test_fig11_one_row_per_qp_of_the_log(self):
        table = rows(self.tables["figures/fig11_mprgp_vs_ica.csv"])
        header = table[0]
        self.assertEqual(header, paper_data.FIG11_COLUMNS)
        self.assertNotIn("constraints_coupled", header)  # the decoupled row count is named as such
        first = dict(zip(header, table[1]))
        self.assertEqual(first["snapshot"], "tempt_two_mprgp_h005_77")
        self.assertEqual((first["dofs"], first["rows_decoupled"], first["j_nonzeros"]), ("600", "5", "60"))
        self.assertEqual((first["power_iterations"], first["mprgp_cg_steps"], first["mprgp_expansion_steps"],
                          first["mprgp_proportioning_steps"], first["mprgp_iterations"]), ("12", "30", "1", "2", "33"))
        self.assertEqual((first["mprgp_active_rows"], first["mprgp_time_s"], first["ica_time_s"],
                          first["ica_iterations"], first["ica_residual"]), ("3", "0.25", "1.75", "400", "7.9e-05"))
        second = dict(zip(header, table[2]))
        self.assertEqual((second["dofs"], second["rows_decoupled"], second["ica_time_s"]), ("1200", "9", "4.0"))
        self.assertEqual(len(table), 3)

    def test_a_record_missing_a_field_is_named(self):
        log = read_fixture("mprgp_ica_log").replace("J.rows() = 9\n", "")
        with self.assertRaises(paper_data.DataError) as e:
            paper_data.parse_mprgp_ica_log(log, "ica_mprgp.txt")
        self.assertEqual(str(e.exception), "ica_mprgp.txt: record tempt_two_mprgp_h005_88: missing rows_decoupled")

    def test_a_bad_number_is_named(self):
        with self.assertRaises(paper_data.DataError) as e:
            paper_data.number_list("1.5, 2.x, 3", "cg.txt")
        self.assertEqual(str(e.exception), "cg.txt: value 2: expected a number, got '2.x'")


class FetchVerifyExtract(unittest.TestCase):
    """A made-up tree with every used file; a manifest of its own hashes stands in for the real one."""

    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.tree = os.path.join(self.tmp.name, "MPRGP")
        for out, src in paper_data.COPIED.items():
            self.write(src, f"made-up content of {out}\n")
        for key, src in paper_data.RAW.items():
            self.write(src, read_fixture(key))
        self.manifest = os.path.join(self.tmp.name, "manifest.sha256")
        with open(self.manifest, "w") as f:
            for src in sorted(set(paper_data.COPIED.values()) | set(paper_data.RAW.values())):
                path = os.path.join(self.tree, src)
                f.write(f"{paper_data.sha256(path)} {os.path.getsize(path)} {src}\n")
        self.saved_manifest = paper_data.MANIFEST
        paper_data.MANIFEST = self.manifest
        self.dest = os.path.join(self.tmp.name, "cache", "paper-data")

    def tearDown(self):
        paper_data.MANIFEST = self.saved_manifest
        self.tmp.cleanup()

    def write(self, rel, text):
        path = os.path.join(self.tree, rel)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "w") as f:
            f.write(text)

    def tarball(self):
        path = os.path.join(self.tmp.name, "tree.tar.gz")
        with tarfile.open(path, "w:gz") as t:
            t.add(self.tree, arcname="MPRGP")
        return path

    def run_main(self, source):
        err = io.StringIO()
        with contextlib.redirect_stderr(err):
            status = paper_data.main(["--source", source, "--dest", self.dest])
        return status, err.getvalue()

    def test_tarball_is_verified_and_extracted(self):
        status, err = self.run_main(self.tarball())
        self.assertEqual(status, 0, err)
        with open(os.path.join(self.dest, "meshes", "dino_1303_4014.abq")) as f:
            self.assertEqual(f.read(), "made-up content of meshes/dino_1303_4014.abq\n")
        with open(os.path.join(self.dest, "figures", "fig6_decoupling_time.csv")) as f:
            self.assertEqual(f.read(), paper_data.convert_figures(read_fixture)["figures/fig6_decoupling_time.csv"])
        self.assertIn("34 files verified", err)

    def test_folder_source_works_too(self):
        status, err = self.run_main(self.tree)
        self.assertEqual(status, 0, err)
        self.assertTrue(os.path.isfile(os.path.join(self.dest, "scenes", "dino_two_mprgp_1303.ini")))

    def test_altered_file_is_refused_and_nothing_written(self):
        self.write("data/dino/model/mesh_1303_4014.abq", "made-up content of meshes/dino_1303_4014.abX\n")
        self.write("script/data/cg.txt", read_fixture("cg_objective").replace("1", "7"))
        for source in (self.tarball(), self.tree):
            status, err = self.run_main(source)
            self.assertEqual(status, 2)
            self.assertIn(f"paper-data: error: {source}: SHA-256 differs from manifest.sha256 (not commit 57fdd2c?): "
                          "data/dino/model/mesh_1303_4014.abq, script/data/cg.txt\n", err)
            self.assertFalse(os.path.exists(self.dest))
            # no temporary folder left, and the parent the run made for DEST is gone again
            self.assertFalse(os.path.exists(os.path.dirname(self.dest)))

    def test_file_of_another_size_is_refused_before_it_is_copied(self):
        self.write("data/dino/model/mesh_1303_4014.abq", "altered\n")
        expected = paper_data.read_manifest(self.manifest)["data/dino/model/mesh_1303_4014.abq"].size
        status, err = self.run_main(self.tarball())
        self.assertEqual(status, 2)
        self.assertIn(f"member 'MPRGP/data/dino/model/mesh_1303_4014.abq': 8 bytes where {expected} are expected; "
                      "refused before unpacking it", err)
        status, err = self.run_main(self.tree)
        self.assertEqual(status, 2)
        self.assertIn(f"{self.tree}/data/dino/model/mesh_1303_4014.abq: 8 bytes where {expected} are expected; "
                      "refused before copying it", err)
        self.assertFalse(os.path.exists(self.dest))

    def test_missing_file_is_named(self):
        os.remove(os.path.join(self.tree, "script", "data", "cg.txt"))
        status, err = self.run_main(self.tarball())
        self.assertEqual(status, 2)
        self.assertIn("lacks 1 file(s) contactbench uses: script/data/cg.txt", err)
        self.assertFalse(os.path.exists(self.dest))

    def test_committed_manifest_lists_every_used_file(self):
        listed = paper_data.read_manifest(self.saved_manifest)
        self.assertEqual(sorted(listed), sorted(set(paper_data.COPIED.values()) | set(paper_data.RAW.values())))
        self.assertEqual(listed["script/data/ica_mprgp.txt"].size, 15329)  # sizes too, checked before copying


if __name__ == "__main__":
    unittest.main()
