#!/usr/bin/python3
"""docs-check: every document the repository cites exists, and every section it cites is a heading.

Usage: /usr/bin/python3 tests/python/docs_check.py [REPO]      (`make docs-check`)

What counts as a citation, in any text file git knows (tracked or untracked, not ignored):
- a Markdown document name, with or without a folder: `ALGORITHMS.md`, `scenes/README.md`;
- a section after it: `ALGORITHMS.md §3`, `DESIGN.md "Metrics"`, `ALGORITHMS.md §3 "Power method"`,
  and a bare section number later in the same file (it refers to the document cited last, as in
  a table);
- a relative Markdown link `[text](path#anchor)` in a .md file (the path must exist).
Resolution: a name with a folder is relative to the citing file, then to the repository root; a bare
name is looked up beside the citing file, at the root, then in docs/. `§n` resolves to a heading
numbered n (a heading "3. ..."); a quoted name to a heading that contains it.
Also checked: every repository path a document or a comment cites (`harness/runner.cpp`,
`solvers/methods/template_solver.{hpp,cpp}`, `harness/cmd_*.cpp`: a path under a top-level source folder,
braces expanded, globs matching at least one file) exists, relative to the root or to the citing
file; and, when a built contactbench is at hand ($CB_CONTACTBENCH or build/bin/contactbench),
the counts the code prints match what the documents say (check_counts below).
Also checked, in a git checkout: a document's "Measured at <commit> with `<command>`" line is not
older than a change to the code it describes, unless its paragraph says why the figures still stand
(stale_figures.py).
Also reported: any file outside .ci/ that mentions the shared folder beside the checkout (the
string is assembled below so that this file does not mention it itself).

Exit status 0 when clean, 1 with one line per problem: FILE:LINE: what is wrong.
"""
import glob
import os
import re
import subprocess
import sys
from typing import Dict, List, Optional, Tuple

import stale_figures

#: the folder beside the checkout that only CI may name
SHARED = ".." + "/" + "shared"
#: Markdown files the code writes into results folders (outputs, not documents of the repository)
GENERATED_OUTPUTS = {"report.md", "stability.md", "profiles.md", "table1.md", "friction_chains.md"}
TEXT_SUFFIXES = (".cpp", ".hpp", ".h", ".py", ".md", ".txt", ".json", ".cmake", ".sh", ".yml", ".yaml",
                 ".clang-format", ".clang-tidy")
TEXT_NAMES = {"Makefile", "CMakeLists.txt", "run"}
#: files whose citations are made-up examples on purpose (the tests of this script)
EXAMPLES = {"tests/python/test_docs_check.py"}

DOC_RE = re.compile(r"(?<![\w/.-])((?:[\w.-]+/)*[\w.-]*[A-Za-z0-9_]\.md)\b")
# after a document name: optional " §n" and/or quoted section names ("A", "B")
SECTION_TAIL_RE = re.compile(r'^(?:\s*§(\d+))?((?:,?\s+"[^"\n]{1,60}")*)')
QUOTED_RE = re.compile(r'"([^"\n]{1,60})"')
BARE_SECTION_RE = re.compile(r"(?<![\w.])§(\d+)")
LINK_RE = re.compile(r"\]\(([^)\s]+)\)")
HEADING_RE = re.compile(r"^#{1,6}\s+(.*?)\s*#*\s*$")
#: the repository's top-level folders: a path that starts with one of them is a file citation
SOURCE_FOLDERS = ("solvers", "problems", "harness", "sim", "plots", "tools", "tests", "scenes", "suites",
                  "examples", "cmake", "docs")
# A repository path (`harness/runner.cpp`, `solvers/methods/template_solver.{hpp,cpp}`, `harness/cmd_*.cpp`,
# `solvers/mprgp/mprgp.*`, `solvers/linalg/a_product` for the pair); not inside a longer path or a URL, not a
# placeholder filled in later (`cmd_<name>.cpp`, `corpus_$t`).
PATH_RE = re.compile(r"(?<![\w/.$~-])((?:" + "|".join(SOURCE_FOLDERS) + r")/[\w./*{},+-]*[\w*}])(?![<$\w])")


