"""Copies a known set of files out of an untrusted .tar.gz or folder, checking them as they are copied.

The caller names the files it wants (path in the tree -> SHA-256 and size) and where each one goes
(`open_sink(path)` returns a writable binary file). Nothing else is ever written: the archive is
read as a stream and never unpacked. The rules, the same for an archive and a folder:

- the tree holds only regular files and folders: a symbolic link, a device node, a FIFO, a file
  with a setuid/setgid bit is refused anywhere in it; in an archive also a hard link, a sparse
  file, a setuid/setgid folder, an absolute name or a '..' in a name;
- a wanted file's size is compared with the expected one before any of its bytes are copied, and
  at most that many bytes are copied;
- an archive's members may declare at most MAX_ARCHIVE_BYTES in all and be at most MAX_MEMBERS,
  checked on each header before its data is read (a gzip bomb stops at its header);
- the SHA-256 is computed on the bytes written to the sink, so a file swapped during the copy
  cannot pass.

Python's tarfile.data_filter (3.11.4 and later; Debian 12's 3.11.2 lacks it) is applied to every
member too when it exists; the checks here are stricter and come first.
"""
import hashlib
import os
import re
import stat
import tarfile
import zlib
from typing import BinaryIO, Callable, Dict, List, NamedTuple, Optional, Set

MAX_ARCHIVE_BYTES = 1 << 30  # the offline tarball of the authors' tree at 57fdd2c declares 33 MB
MAX_MEMBERS = 100_000        # it has 443
MAX_TRAILING_BYTES = 1 << 20  # after the tar's end marker: padding (GNU tar pads to 10 KiB)
MAX_META_BYTES = 1 << 20      # a pax or GNU long-name header, which tarfile reads whole into memory
CHUNK = 1 << 16


class Refused(Exception):
    """The source breaks a rule above, or cannot be read; the message is one line naming it."""


class Expected(NamedTuple):
    sha256: str
    size: int


class Copied(NamedTuple):
    """What a copy found: the wanted files it copied, and those whose SHA-256 differs."""
    found: Set[str]
    differing: List[str]


def shown(text: str) -> str:
    """A name as one printable line: control characters (a newline in a member name) escaped."""
    return re.sub(r"[\x00-\x1f\x7f]", lambda m: f"\\x{ord(m.group()):02x}", text)


def _copy_counted(read: Callable[[int], bytes], size: int, sink: BinaryIO, rel: str) -> Optional[str]:
    """Copies at most size bytes, hashing what is written; None if the source has more or fewer."""
    h = hashlib.sha256()
    left = size
    while left > 0:
        block = read(min(CHUNK, left))
        if not block:
            return None
        try:
            sink.write(block)
        except OSError as e:
            raise Refused(f"cannot write {rel} ({e.strerror})") from None
        h.update(block)
        left -= len(block)
    if read(1):
        return None
    return h.hexdigest()

# ---------------------------------------------------------------- .tar.gz

def _member_problem(m: tarfile.TarInfo) -> Optional[str]:
    """Why a member breaks the rules, or None."""
    if m.name.startswith("/"):
        return "absolute name"
    if ".." in m.name.split("/"):
        return "'..' in its name"
    if m.issym():
        return f"symbolic link to '{shown(m.linkname)}'"
    if m.islnk():
        return f"hard link to '{shown(m.linkname)}'"
    if m.ischr() or m.isblk():
        return "device node"
    if m.isfifo():
        return "FIFO"
    if m.issparse():
        return "sparse file"
    if not (m.isreg() or m.isdir()):
        return f"unsupported member type {m.type!r}"
    if m.mode & (stat.S_ISUID | stat.S_ISGID):
        return f"setuid/setgid bit (mode {m.mode:o})"
    floor = getattr(tarfile, "data_filter", None)
    if floor is not None:
        try:
            floor(m, os.path.join(os.sep, "safe-extract-check"))
        except tarfile.FilterError as e:
            return f"refused by tarfile.data_filter ({e})"
    return None


def _tree_path(parts: List[str], wanted: Dict[str, Expected], top: Optional[str]):
    """(top folder, path in the tree) when the member is a wanted file, else None. The first wanted
    member fixes the top folder ('' for a tree at the archive's root); later ones must share it."""
    rel = "/".join(parts)
    if rel in wanted and top in (None, ""):
        return "", rel
    rel = "/".join(parts[1:])
    if len(parts) > 1 and rel in wanted and top in (None, parts[0]):
        return parts[0], rel
    return None


class _MetaTooLarge(Exception):
    def __init__(self, info: tarfile.TarInfo):
        super().__init__(f"a {info.type.decode('latin-1')!r} header of {info.size} bytes, more than the "
                         f"{MAX_META_BYTES} accepted; refused before reading it")


