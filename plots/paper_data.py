#!/usr/bin/python3
"""Fetch the paper authors' public repository, verify it and extract the data contactbench uses.

    /usr/bin/python3 -m plots.paper_data [--source SRC] [--dest DIR]          (`make paper-data`)

SRC is a git URL (default: the authors' repository simba518/MPRGP, checked out at commit 57fdd2c),
a local folder holding that tree, or a .tar.gz of it. Every file used is checked against the
SHA-256 manifest committed beside this script (paper_data.sha256); a missing or altered file is an
error that names it, and nothing is written. DIR (default $CB_CACHE/paper-data, CB_CACHE defaulting
to ~/.cache/contactbench) receives:

    meshes/   the authors' tet meshes and obstacle surfaces, under the names the scenes use
    scenes/   their scene settings (.ini) and materials (.elastic)
    figures/  CSV tables converted by this script from the raw logs and number lists under the
              tree's script/data/ (never copies): see docs/SOURCES.md for every column
    paper-data.json   where it came from: source, commit, every file with its hash

The repository carries no license: its files are read as reference data and never committed to
contactbench.
"""
import argparse
import csv
import hashlib
import io
import json
import os
import re
import shutil
import subprocess
import sys
import tarfile
import tempfile
from typing import Dict, List, Optional, Tuple

DEFAULT_SOURCE = "https://github.com/simba518/MPRGP.git"
COMMIT = "57fdd2c"
MANIFEST = os.path.join(os.path.dirname(os.path.abspath(__file__)), "paper_data.sha256")

#: output path -> path in the authors' tree (files copied unchanged into the cache)
COPIED = {
    "meshes/dino_1303_4014.abq": "data/dino/model/mesh_1303_4014.abq",
    "meshes/dino_1493_5429.abq": "data/dino/model/mesh_1493_5429.abq",
    "meshes/dino_2970_10759.abq": "data/dino/model/mesh_2970_10759.abq",
    "meshes/dino_5910_20802.abq": "data/dino/model/mesh_5910_20802.abq",
    "meshes/dino_9381_41992.abq": "data/dino/model/mesh_9381_41992.abq",
    "meshes/dino_20044_84904.abq": "data/dino/model/mesh_20044_84904.abq",
    "meshes/dragon_asia_small.abq": "data/dragon_asia/model/mesh.abq",
    "meshes/stairs.obj": "data/beam/model/stairs.obj",
    "meshes/bowl.obj": "data/beam-coarse/model/bowl.obj",
    "meshes/cup.obj": "data/beam-coarse/model/cup.obj",
    "scenes/bunny_one.ini": "data/bunny/one.ini",
    "scenes/bunny_one2.ini": "data/bunny/one2.ini",
    "scenes/bunny_two_general.ini": "data/bunny/two_general.ini",
    "scenes/bunny_mesh.elastic": "data/bunny/model/mesh.elastic",
    "scenes/bunny_mesh-soft.elastic": "data/bunny/model/mesh-soft.elastic",
    "scenes/cube_selfcon_mprgp.ini": "data/cube/selfcon_mprgp.ini",
    "scenes/dino_cubes_decoupled.ini": "data/dino/cubes_decoupled.ini",
    "scenes/dino_cubes_general.ini": "data/dino/cubes_general.ini",
    "scenes/dino_mesh.elastic": "data/dino/model/mesh.elastic",
    "scenes/dino_mesh_hard.elastic": "data/dino/model/mesh_hard.elastic",
    "scenes/dino_two_ica_1303.ini": "data/dino/two_ica_1303.ini",
    "scenes/dino_two_mprgp_1303.ini": "data/dino/two_mprgp_1303.ini",
    "scenes/dino_two_mprgp_9381.ini": "data/dino/two_mprgp_9381.ini",
    "scenes/dino_two_mprgp_20044.ini": "data/dino/two_mprgp_20044.ini",
    "scenes/dragon_mesh.elastic": "data/dragon/model/mesh.elastic",
    "scenes/dragon_mesh_soft.elastic": "data/dragon/model/mesh_soft.elastic",
    "scenes/dragon_plane.ini": "data/dragon/plane.ini",
    "scenes/dragon_stair2.ini": "data/dragon/stair2.ini",
    "scenes/longcube_mprgp.ini": "data/longcube/mprgp.ini",
}