def is_placeholder(path: str) -> bool:
    """A name made up for an example: `scenes/x.json`, `scenes/SCENE.json`, `two_dinos_K.json`,
    `solvers/my_solver.hpp` (a one-letter stem, an upper-case word, or my_...)."""
    stem = os.path.basename(path).split(".")[0]
    return (len(stem) == 1 and stem.islower()) or stem.startswith("my_") or \
        any(word.isupper() for word in stem.split("_"))


def repo_files(repo: str) -> List[str]:
    """Files git knows in REPO (tracked and untracked-not-ignored); every file when git is absent."""
    try:
        out = subprocess.run(["git", "ls-files", "-co", "--exclude-standard"], cwd=repo, check=True,
                             capture_output=True, text=True).stdout
        files = [f for f in out.splitlines() if f]
    except (OSError, subprocess.CalledProcessError):
        files = []
        for root, dirs, names in os.walk(repo):
            dirs[:] = [d for d in dirs if not d.startswith(".git") and not d.startswith("build")]
            files += [os.path.relpath(os.path.join(root, n), repo) for n in names]
    return sorted(f for f in files if os.path.isfile(os.path.join(repo, f)))


def is_text(path: str) -> bool:
    base = os.path.basename(path)
    return base in TEXT_NAMES or base.endswith(TEXT_SUFFIXES)


def headings(path: str, cache: Dict[str, List[str]]) -> List[str]:
    if path not in cache:
        with open(path, encoding="utf-8", errors="replace") as f:
            cache[path] = [m.group(1) for m in (HEADING_RE.match(line) for line in f) if m]
    return cache[path]


def has_numbered(heads: List[str], n: str) -> bool:
    return any(re.match(r"^(?:§\s*)?" + n + r"(?:[.):]|\s|$)", h) for h in heads)


def has_named(heads: List[str], name: str) -> bool:
    return any(name.lower() in h.lower() for h in heads)


def resolve(repo: str, citing: str, ref: str) -> Optional[str]:
    """The repository path REF (cited in CITING) names, or None."""
    here = os.path.dirname(citing)
    candidates = [os.path.join(here, ref), ref]
    if "/" not in ref:
        candidates.append(os.path.join("docs", ref))
    for c in candidates:
        full = os.path.normpath(os.path.join(repo, c))
        if os.path.exists(full):
            return full
    return None


def skip_reference(ref: str) -> bool:
    first = ref.split("/")[0]
    return (os.path.basename(ref) in GENERATED_OUTPUTS or first == "results"
            or (first.isupper() and "/" in ref)          # placeholders: DIR/x.md, RESULTS/x.md
            or ref.startswith(("http:", "https:")))


def expand_braces(path: str) -> List[str]:
    """`a.{hpp,cpp}` -> [`a.hpp`, `a.cpp`] (one level of braces, as the documents write them)."""
    m = re.search(r"\{([^{}]*)\}", path)
    if not m:
        return [path]
    return [x for alt in m.group(1).split(",") for x in expand_braces(path[:m.start()] + alt + path[m.end():])]


def path_exists(repo: str, citing: str, path: str) -> bool:
    """PATH (braces expanded, globs matching something) exists at the root or beside CITING."""
    for candidate in expand_braces(path):
        found = False
        for base in (repo, os.path.join(repo, os.path.dirname(citing))):
            full = os.path.normpath(os.path.join(base, candidate))
            # a stem names its file pair: `solvers/linalg/a_product` -> a_product.hpp, a_product.cpp
            if ("*" in candidate and glob.glob(full)) or os.path.exists(full) or glob.glob(glob.escape(full) + ".*"):
                found = True
                break
        if not found:
            return False
    return True


def prose_lines(rel: str, lines: List[str]) -> List[bool]:
    """Which lines of a file are prose: every line of a document; in code, comment lines (C++ //,
    shell/CMake/Python #) and the lines of Python docstrings (string data is not a citation)."""
    if rel.endswith(".md") or os.path.basename(rel) in TEXT_NAMES:
        return [True] * len(lines)
    out, in_docstring = [], False
    for line in lines:
        stripped = line.strip()
        if rel.endswith((".cpp", ".hpp", ".h")):
            out.append(stripped.startswith(("//", "*", "/*")))
            continue
        quotes = stripped.count('"' * 3) + stripped.count("'" * 3)
        out.append(in_docstring or quotes > 0 or stripped.startswith("#"))
        if quotes % 2 == 1:
            in_docstring = not in_docstring
    return out