class _BoundedTarInfo(tarfile.TarInfo):
    """tarfile reads a pax or GNU long-name header whole into memory before it returns the member it
    describes: its declared size is checked first (a hook on tarfile's per-header step)."""

    def _proc_member(self, tarfile_):
        if self.type in (tarfile.XHDTYPE, tarfile.XGLTYPE, tarfile.SOLARIS_XHDTYPE, tarfile.GNUTYPE_LONGNAME,
                         tarfile.GNUTYPE_LONGLINK) and self.size > MAX_META_BYTES:
            raise _MetaTooLarge(self)
        return super()._proc_member(tarfile_)


def _open_archive(path: str) -> BinaryIO:
    return open(path, "rb")


def copy_from_tarball(archive: str, wanted: Dict[str, Expected], open_sink: Callable[[str], BinaryIO],
                      fileobj: Optional[BinaryIO] = None) -> Copied:
    """Streams the .tar.gz once; wanted files go to their sinks. Raises Refused (one line, naming the
    archive and the member) on the first member that breaks a rule; other differences are returned."""
    raw = fileobj if fileobj is not None else _open_archive(archive)
    try:
        if raw.read(2) != b"\x1f\x8b":
            raise Refused(f"{archive}: not a gzip file (expected a .tar.gz)")
        raw.seek(0)
        return _copy_members(archive, raw, wanted, open_sink)
    finally:
        if fileobj is None:
            raw.close()


def _copy_members(archive, raw, wanted, open_sink) -> Copied:
    found: Set[str] = set()
    differing: List[str] = []
    top: Optional[str] = None
    declared = 0
    count = 0
    last = "(its first header)"
    damaged = (tarfile.TarError, EOFError, zlib.error, OSError)
    try:
        tar = tarfile.open(fileobj=raw, mode="r:gz", tarinfo=_BoundedTarInfo)
    except _MetaTooLarge as e:
        raise Refused(f"{archive}: {e} (at {last})") from None
    except damaged as e:
        raise Refused(f"{archive}: damaged or truncated archive ({shown(str(e))}) at {last}") from None
    with tar:
        members = iter(tar)
        while True:
            try:
                m = next(members)
            except StopIteration:
                break
            except _MetaTooLarge as e:
                raise Refused(f"{archive}: {e} (after member '{last}')") from None
            except damaged as e:
                raise Refused(f"{archive}: damaged or truncated archive ({shown(str(e))}) after member "
                              f"'{last}'") from None
            where = f"{archive}: member '{shown(m.name)}'"
            count += 1
            if count > MAX_MEMBERS:
                raise Refused(f"{where}: more than {MAX_MEMBERS} members; refused before reading further")
            problem = _member_problem(m)
            if problem:
                raise Refused(f"{where}: {problem} (only regular files and folders are accepted)")
            if m.size < 0:  # a pax "size" record may say anything; tarfile would seek backwards
                raise Refused(f"{where}: a negative size ({m.size} bytes) in its header; refused before "
                              "reading further")
            declared += m.size
            if declared > MAX_ARCHIVE_BYTES:
                raise Refused(f"{where}: the members declare {declared} bytes so far, more than the "
                              f"{MAX_ARCHIVE_BYTES} accepted (a compression bomb?); refused before unpacking it")
            last = shown(m.name)
            parts = [p for p in m.name.split("/") if p not in ("", ".")]
            hit = _tree_path(parts, wanted, top) if m.isreg() else None
            if hit is None:
                continue
            top, rel = hit
            if rel in found:
                raise Refused(f"{where}: a second member for {rel}")
            found.add(rel)
            expected = wanted[rel]
            if m.size != expected.size:
                raise Refused(f"{where}: {m.size} bytes where {expected.size} are expected; "
                              "refused before unpacking it")
            data = tar.extractfile(m)

            def read(n: int, data=data, where=where) -> bytes:
                try:
                    return data.read(n)
                except damaged as e:
                    raise Refused(f"{where}: damaged or truncated archive ({shown(str(e))})") from None

            with open_sink(rel) as sink:
                digest = _copy_counted(read, m.size, sink, rel)
            if digest is None:
                raise Refused(f"{where}: damaged or truncated archive (fewer bytes than its header says)")
            if digest != expected.sha256:
                differing.append(rel)
        _read_to_the_end(archive, tar.fileobj, last)
    return Copied(found, differing)


