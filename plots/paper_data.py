#!/usr/bin/python3
"""Fetch the paper authors' public repository, verify it and extract the data contactbench uses.

    /usr/bin/python3 -m plots.paper_data [--source SRC] [--dest DIR]          (`make paper-data`)

SRC is a git URL (default: the authors' repository simba518/MPRGP, checked out at commit 57fdd2c),
a local folder holding that tree, or a .tar.gz of it. Every file used is checked against the
SHA-256 and size in the manifest committed beside this script (paper_data.sha256), on the bytes
copied; a missing or altered file is an error that names it, and nothing is written. The source is
untrusted: plots/safe_extract.py reads only the files listed, refuses links, special files and
setuid bits anywhere in the tree, and stops a compression bomb at its header. DIR (default
$CB_CACHE/paper-data, CB_CACHE defaulting to ~/.cache/contactbench) is written whole or not at all
(plots/atomic_folder.py): an existing DIR is replaced only if it holds nothing but an earlier run's
files. It receives:

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
import signal
import subprocess
import sys
import tempfile
from typing import Dict, List, Optional, Set, Tuple

try:  # run as `python3 -m plots.paper_data`, or imported with plots/ on the path (the tests)
    from plots.atomic_folder import AtomicFolder, FolderError
    from plots.safe_extract import Copied, Expected, Refused, check_folder, copy_from_folder, \
        copy_from_tarball, shown
except ImportError:  # run as plots/paper_data.py
    from atomic_folder import AtomicFolder, FolderError  # type: ignore
    from safe_extract import Copied, Expected, Refused, check_folder, copy_from_folder, \
        copy_from_tarball, shown  # type: ignore

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

RECORD = "paper-data.json"
GIT_URL = re.compile(r"^(https?|git|ssh|file)://|^git@|\.git$")


def read_manifest(path: str) -> Dict[str, Expected]:
    """path in the tree -> (SHA-256 hex, size in bytes)."""
    out = {}
    with open(path) as f:
        for number, line in enumerate(f, 1):
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            parts = line.split()
            if len(parts) != 3 or not re.fullmatch(r"[0-9a-f]{64}", parts[0]) or not parts[1].isdigit():
                raise DataError(f"{path}: line {number}: expected '<sha256> <bytes> <path>', got '{line}'")
            out[parts[2]] = Expected(parts[0], int(parts[1]))
    return out


def sha256(path: str) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def needed_files() -> List[str]:
    return sorted(set(COPIED.values()) | set(RAW.values()))


def tree_root(folder: str) -> str:
    """The folder holding data/ and script/ (the tree itself or one of its folders, not a link)."""
    def holds_tree(d: str) -> bool:
        return os.path.isdir(os.path.join(d, "data")) and os.path.isdir(os.path.join(d, "script"))

    if holds_tree(folder):
        return folder
    for name in sorted(os.listdir(folder)):
        sub = os.path.join(folder, name)
        if holds_tree(sub):
            if os.path.islink(sub):
                raise DataError(f"{shown(sub)}: the tree's top folder is a symbolic link (refused: only "
                                "regular files and folders are accepted)")
            return sub
    raise DataError(f"{folder}: not the authors' tree (no data/ and script/ folders in it or in a subfolder)")


def previous_outputs(dest: str) -> Optional[Set[str]]:
    """The files an earlier run recorded in DEST/paper-data.json (with the record), or None."""
    record = os.path.join(dest, RECORD)
    try:
        if os.path.islink(dest) or not os.path.isfile(record) or os.path.islink(record) \
                or os.path.getsize(record) > (1 << 20):
            return None
        with open(record) as f:
            outputs = json.load(f).get("outputs")
    except (OSError, ValueError, AttributeError):
        return None
    if not isinstance(outputs, dict):
        return None
    files = {RECORD}
    for rel in outputs:
        parts = rel.split("/") if isinstance(rel, str) else [""]
        if rel.startswith("/") or any(p in ("", ".", "..") for p in parts):
            return None
        files.add(rel)
    return files


def git_checkout(source: str, scratch: str, say) -> str:
    """Clones source into scratch and checks out COMMIT; returns the clone's folder."""
    target = os.path.join(scratch, "MPRGP")
    say(f"cloning {shown(source)} at {COMMIT}")
    env = dict(os.environ, GIT_TERMINAL_PROMPT="0")  # a wrong URL fails instead of asking for a password
    try:
        # `--` keeps the URL an argument; ext:: (a URL that runs a command) stays refused
        subprocess.run(["git", "-c", "protocol.ext.allow=never", "clone", "--quiet", "--no-checkout", "--",
                        source, target], check=True, env=env, stdin=subprocess.DEVNULL)
        subprocess.run(["git", "-C", target, "checkout", "--quiet", COMMIT, "--"], check=True, env=env,
                       stdin=subprocess.DEVNULL)
    except (OSError, subprocess.CalledProcessError) as e:
        raise DataError(f"{shown(source)}: git clone/checkout of {COMMIT} failed ({e}); without a network, "
                        f"set PAPER_DATA_SOURCE to a local copy (folder or .tar.gz)") from None
    return target


