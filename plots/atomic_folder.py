"""A folder written whole or not at all, and never at the cost of files this program did not write.

Files are created in a fresh temporary sibling of the destination (`.NAME-XXXXXXXX`), which replaces
the destination by rename once everything in it is complete. An existing destination is replaced
only when it is empty or holds nothing but the files a previous run recorded (`previous`); those
files, and nothing else, are removed afterwards. A failure or an interruption removes the
temporary sibling and any parent folder made for it, so nothing is left behind.

    with AtomicFolder(dest, previous={"a.txt"}) as out:
        with out.create("sub/b.txt") as f:
            f.write(b"...")
        out.commit()
"""
import os
import shutil
import stat
import tempfile
from typing import BinaryIO, List, Optional, Set, Tuple


class FolderError(Exception):
    """The destination cannot be written or replaced safely (exit status 2); one line, naming it."""


def listing(folder: str) -> Tuple[Set[str], Set[str], List[str]]:
    """(files, folders, others) under folder, as relative paths; links are never followed, and
    anything that is neither a regular file nor a folder (a link, a FIFO, a device) is in others."""
    files: Set[str] = set()
    dirs: Set[str] = set()
    others: List[str] = []
    for top, subdirs, names in os.walk(folder, followlinks=False):
        rel_top = os.path.relpath(top, folder)
        for name in subdirs + names:
            rel = os.path.normpath(os.path.join(rel_top, name))
            mode = os.lstat(os.path.join(top, name)).st_mode
            if stat.S_ISDIR(mode):
                dirs.add(rel)
            elif stat.S_ISREG(mode):
                files.add(rel)
            else:
                others.append(rel)
    return files, dirs, sorted(others)


def parent_folders(files: Set[str]) -> Set[str]:
    out = set()
    for rel in files:
        head = os.path.dirname(rel)
        while head:
            out.add(head)
            head = os.path.dirname(head)
    return out


def check_replaceable(dest: str, previous: Optional[Set[str]]) -> None:
    """Refuses a destination that is not a folder, or holds anything outside `previous`."""
    if not os.path.lexists(dest):
        return
    if os.path.islink(dest):
        raise FolderError(f"{dest}: is a symbolic link; name the folder it points to, or another folder")
    if not os.path.isdir(dest):
        raise FolderError(f"{dest}: exists and is not a folder")
    files, dirs, others = listing(dest)
    if not (files or dirs or others):
        return
    if previous is None:
        raise FolderError(f"{dest}: exists, is not empty and holds no record of an earlier run; "
                          "refusing to replace it (move it away or name another folder)")
    foreign = sorted(others + sorted(files - previous) + sorted(dirs - parent_folders(previous)))
    if foreign:
        more = f" and {len(foreign) - 1} more" if len(foreign) > 1 else ""
        raise FolderError(f"{dest}: holds '{foreign[0]}'{more}, which the earlier run did not write; "
                          "refusing to replace it (move it away or name another folder)")


def _open_dir_nofollow(root_fd: int, parts: List[str]) -> int:
    fd = os.dup(root_fd)
    for part in parts:
        try:
            nxt = os.open(part, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW | os.O_CLOEXEC, dir_fd=fd)
        finally:
            os.close(fd)
        fd = nxt
    return fd


def remove_recorded(folder: str, files: Set[str]) -> bool:
    """Removes the listed files and their then-empty folders, then folder itself if empty; never
    follows a link and never removes anything else. True when folder is gone."""
    root = os.open(folder, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW | os.O_CLOEXEC)
    try:
        for rel in sorted(files):
            parts = rel.split("/")
            try:
                fd = _open_dir_nofollow(root, parts[:-1])
            except OSError:
                continue  # its folder is gone or was replaced by something else: leave it be
            try:
                if stat.S_ISREG(os.lstat(parts[-1], dir_fd=fd).st_mode):
                    os.unlink(parts[-1], dir_fd=fd)
            except OSError:
                pass
            finally:
                os.close(fd)
        for rel in sorted(parent_folders(files), key=lambda d: -d.count("/")):
            try:
                os.rmdir(rel, dir_fd=root)  # only if empty: never a file that was not recorded
            except OSError:
                pass
    finally:
        os.close(root)
    try:
        os.rmdir(folder)
        return True
    except OSError:
        return False