#: raw files the figure tables are converted from
RAW = {
    "mprgp_objective": "script/data/mprgp.txt",      # Fig. 8: MPRGP objective per iteration
    "cg_objective": "script/data/cg.txt",            # Fig. 8: CG objective per iteration
    "decoupled_time": "script/data/dec_solving_time.txt",  # Fig. 6: seconds per frame, decoupled J
    "coupled_time": "script/data/gen_solving_time.txt",    # Fig. 6: seconds per frame, general J
    "mprgp_ica_log": "script/data/ica_mprgp.txt",    # Figs. 10-11: test log of MPRGP vs ICA
}


class DataError(Exception):
    """Bad or missing input data (exit status 2)."""


# ---------------------------------------------------------------- conversion (pure functions)

def number_list(text: str, where: str) -> List[float]:
    """A comma- and/or newline-separated list of numbers (the authors' .txt series)."""
    values = []
    for k, token in enumerate(t.strip() for t in re.split(r"[,\n]", text)):
        if not token:
            continue
        try:
            values.append(float(token))
        except ValueError:
            raise DataError(f"{where}: value {k + 1}: expected a number, got '{token}'") from None
    if not values:
        raise DataError(f"{where}: no numbers")
    return values


def columns_csv(header: List[str], series: List[List[float]], index_name: str) -> str:
    """CSV with an index column 0..N-1 and one column per series (empty cells past a series' end)."""
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow([index_name] + header)
    for i in range(max(len(s) for s in series)):
        w.writerow([i] + [repr(s[i]) if i < len(s) else "" for s in series])
    return out.getvalue()


#: one line of the MPRGP-vs-ICA log -> (output column, type)
LOG_FIELDS = [
    (r"^A\.rows\(\) = (\S+)", "dofs", int),
    (r"^J\.rows\(\) = (\S+)", "rows_decoupled", int),
    (r"^A\.nonZeros\(\) = (\S+)", "a_nonzeros", int),
    (r"^J\.nonZeros\(\) = (\S+)", "j_nonzeros", int),
    (r"power iter: (\S+)", "power_iterations", int),
    (r"mprgp with precond cg steps: (\S+)", "mprgp_cg_steps", int),
    (r"mprgp with precond exp steps: (\S+)", "mprgp_expansion_steps", int),
    (r"mprgp with precond prop steps: (\S+)", "mprgp_proportioning_steps", int),
    (r"mprgp with precond total iter: (\S+)", "mprgp_iterations", int),
    (r"mprgp with precond residual: (\S+)", "mprgp_residual", float),
    (r"mprgp with precond constraints: (\S+)", "mprgp_active_rows", int),
    (r"mprgp with con solving time: (\S+)", "mprgp_time_s", float),
    (r"ica with con solving time: (\S+)", "ica_time_s", float),
    (r"ica with con iterations: (\S+)", "ica_iterations", int),
    (r"ica with con residual: (\S+)", "ica_residual", float),
]
FIG11_COLUMNS = ["snapshot"] + [name for _, name, _ in LOG_FIELDS]


def parse_mprgp_ica_log(text: str, where: str) -> List[Dict[str, object]]:
    """One record per QP of the authors' MPRGP-vs-ICA test log (a path line opens a record)."""
    records: List[Dict[str, object]] = []
    for number, line in enumerate(text.splitlines(), 1):
        line = line.strip()
        m = re.search(r"/([^/]+)/QP/[^/]+$", line)
        if m:
            records.append({"snapshot": m.group(1)})
            continue
        for pattern, name, kind in LOG_FIELDS:
            f = re.search(pattern, line)
            if f:
                if not records:
                    raise DataError(f"{where}: line {number}: '{name}' before the first QP path line")
                try:
                    records[-1][name] = kind(f.group(1))
                except ValueError:
                    raise DataError(f"{where}: line {number}: {name}: expected a number, got '{f.group(1)}'") from None
                break
    if not records:
        raise DataError(f"{where}: no QP record (a line ending in /<run>/QP/<file>)")
    for r in records:
        missing = [c for c in FIG11_COLUMNS if c not in r]
        if missing:
            raise DataError(f"{where}: record {r['snapshot']}: missing {', '.join(missing)}")
    return records