def check_paths(repo: str, rel: str, lines: List[str]) -> List[str]:
    """Every repository path cited in a document, or in a comment of a code file, exists."""
    problems: List[str] = []
    marker = " //" if rel.endswith((".cpp", ".hpp", ".h")) else " #"
    for i, (line, prose) in enumerate(zip(lines, prose_lines(rel, lines)), 1):
        if not prose:  # code: only its trailing comment is prose
            line = line[line.index(marker):] if marker in line else ""
        for m in PATH_RE.finditer(line):
            path = m.group(1).rstrip(".,")
            if path.endswith(".md") or is_placeholder(path):
                continue  # documents and their sections: checked above; examples' placeholders
            if not path_exists(repo, rel, path):
                problems.append(f"{rel}:{i}: cites {path}, which is not in the repository")
    return problems


def check_file(repo: str, rel: str, cache: Dict[str, List[str]]) -> List[str]:
    problems: List[str] = []
    with open(os.path.join(repo, rel), encoding="utf-8", errors="replace") as f:
        lines = f.read().split("\n")
    if SHARED in "\n".join(lines) and not rel.startswith(".ci/"):
        for i, line in enumerate(lines, 1):
            if SHARED in line:
                problems.append(f"{rel}:{i}: mentions {SHARED} (only .ci/ may: nothing may depend on it)")
    last_doc: Optional[Tuple[str, str]] = None  # (name as cited, resolved path)
    for i, line in enumerate(lines, 1):
        covered = []  # spans of sections already checked with their document
        for m in DOC_RE.finditer(line):
            ref = m.group(1)
            if skip_reference(ref):
                continue
            target = resolve(repo, rel, ref)
            tail = SECTION_TAIL_RE.match(line[m.end():])
            covered.append((m.end(), m.end() + tail.end()))
            if target is None:
                problems.append(f"{rel}:{i}: cites {ref}, which is not in the repository")
                last_doc = None
                continue
            last_doc = (ref, target)
            heads = headings(target, cache) if target.endswith(".md") else []
            if tail.group(1) and not has_numbered(heads, tail.group(1)):
                problems.append(f"{rel}:{i}: cites {ref} §{tail.group(1)}, which has no heading numbered {tail.group(1)}")
            for name in QUOTED_RE.findall(tail.group(2) or ""):
                if not has_named(heads, name):
                    problems.append(f"{rel}:{i}: cites {ref} \"{name}\", which has no such heading")
        for m in BARE_SECTION_RE.finditer(line):
            if any(a <= m.start() < b for a, b in covered):
                continue
            if last_doc is None:
                problems.append(f"{rel}:{i}: cites §{m.group(1)} without naming a document before it")
            elif not has_numbered(headings(last_doc[1], cache), m.group(1)):
                problems.append(f"{rel}:{i}: cites §{m.group(1)} of {last_doc[0]}, which has no heading numbered {m.group(1)}")
        if rel.endswith(".md"):
            for m in LINK_RE.finditer(line):
                target = m.group(1).split("#")[0]
                if not target or re.match(r"^[a-z]+:", target) or skip_reference(target):
                    continue
                if not os.path.exists(os.path.normpath(os.path.join(repo, os.path.dirname(rel), target))):
                    problems.append(f"{rel}:{i}: links to {target}, which is not in the repository")
    return problems + check_paths(repo, rel, lines)


#: "42 seeded cases in 15 families": the stress suite as `contactbench stress --list` prints it
STRESS_CLAIM_RE = re.compile(r"\b(\d+) seeded\s+cases\s+in\s+(\d+)\s+families")
#: a row of README.md's solver table: | `name` | what | spec |
SOLVER_ROW_RE = re.compile(r"^\|\s*`([a-z0-9-]+)`\s*\|(.*)$")