def _current_umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


class AtomicFolder:
    def __init__(self, dest: str, previous: Optional[Set[str]] = None):
        self.dest = os.path.abspath(dest)
        self.previous = previous
        self.notes: List[str] = []  # things the caller should tell the user (leftovers)
        check_replaceable(self.dest, previous)
        self.parent = os.path.dirname(self.dest)
        self.prefix = "." + os.path.basename(self.dest) + "-"
        self.made_parents: List[str] = []
        self.done = False
        self.tmp = ""
        self._make_parents()
        try:
            self.stale = sorted(os.path.join(self.parent, n) for n in os.listdir(self.parent)
                                if n.startswith(self.prefix))
            self.tmp = tempfile.mkdtemp(prefix=self.prefix, dir=self.parent)
            os.chmod(self.tmp, 0o777 & ~_current_umask())
        except BaseException:
            self.discard()  # the parents made just now
            raise

    def _make_parents(self) -> None:
        missing = []
        head = self.parent
        while not os.path.lexists(head):
            missing.append(head)
            head = os.path.dirname(head)
        if not os.path.isdir(head):
            raise FolderError(f"{self.dest}: cannot be made: {head} is not a folder")
        for folder in reversed(missing):
            try:
                os.mkdir(folder)
            except FileExistsError:
                continue
            except OSError as e:
                self.discard()
                raise FolderError(f"{self.dest}: cannot make {folder}: {e.strerror}") from None
            self.made_parents.append(folder)

    def create(self, rel: str) -> BinaryIO:
        """A new file at rel inside the temporary folder (its subfolders made as needed)."""
        parts = rel.split("/")
        if not rel or rel.startswith("/") or any(p in ("", ".", "..") for p in parts):
            raise FolderError(f"{self.dest}: refusing to write '{rel}' (not a plain relative path)")
        head = self.tmp
        for part in parts[:-1]:
            head = os.path.join(head, part)
            if not os.path.isdir(head):  # the temporary folder is ours alone: no link can be in it
                os.mkdir(head, 0o777)
        fd = os.open(os.path.join(self.tmp, rel),
                     os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | os.O_CLOEXEC, 0o666)
        return os.fdopen(fd, "wb")

    def commit(self) -> None:
        """Puts the temporary folder in place of the destination."""
        check_replaceable(self.dest, self.previous)  # again: it may have changed meanwhile
        if not os.path.lexists(self.dest) or not os.listdir(self.dest):
            # rename replaces an empty folder atomically, and fails on anything else that appeared
            self._rename(self.tmp, self.dest)
        else:
            old = tempfile.mkdtemp(prefix=self.prefix + "old-", dir=self.parent)
            try:
                self._rename(self.dest, old)
            except BaseException:
                os.rmdir(old)
                raise
            try:
                self._rename(self.tmp, self.dest)
            except BaseException:
                os.rename(old, self.dest)
                raise
            if not remove_recorded(old, self.previous or set()):
                self.notes.append(f"{old}: the earlier {os.path.basename(self.dest)} was left here: it holds "
                                  "files the earlier run did not write")
        self.done = True

    def _rename(self, src: str, dst: str) -> None:
        try:
            os.rename(src, dst)
        except OSError as e:
            raise FolderError(f"{dst}: cannot be replaced ({e.strerror})") from None

    def discard(self) -> None:
        if not self.done and self.tmp and os.path.isdir(self.tmp):
            shutil.rmtree(self.tmp, ignore_errors=True)  # made by mkdtemp: everything in it is ours
        for folder in reversed(self.made_parents):
            try:
                os.rmdir(folder)
            except OSError:
                break
        self.made_parents = []

    def __enter__(self) -> "AtomicFolder":
        return self

    def __exit__(self, *exc) -> None:
        if not self.done:
            self.discard()