def records_csv(columns: List[str], records: List[Dict[str, object]]) -> str:
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(columns)
    for r in records:
        w.writerow([repr(r[c]) if isinstance(r[c], float) else r[c] for c in columns])
    return out.getvalue()


def convert_figures(read) -> Dict[str, str]:
    """The figure tables from the raw files; `read(key)` returns the text of RAW[key]."""
    fig8 = columns_csv(["mprgp_objective", "cg_objective"],
                       [number_list(read("mprgp_objective"), RAW["mprgp_objective"]),
                        number_list(read("cg_objective"), RAW["cg_objective"])], "iteration")
    fig6 = columns_csv(["decoupled_time_s", "coupled_time_s"],
                       [number_list(read("decoupled_time"), RAW["decoupled_time"]),
                        number_list(read("coupled_time"), RAW["coupled_time"])], "frame")
    fig11 = records_csv(FIG11_COLUMNS, parse_mprgp_ica_log(read("mprgp_ica_log"), RAW["mprgp_ica_log"]))
    return {"figures/fig8_objective_history.csv": fig8, "figures/fig6_decoupling_time.csv": fig6,
            "figures/fig11_mprgp_vs_ica.csv": fig11}


# ---------------------------------------------------------------- fetching and verifying

def read_manifest(path: str) -> Dict[str, str]:
    """path in the tree -> SHA-256 hex."""
    out = {}
    with open(path) as f:
        for number, line in enumerate(f, 1):
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            parts = line.split()
            if len(parts) != 2 or not re.fullmatch(r"[0-9a-f]{64}", parts[0]):
                raise DataError(f"{path}: line {number}: expected '<sha256> <path>', got '{line}'")
            out[parts[1]] = parts[0]
    return out


def sha256(path: str) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def tree_root(folder: str) -> str:
    """The folder holding data/ and script/ (the tree itself or its single top-level folder)."""
    if os.path.isdir(os.path.join(folder, "data")) and os.path.isdir(os.path.join(folder, "script")):
        return folder
    subs = [os.path.join(folder, d) for d in sorted(os.listdir(folder)) if os.path.isdir(os.path.join(folder, d))]
    for s in subs:
        if os.path.isdir(os.path.join(s, "data")) and os.path.isdir(os.path.join(s, "script")):
            return s
    raise DataError(f"{folder}: not the authors' tree (no data/ and script/ folders in it or in a subfolder)")


def fetch(source: str, scratch: str, say) -> Tuple[str, str]:
    """Makes the tree available under scratch; returns (tree root, what it was)."""
    if source.endswith((".tar.gz", ".tgz")) and os.path.isfile(source):
        say(f"unpacking {source}")
        with tarfile.open(source, "r:gz") as t:
            for member in t.getmembers():
                if member.name.startswith("/") or ".." in member.name.split("/"):
                    raise DataError(f"{source}: unsafe member path '{member.name}'")
            t.extractall(scratch)
        return tree_root(scratch), f"tarball {os.path.abspath(source)}"
    if os.path.isdir(source):
        return tree_root(source), f"folder {os.path.abspath(source)}"
    if re.match(r"^(https?|git|ssh)://|^git@|\.git$", source):
        target = os.path.join(scratch, "MPRGP")
        say(f"cloning {source} at {COMMIT}")
        try:
            subprocess.run(["git", "clone", "--quiet", source, target], check=True)
            subprocess.run(["git", "-C", target, "checkout", "--quiet", COMMIT], check=True)
        except (OSError, subprocess.CalledProcessError) as e:
            raise DataError(f"{source}: git clone/checkout of {COMMIT} failed ({e}); without a network, "
                            f"set PAPER_DATA_SOURCE to a local copy (folder or .tar.gz)") from None
        return target, f"git {source} at {COMMIT}"
    raise DataError(f"{source}: not a .tar.gz file, a folder or a git URL")