def _read_to_the_end(archive: str, stream, last: str) -> None:
    """Reads what follows the tar's end marker (a few KB of padding) so that gzip checks its CRC
    and length: a cut or corrupted archive is refused even when the files it was read for are whole."""
    left = MAX_TRAILING_BYTES
    try:
        while True:
            block = stream.read(min(CHUNK, left + 1))
            if not block:
                return
            left -= len(block)
            if left < 0:
                raise Refused(f"{archive}: more than {MAX_TRAILING_BYTES} bytes after the end of the tar archive "
                              f"(after member '{last}')")
    except (tarfile.TarError, EOFError, zlib.error, OSError) as e:
        raise Refused(f"{archive}: damaged or truncated archive ({shown(str(e))}) after member '{last}'") from None


# ---------------------------------------------------------------- folder

def _kind(mode: int) -> str:
    if stat.S_ISLNK(mode):
        return "symbolic link"
    if stat.S_ISFIFO(mode):
        return "FIFO"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "device node"
    if stat.S_ISSOCK(mode):
        return "socket"
    return "special file"


def check_folder(folder: str, skip: Set[str] = frozenset()) -> None:
    """Refuses a tree holding anything but regular files and folders, or a file with a setuid/setgid
    bit (top-level names in skip, such as '.git', are not walked). A file with several hard links is
    accepted: it is only read, and a folder cannot tell which of its names came first."""
    for top, dirs, names in os.walk(folder, followlinks=False, onerror=_walk_error):
        if top == folder:
            dirs[:] = [d for d in dirs if d not in skip]
        for name in dirs + names:
            path = os.path.join(top, name)
            mode = os.lstat(path).st_mode
            if not (stat.S_ISREG(mode) or stat.S_ISDIR(mode)):
                raise Refused(f"{path}: {_kind(mode)} (only regular files and folders are accepted)")
            if stat.S_ISREG(mode) and mode & (stat.S_ISUID | stat.S_ISGID):  # a setgid folder is common
                raise Refused(f"{path}: setuid/setgid bit (mode {stat.S_IMODE(mode):o}; "
                              "only plain files are accepted)")


def _walk_error(e: OSError) -> None:
    raise Refused(f"{e.filename}: cannot be read ({e.strerror})")


def copy_from_folder(root: str, wanted: Dict[str, Expected], open_sink: Callable[[str], BinaryIO]) -> Copied:
    """Copies the wanted files under root (already passed through check_folder), opening each path
    component without following links, so that a link put in place meanwhile is refused too."""
    found: Set[str] = set()
    differing: List[str] = []
    root_fd = os.open(root, os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
    try:
        for rel in sorted(wanted):
            fd = _open_file_nofollow(root, root_fd, rel)
            if fd is None:
                continue
            try:
                st = os.fstat(fd)
                expected = wanted[rel]
                if st.st_size != expected.size:
                    raise Refused(f"{os.path.join(root, rel)}: {st.st_size} bytes where {expected.size} "
                                  "are expected; refused before copying it")
                found.add(rel)
                with open(fd, "rb", closefd=False) as src, open_sink(rel) as sink:
                    digest = _copy_counted(src.read, expected.size, sink, rel)
                if digest is None:
                    differing.append(f"{rel} (changed while copied)")
                elif digest != expected.sha256:
                    differing.append(rel)
            finally:
                os.close(fd)
    finally:
        os.close(root_fd)
    return Copied(found, differing)


def _open_file_nofollow(root: str, root_fd: int, rel: str) -> Optional[int]:
    """An fd of the regular file root/rel, None if it is missing; Refused for anything else."""
    parts = rel.split("/")
    fd = os.dup(root_fd)
    try:
        for i, part in enumerate(parts):
            path = os.path.join(root, *parts[:i + 1])
            try:
                st = os.lstat(part, dir_fd=fd)
            except FileNotFoundError:
                return None
            last = i == len(parts) - 1
            if not (stat.S_ISDIR(st.st_mode) or stat.S_ISREG(st.st_mode)):
                raise Refused(f"{path}: {_kind(st.st_mode)} (only regular files and folders are accepted)")
            if last != stat.S_ISREG(st.st_mode):
                return None  # a folder where the file should be, or a file where a folder should be
            if last and st.st_mode & (stat.S_ISUID | stat.S_ISGID):
                raise Refused(f"{path}: setuid/setgid bit (mode {stat.S_IMODE(st.st_mode):o}; "
                              "only plain files are accepted)")
            flags = os.O_RDONLY | os.O_NOFOLLOW | os.O_CLOEXEC | (os.O_NONBLOCK if last else os.O_DIRECTORY)
            try:
                nxt = os.open(part, flags, dir_fd=fd)
            except OSError as e:
                raise Refused(f"{path}: cannot be opened safely ({e.strerror})") from None
            os.close(fd)
            fd = nxt
            now = os.fstat(fd)
            if (now.st_dev, now.st_ino) != (st.st_dev, st.st_ino):
                raise Refused(f"{path}: replaced while being opened")
        result, fd = fd, -1
        return result
    finally:
        if fd >= 0:
            os.close(fd)