def copy_tree(source: str, wanted: Dict[str, Expected], open_sink, say) -> Tuple[Copied, str]:
    """Copies the wanted files of the source (tarball, folder or git URL); returns them and what it was."""
    if source.startswith("-"):
        raise DataError(f"{shown(source)}: a source cannot start with '-'")
    if os.path.isdir(source):
        root = tree_root(source)
        check_folder(root)
        return copy_from_folder(root, wanted, open_sink), f"folder {os.path.abspath(source)}"
    if os.path.lexists(source):
        if not os.path.isfile(source):
            raise DataError(f"{shown(source)}: not a regular file, a folder or a git URL")
        say(f"reading {source}")
        return copy_from_tarball(source, wanted, open_sink), f"tarball {os.path.abspath(source)}"
    if GIT_URL.search(source):
        with tempfile.TemporaryDirectory(prefix="cb-paper-data-") as scratch:
            root = git_checkout(source, scratch, say)
            check_folder(root, skip={".git"})
            return copy_from_folder(root, wanted, open_sink), f"git {source} at {COMMIT}"
    raise DataError(f"{shown(source)}: no such file or folder, and not a git URL")


class KeptBytes(io.BytesIO):
    """An in-memory sink whose bytes outlive its `with` block."""

    def close(self) -> None:
        self.kept = self.getvalue()
        super().close()


def fetch_and_extract(source: str, dest: str, say) -> Dict[str, str]:
    """Copies, verifies and converts into DEST (whole or not at all); returns output -> source."""
    manifest = read_manifest(MANIFEST)
    needed = needed_files()
    unlisted = [p for p in needed if p not in manifest]
    if unlisted:
        raise DataError(f"{MANIFEST}: no hash for {', '.join(unlisted)}")
    wanted = {p: manifest[p] for p in needed}
    output_of = {src: out for out, src in COPIED.items()}
    raw: Dict[str, KeptBytes] = {}

    with AtomicFolder(dest, previous_outputs(dest)) as folder:
        for leftover in folder.stale:
            say(f"{leftover}: left by an interrupted run (not removed: remove it if it is not yours)")

        def open_sink(rel: str):
            if rel in output_of:
                return folder.create(output_of[rel])
            raw[rel] = KeptBytes()
            return raw[rel]

        copied, desc = copy_tree(source, wanted, open_sink, say)
        missing = [p for p in needed if p not in copied.found]
        if missing:
            raise DataError(f"{shown(source)}: the authors' tree lacks {len(missing)} file(s) contactbench "
                            "uses: " + ", ".join(missing))
        if copied.differing:
            raise DataError(f"{shown(source)}: SHA-256 differs from {os.path.basename(MANIFEST)} (not commit "
                            f"{COMMIT}?): " + ", ".join(copied.differing))
        say(f"{len(needed)} files verified against {os.path.relpath(MANIFEST)} (SHA-256 of the bytes copied)")

        made = dict(COPIED)
        figures = convert_figures(lambda key: raw[RAW[key]].kept.decode("utf-8", errors="replace"))
        for out, text in figures.items():
            with folder.create(out) as f:
                f.write(text.encode())
            made[out] = "converted by plots/paper_data.py"
        with folder.create(RECORD) as f:
            f.write(json.dumps({"source": desc, "commit": COMMIT,
                                "files": {p: manifest[p].sha256 for p in needed},
                                "outputs": made}, indent=1).encode())
        folder.commit()
        for note in folder.notes:
            say(note)
    return made


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
        print(f"paper-data: {shown(msg)}", file=sys.stderr, flush=True)  # one line, whatever the paths hold

    try:
        made = fetch_and_extract(args.source, args.dest, say)
    except (DataError, Refused, FolderError) as e:
        print(f"paper-data: error: {shown(str(e))}", file=sys.stderr)
        return 2
    except OSError as e:  # the destination or the source could not be read or written
        print(f"paper-data: error: {shown(str(e.filename or args.dest))}: {e.strerror or e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"paper-data: interrupted; {shown(args.dest)} left as it was", file=sys.stderr)
        return 130
    say(f"wrote {len(made)} files into {args.dest} (meshes/, scenes/, figures/ converted from script/data/)")
    return 0


def _interrupt(signum, frame) -> None:
    raise KeyboardInterrupt  # a SIGTERM cleans up like Ctrl-C


if __name__ == "__main__":
    signal.signal(signal.SIGTERM, _interrupt)
    sys.exit(main())