def verify(root: str, manifest: Dict[str, str], needed: List[str]) -> None:
    missing = [p for p in needed if not os.path.isfile(os.path.join(root, p))]
    if missing:
        raise DataError(f"{root}: the authors' tree lacks {len(missing)} file(s) contactbench uses: "
                        + ", ".join(missing))
    unlisted = [p for p in needed if p not in manifest]
    if unlisted:
        raise DataError(f"{MANIFEST}: no hash for {', '.join(unlisted)}")
    bad = [p for p in needed if sha256(os.path.join(root, p)) != manifest[p]]
    if bad:
        raise DataError(f"{root}: SHA-256 differs from {os.path.basename(MANIFEST)} (not commit {COMMIT}?): "
                        + ", ".join(bad))


def extract(root: str, dest: str, source_desc: str, manifest: Dict[str, str]) -> Dict[str, str]:
    """Writes DEST atomically (a sibling temporary folder, then a rename); returns output -> source."""
    parent = os.path.dirname(os.path.abspath(dest)) or "."
    os.makedirs(parent, exist_ok=True)
    tmp = tempfile.mkdtemp(prefix=".paper-data-", dir=parent)
    try:
        made = {}
        for out, src in COPIED.items():
            os.makedirs(os.path.dirname(os.path.join(tmp, out)), exist_ok=True)
            shutil.copyfile(os.path.join(root, src), os.path.join(tmp, out))
            made[out] = src

        def read(key: str) -> str:
            with open(os.path.join(root, RAW[key]), encoding="utf-8", errors="replace") as f:
                return f.read()

        os.makedirs(os.path.join(tmp, "figures"), exist_ok=True)
        for out, text in convert_figures(read).items():
            with open(os.path.join(tmp, out), "w") as f:
                f.write(text)
            made[out] = "converted by plots/paper_data.py"
        used = sorted(set(COPIED.values()) | set(RAW.values()))
        with open(os.path.join(tmp, "paper-data.json"), "w") as f:
            json.dump({"source": source_desc, "commit": COMMIT, "files": {p: manifest[p] for p in used},
                       "outputs": made}, f, indent=1)
        if os.path.isdir(dest):
            old = dest + ".old"
            shutil.rmtree(old, ignore_errors=True)
            os.rename(dest, old)
            os.rename(tmp, dest)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.rename(tmp, dest)
        return made
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def default_dest() -> str:
    cache = os.environ.get("CB_CACHE") or os.path.join(os.path.expanduser("~"), ".cache", "contactbench")
    return os.path.join(cache, "paper-data")


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--source", default=os.environ.get("PAPER_DATA_SOURCE") or DEFAULT_SOURCE,
                        help=f"git URL, folder or .tar.gz of the tree (default {DEFAULT_SOURCE} at {COMMIT})")
    parser.add_argument("--dest", default=default_dest(), help="output folder (default $CB_CACHE/paper-data)")
    args = parser.parse_args(argv)

    def say(msg: str) -> None:
        print(f"paper-data: {msg}", file=sys.stderr, flush=True)

    try:
        manifest = read_manifest(MANIFEST)
        with tempfile.TemporaryDirectory(prefix="cb-paper-data-") as scratch:
            root, desc = fetch(args.source, scratch, say)
            needed = sorted(set(COPIED.values()) | set(RAW.values()))
            verify(root, manifest, needed)
            say(f"{len(needed)} files verified against {os.path.relpath(MANIFEST)} (SHA-256)")
            made = extract(root, args.dest, desc, manifest)
    except DataError as e:
        print(f"paper-data: error: {e}", file=sys.stderr)
        return 2
    say(f"wrote {len(made)} files into {args.dest} (meshes/, scenes/, figures/ converted from script/data/)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
