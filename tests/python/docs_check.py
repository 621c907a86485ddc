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
Also reported: any file outside .ci/ that mentions the shared folder beside the checkout (the
string is assembled below so that this file does not mention it itself).

Exit status 0 when clean, 1 with one line per problem: FILE:LINE: what is wrong.
"""
import os
import re
import subprocess
import sys
from typing import Dict, List, Optional, Tuple

#: the folder beside the checkout that only CI may name
SHARED = ".." + "/" + "shared"
#: Markdown files the code writes into results folders (outputs, not documents of the repository)
GENERATED_OUTPUTS = {"report.md", "stability.md", "profiles.md", "table1.md"}
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
    return problems


def check(repo: str) -> List[str]:
    cache: Dict[str, List[str]] = {}
    problems: List[str] = []
    for rel in repo_files(repo):
        if is_text(rel) and rel not in EXAMPLES:
            problems += check_file(repo, rel, cache)
    return problems


def main(argv: List[str]) -> int:
    repo = os.path.abspath(argv[1] if len(argv) > 1 else os.path.join(os.path.dirname(__file__), "..", ".."))
    problems = check(repo)
    for p in problems:
        print(p)
    print(f"docs-check: {len(problems)} problem(s) in {repo}", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