def find_binary(repo: str) -> Optional[str]:
    """$CB_CONTACTBENCH, else REPO/build/bin/contactbench, when it exists."""
    for candidate in (os.environ.get("CB_CONTACTBENCH"), os.path.join(repo, "build", "bin", "contactbench")):
        if candidate and os.path.isfile(candidate) and os.access(candidate, os.X_OK):
            return candidate
    return None


def printed(binary: str, *args: str) -> List[str]:
    """The lines `binary args...` prints (RuntimeError naming the command when it fails)."""
    result = subprocess.run([binary, *args], capture_output=True, text=True, timeout=120)
    if result.returncode != 0:
        raise RuntimeError(f"{binary} {' '.join(args)} failed (exit {result.returncode}): {result.stderr.strip()}")
    return [line for line in result.stdout.split("\n") if line.strip()]


def check_counts(repo: str, binary: str) -> List[str]:
    """The counts the code prints, against what the documents claim: the stress suite's cases and
    families (`stress --list`: one tab-separated line per case, family second), and the solvers
    (`solvers`: one line per registered solver, name first) against README.md's solver table
    (every registered solver is named in README.md; every row of the table is a registered solver
    or marked optional, a peer this build may lack)."""
    problems: List[str] = []
    cases = [line.split("\t") for line in printed(binary, "stress", "--list")]
    n_cases, n_families = len(cases), len({c[1] for c in cases if len(c) > 1})
    solvers = [line.split()[0] for line in printed(binary, "solvers")]
    for rel in repo_files(repo):
        if not rel.endswith(".md") or rel in EXAMPLES:
            continue
        with open(os.path.join(repo, rel), encoding="utf-8", errors="replace") as f:
            text = f.read()
        for m in STRESS_CLAIM_RE.finditer(text):
            line = text.count("\n", 0, m.start()) + 1
            if (int(m.group(1)), int(m.group(2))) != (n_cases, n_families):
                problems.append(f"{rel}:{line}: says {m.group(1)} seeded cases in {m.group(2)} families; "
                                f"`contactbench stress --list` prints {n_cases} cases in {n_families} families")
    readme = os.path.join(repo, "README.md")
    if os.path.isfile(readme):
        with open(readme, encoding="utf-8") as f:
            lines = f.read().split("\n")
        text = "\n".join(lines)
        for name in solvers:
            if "`" + name + "`" not in text:
                problems.append(f"README.md: does not name the registered solver `{name}`")
        for i, line in enumerate(lines, 1):
            m = SOLVER_ROW_RE.match(line)
            if m and m.group(1) not in solvers and "optional" not in m.group(2):
                problems.append(f"README.md:{i}: the solver table lists `{m.group(1)}`, which is not registered "
                                f"(`contactbench solvers`) and not marked optional")
    return problems


def check(repo: str, binary: Optional[str] = None) -> List[str]:
    """Every problem found in REPO; the counts only with a contactbench binary (find_binary)."""
    cache: Dict[str, List[str]] = {}
    problems: List[str] = []
    dated = stale_figures.is_git_checkout(repo)
    if not dated:
        print("docs-check: not a git checkout: measured figures are not checked against later changes",
              file=sys.stderr)
    for rel in repo_files(repo):
        if is_text(rel) and rel not in EXAMPLES:
            problems += check_file(repo, rel, cache)
            if dated and rel.endswith(".md"):
                with open(os.path.join(repo, rel), encoding="utf-8", errors="replace") as f:
                    problems += stale_figures.check_measured(repo, rel, f.read().split("\n"))
    if binary:
        problems += check_counts(repo, binary)
    return problems


def main(argv: List[str]) -> int:
    repo = os.path.abspath(argv[1] if len(argv) > 1 else os.path.join(os.path.dirname(__file__), "..", ".."))
    binary = find_binary(repo)
    if binary is None:
        print("docs-check: no contactbench binary ($CB_CONTACTBENCH or build/bin/contactbench): the counts the "
              "code prints are not checked", file=sys.stderr)
    problems = check(repo, binary)
    for p in problems:
        print(p)
    print(f"docs-check: {len(problems)} problem(s) in {repo}", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
