"""Figures a document quotes from a run, tied to the commit and command that measured them.

A measured block in a Markdown document carries one visible line of this form:

    Measured at <commit> with `<command>`.
    Measured at <commit> with `<command>` (covers solvers/mprgp/mprgp.cpp solvers/linalg/a_product.*).

It is stale when the code it describes changed after <commit>: by default the solver, problem and
simulator sources (DEFAULT_COVERS), or the paths it names after "covers". A stale block fails the
docs-check unless its paragraph says openly that the figures were not measured again ("Not
re-measured: <what changed, what to run>") or says why they still stand ("Still stands: <commit>
<reason>"). A reason vouches for the code up to the newest commit it names: a change after that
commit makes the block stale again, so a reason written for one change cannot cover the next. A commit this clone does not
have (a shallow clone, a tarball) is reported too: the claim cannot be checked there.
"""
import fnmatch
import os
import re
import subprocess
from typing import List, Optional, Sequence

#: what a measured figure describes unless its line names other paths
DEFAULT_COVERS = ("solvers/", "problems/", "sim/")
#: the subject prefix of a commit that only moves files (and rewrites the paths naming them)
PURE_MOVE = "Pure move:"
MEASURED_RE = re.compile(r"[Mm]easured at ([0-9a-f]{7,40}) with `([^`]+)`(?:\s*\(covers ([^)]*)\))?")
NOT_REMEASURED_RE = re.compile(r"Not re-measured:\s*\S")
STILL_STANDS_RE = re.compile(r"Still stands:\s*\S")
HASH_RE = re.compile(r"\b[0-9a-f]{7,40}\b")


def git(repo: str, *args: str) -> Optional[str]:
    """stdout of `git ARGS` in REPO, or None when git or the repository is not there."""
    try:
        done = subprocess.run(["git", *args], cwd=repo, capture_output=True, text=True)
    except OSError:
        return None
    return done.stdout if done.returncode == 0 else None


def changed_since(repo: str, commit: str, covers: Sequence[str]) -> Optional[List[str]]:
    """Files under COVERS (folders end in '/', else globs) changed between COMMIT and HEAD; None
    when COMMIT is not in this clone."""
    if git(repo, "cat-file", "-e", commit + "^{commit}") is None:
        return None
    # Every commit since, but the pure moves: a commit whose subject starts with PURE_MOVE moves files
    # and rewrites the paths that name them, which changes no figure.
    out = git(repo, "log", "--format=%x01%s", "--name-only", commit + "..HEAD")
    if out is None:
        return None
    touched = set()
    for entry in out.split("\x01")[1:]:
        subject, _, names = entry.partition("\n")
        if not subject.startswith(PURE_MOVE):
            touched.update(name for name in names.splitlines() if name.strip())
    changed = []
    for path in sorted(touched):
        for cover in covers:
            if (cover.endswith("/") and path.startswith(cover)) or fnmatch.fnmatch(path, cover):
                changed.append(path)
                break
    return changed


def paragraphs(lines: List[str]):
    """(index of the first line, the lines joined by spaces) of each blank-line-delimited paragraph:
    a measured line wrapped over two or more lines is read whole."""
    i = 0
    while i < len(lines):
        if not lines[i].strip():
            i += 1
            continue
        j = i
        while j + 1 < len(lines) and lines[j + 1].strip():
            j += 1
        yield i, " ".join(line.strip() for line in lines[i:j + 1])
        i = j + 1


def line_of(lines: List[str], first: int, text: str, offset: int) -> int:
    """The index of the line of the paragraph starting at FIRST that holds character OFFSET of TEXT
    (the paragraph's lines joined by single spaces)."""
    seen = 0
    index = first
    while index < len(lines) and lines[index].strip():
        seen += len(lines[index].strip()) + 1
        if offset < seen:
            return index
        index += 1
    return index - 1


def newest_named(repo: str, commit: str, text: str) -> str:
    """The newest of COMMIT and the commits TEXT's "Still stands:" reasons name (a name that is not a
    commit of this clone, or not on COMMIT's line of history, is passed over)."""
    newest = commit
    for reason in re.split(r"Still stands:", text)[1:]:
        for name in HASH_RE.findall(reason):
            if git(repo, "merge-base", "--is-ancestor", newest, name) is not None:
                newest = name
    return newest


def check_measured(repo: str, rel: str, lines: List[str]) -> List[str]:
    """One problem per stale or uncheckable measured block of document REL."""
    problems: List[str] = []
    for first, text in paragraphs(lines):
        for m in MEASURED_RE.finditer(text):
            commit, command = m.group(1), m.group(2)
            covers = m.group(3).split() if m.group(3) else list(DEFAULT_COVERS)
            changed = changed_since(repo, commit, covers)
            i = line_of(lines, first, text, m.start())
            where = f"{rel}:{i + 1}"
            if changed is None:
                problems.append(f"{where}: figures measured at {commit}, a commit this clone does not have "
                                f"(cannot tell whether `{command}` would still give them)")
            elif changed and not NOT_REMEASURED_RE.search(text):
                vouched = newest_named(repo, commit, text) if STILL_STANDS_RE.search(text) else commit
                if vouched != commit:
                    changed = changed_since(repo, vouched, covers)
                if not changed:
                    continue
                shown = ", ".join(changed[:3]) + (f" and {len(changed) - 3} more" if len(changed) > 3 else "")
                said = f" (said to still stand at {vouched})" if vouched != commit else ""
                problems.append(f"{where}: figures measured at {commit} with `{command}`{said} predate changes to "
                                f"{shown}: re-measure, or say why they still stand (\"Still stands: <commit> ...\") or that they were not "
                                f"re-measured (\"Not re-measured: ...\")")
    return problems


def is_git_checkout(repo: str) -> bool:
    return os.path.exists(os.path.join(repo, ".git")) and git(repo, "rev-parse", "HEAD") is not None
