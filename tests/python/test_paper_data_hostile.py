"""Hostile sources for `make paper-data` (plots/paper_data.py, plots/safe_extract.py, plots/atomic_folder.py):
archives, folders and git repositories built here to write outside the destination, plant links,
devices or setuid files, or exhaust the disk. Each must end in exit status 2 with a one-line
message naming the archive and the member, nothing written anywhere (the whole scratch folder is
compared before and after, including the victim file outside) and no temporary folder left.

Every hostile case runs everywhere; the authors' genuine tree is test_paper_data_genuine.py (it
runs only when PAPER_DATA_SOURCE names a local copy of it, and is reported skipped otherwise)."""
import contextlib
import gzip
import hashlib
import io
import os
import re
import shutil
import stat
import subprocess
import sys
import tarfile
import tempfile
import unittest
from unittest import mock

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, ROOT)  # plots is a package of the repository root
from plots import paper_data, safe_extract  # noqa: E402

FIXTURES = os.path.join(HERE, "fixtures", "paper_data")
MESH = "data/dino/model/mesh_1303_4014.abq"  # a file the fetcher copies
MiB = 1 << 20


def snapshot(folder, skip=None):
    """Every entry under folder (but skip): kind, mode, size, content hash or link target."""
    out = {}
    for top, dirs, names in os.walk(folder):
        if top == skip:
            dirs[:], names = [], []
        for name in dirs + names:
            path = os.path.join(top, name)
            st = os.lstat(path)
            if stat.S_ISLNK(st.st_mode):
                what = "link " + os.readlink(path)
            elif stat.S_ISREG(st.st_mode):
                with open(path, "rb") as f:
                    what = hashlib.sha256(f.read()).hexdigest()
            else:
                what = ""
            out[os.path.relpath(path, folder)] = (stat.S_IFMT(st.st_mode), stat.S_IMODE(st.st_mode), st.st_size, what)
    return out


def temp_leftovers():
    return {n for n in os.listdir(tempfile.gettempdir()) if n.startswith("cb-paper-data-")}


class CountingFile:
    """A read-only file that counts the compressed bytes tarfile pulls from it."""

    def __init__(self, path):
        self.f = open(path, "rb")
        self.bytes_read = 0

    def read(self, n=-1):
        data = self.f.read(n)
        self.bytes_read += len(data)
        return data

    def seek(self, *a):
        return self.f.seek(*a)

    def tell(self):
        return self.f.tell()

    def close(self):
        self.f.close()


class Hostile(unittest.TestCase):
    """A made-up tree (every used file) with its own manifest, a victim file outside everything."""

    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.root = self.tmp.name
        self.tree = os.path.join(self.root, "src", "MPRGP")
        self.files = {}
        for out, src in paper_data.COPIED.items():
            self.files[src] = f"made-up content of {out}\n".encode()
        for key, src in paper_data.RAW.items():
            with open(os.path.join(FIXTURES, os.path.basename(src)), "rb") as f:
                self.files[src] = f.read()
        for rel, data in self.files.items():
            self.write_tree(rel, data)
        self.manifest = os.path.join(self.root, "manifest.sha256")
        with open(self.manifest, "w") as f:
            for rel in sorted(self.files):
                f.write(f"{hashlib.sha256(self.files[rel]).hexdigest()} {len(self.files[rel])} {rel}\n")
        self.saved_manifest = paper_data.MANIFEST
        paper_data.MANIFEST = self.manifest
        self.outside = os.path.join(self.root, "outside")
        os.mkdir(self.outside)
        self.victim = os.path.join(self.outside, "victim.txt")
        with open(self.victim, "w") as f:
            f.write("the victim's own text\n")
        self.dest = os.path.join(self.root, "cache", "paper-data")
        self.temp_before = temp_leftovers()

    def tearDown(self):
        paper_data.MANIFEST = self.saved_manifest
        self.tmp.cleanup()

    def write_tree(self, rel, data):
        path = os.path.join(self.tree, rel)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "wb") as f:
            f.write(data)

    # ------------------------------------------------------------ building archives

    def genuine_members(self):
        """(TarInfo, bytes) for the made-up tree, folders first, under MPRGP/."""
        members = []
        folders = set()
        for rel in self.files:
            parts = ("MPRGP/" + rel).split("/")[:-1]
            folders |= {"/".join(parts[:i]) for i in range(1, len(parts) + 1)}
        for name in sorted(folders):
            info = tarfile.TarInfo(name)
            info.type, info.mode = tarfile.DIRTYPE, 0o755
            members.append((info, None))
        for rel in sorted(self.files):
            info = tarfile.TarInfo("MPRGP/" + rel)
            info.size, info.mode = len(self.files[rel]), 0o644
            members.append((info, self.files[rel]))
        return members

    def archive(self, members, name="hostile.tar.gz"):
        path = os.path.join(self.root, name)
        with tarfile.open(path, "w:gz", format=tarfile.GNU_FORMAT) as t:
            for info, data in members:
                t.addfile(info, io.BytesIO(data) if data is not None else None)
        return path

    @staticmethod
    def special(name, kind, **fields):
        info = tarfile.TarInfo(name)
        info.type = kind
        info.mode = fields.pop("mode", 0o644)
        for k, v in fields.items():
            setattr(info, k, v)
        return info, None

    def bomb(self, member, mib):
        """A .tar.gz of about mib KB whose member declares and holds mib MiB of zeros: gzip members
        of 1 MiB of zeros each, concatenated (a valid gzip file; tar and gzip -d read it whole)."""
        head = tarfile.TarInfo("MPRGP")
        head.type, head.mode = tarfile.DIRTYPE, 0o755
        info = tarfile.TarInfo(member)
        info.size, info.mode = mib * MiB, 0o644
        zeros = gzip.compress(bytes(MiB), 9)
        path = os.path.join(self.root, "bomb.tar.gz")
        with open(path, "wb") as f:
            f.write(gzip.compress(head.tobuf(format=tarfile.GNU_FORMAT) + info.tobuf(format=tarfile.GNU_FORMAT)))
            for _ in range(mib):
                f.write(zeros)
        return path

    # ------------------------------------------------------------ running

    def run_main(self, source, dest=None):
        err = io.StringIO()
        with contextlib.redirect_stderr(err):
            status = paper_data.main(["--source", source, "--dest", dest or self.dest])
        return status, err.getvalue()

    def assert_refused(self, source, message, dest=None, skip=None):
        """Exit 2, exactly this error line (a str, or a compiled pattern), nothing written or left
        (in the scratch folder but skip, a folder the test itself changes during the run)."""
        before = snapshot(self.root, skip)
        status, err = self.run_main(source, dest)
        self.assertEqual(status, 2, err)
        line = err.splitlines()[-1]
        if isinstance(message, str):
            self.assertEqual(line, f"paper-data: error: {message}")
        else:
            self.assertRegex(line, message)
        self.assertEqual(err.count("\n"), len(err.splitlines()))  # every message is one line
        self.assertNotIn("Traceback", err)
        self.assertEqual(snapshot(self.root, skip), before)  # the victim, the scratch and dest untouched
        self.assertEqual(temp_leftovers(), self.temp_before)
        return err

    def member_error(self, archive, member, problem):
        return f"{archive}: member '{member}': {problem} (only regular files and folders are accepted)"


class HostileArchives(Hostile):
    def test_the_made_up_archive_itself_is_accepted(self):
        status, err = self.run_main(self.archive(self.genuine_members()))
        self.assertEqual(status, 0, err)
        with open(os.path.join(self.dest, "meshes", "dino_1303_4014.abq"), "rb") as f:
            self.assertEqual(f.read(), self.files[MESH])

    def test_symlink_member_followed_by_a_file_of_the_same_name(self):
        link = self.special("MPRGP/" + MESH, tarfile.SYMTYPE, linkname=self.victim)
        members = [m for m in self.genuine_members() if m[0].name != "MPRGP/" + MESH]
        pwn = tarfile.TarInfo("MPRGP/" + MESH)
        pwn.size = 6
        archive = self.archive(members[:5] + [link, (pwn, b"pwned\n")] + members[5:])
        self.assert_refused(archive, self.member_error(archive, "MPRGP/" + MESH,
                                                       f"symbolic link to '{self.victim}'"))

    def test_hard_link_member_followed_by_a_file_of_the_same_name(self):
        link = self.special("MPRGP/x.txt", tarfile.LNKTYPE, linkname=self.victim)
        pwn = tarfile.TarInfo("MPRGP/x.txt")
        pwn.size = 6
        archive = self.archive(self.genuine_members()[:1] + [link, (pwn, b"pwned\n")])
        self.assert_refused(archive, self.member_error(archive, "MPRGP/x.txt", f"hard link to '{self.victim}'"))

    def test_symlinked_folder_member_then_files_through_it(self):
        link = self.special("MPRGP/data/dino", tarfile.SYMTYPE, linkname=self.outside)
        members = [m for m in self.genuine_members() if not m[0].name.startswith("MPRGP/data/dino")]
        evil = tarfile.TarInfo("MPRGP/data/dino/evil.txt")
        evil.size = 6
        archive = self.archive(members[:3] + [link, (evil, b"pwned\n")] + members[3:])
        self.assert_refused(archive, self.member_error(archive, "MPRGP/data/dino",
                                                       f"symbolic link to '{self.outside}'"))

    def test_top_folder_as_a_symlink(self):
        members = [m for m in self.genuine_members() if m[0].name != "MPRGP"]
        archive = self.archive([self.special("MPRGP", tarfile.SYMTYPE, linkname=self.outside)] + members)
        self.assert_refused(archive, self.member_error(archive, "MPRGP", f"symbolic link to '{self.outside}'"))

    def test_device_nodes_and_fifos(self):
        for kind, what in ((tarfile.CHRTYPE, "device node"), (tarfile.BLKTYPE, "device node"),
                           (tarfile.FIFOTYPE, "FIFO")):
            with self.subTest(what=what, kind=kind):
                node = self.special("MPRGP/script/node", kind, devmajor=1, devminor=3)
                archive = self.archive(self.genuine_members() + [node])
                self.assert_refused(archive, self.member_error(archive, "MPRGP/script/node", what))

    def test_setuid_and_setgid_files(self):
        for mode in (0o4755, 0o2755):
            with self.subTest(mode=oct(mode)):
                run = tarfile.TarInfo("MPRGP/script/run.sh")
                run.size, run.mode = 10, mode
                archive = self.archive(self.genuine_members() + [(run, b"#!/bin/sh\n")])
                self.assert_refused(archive, self.member_error(archive, "MPRGP/script/run.sh",
                                                               f"setuid/setgid bit (mode {mode:o})"))

    def test_dot_dot_and_absolute_names(self):
        for name, problem in (("MPRGP/../../outside/x.txt", "'..' in its name"),
                              (os.path.join(self.outside, "abs.txt"), "absolute name")):
            with self.subTest(name=name):
                evil = tarfile.TarInfo(name)
                evil.size = 6
                archive = self.archive(self.genuine_members() + [(evil, b"pwned\n")])
                self.assert_refused(archive, self.member_error(archive, name, problem))

    def test_a_newline_in_a_member_name_stays_on_one_line(self):
        link = self.special("MPRGP/a\nb", tarfile.SYMTYPE, linkname="/etc/passwd\nx")
        archive = self.archive(self.genuine_members() + [link])
        self.assert_refused(archive, self.member_error(archive, "MPRGP/a\\x0ab",
                                                       "symbolic link to '/etc/passwd\\x0ax'"))

    def test_gzip_bomb_stops_at_its_header(self):
        archive = self.bomb("MPRGP/bomb.bin", 1025)
        size = os.path.getsize(archive)
        self.assertLess(size, 1.2 * MiB)
        self.assert_refused(archive, f"{archive}: member 'MPRGP/bomb.bin': the members declare {1025 * MiB} bytes "
                                     f"so far, more than the {1 << 30} accepted (a compression bomb?); refused "
                                     "before unpacking it")
        counted = CountingFile(archive)
        with self.assertRaises(safe_extract.Refused):
            safe_extract.copy_from_tarball(archive, {}, None, fileobj=counted)
        counted.close()
        self.assertLess(counted.bytes_read, size / 4)  # stopped early: most of the bomb never read

    def test_oversized_wanted_member_is_refused_before_it_is_copied(self):
        archive = self.bomb("MPRGP/" + MESH, 512)
        expected = len(self.files[MESH])
        self.assert_refused(archive, f"{archive}: member 'MPRGP/{MESH}': {512 * MiB} bytes where {expected} are "
                                     "expected; refused before unpacking it")
        counted = CountingFile(archive)
        wanted = paper_data.read_manifest(self.manifest)
        with self.assertRaises(safe_extract.Refused):
            safe_extract.copy_from_tarball(archive, wanted, None, fileobj=counted)
        counted.close()
        self.assertLess(counted.bytes_read, os.path.getsize(archive) / 4)

    def test_huge_pax_header_is_refused_before_it_is_read(self):
        members = self.genuine_members()
        pax = tarfile.TarInfo("././@PaxHeader")
        pax.type, pax.size = tarfile.XHDTYPE, 64 * MiB
        archive = os.path.join(self.root, "pax.tar.gz")
        with open(archive, "wb") as f:
            f.write(gzip.compress(b"".join(m.tobuf(format=tarfile.GNU_FORMAT) + (d or b"").ljust(
                -(-len(d or b"") // 512) * 512, b"\0") for m, d in members[:2]) + pax.tobuf(tarfile.USTAR_FORMAT)
                + bytes(MiB)))  # less than declared: reading it would end in "damaged or truncated"
        self.assert_refused(archive, f"{archive}: a 'x' header of {64 * MiB} bytes, more than the {MiB} accepted; "
                                     f"refused before reading it (after member '{members[1][0].name}')")

    def test_negative_pax_size_is_refused_at_its_member(self):
        # tarfile takes a pax "size" as given and seeks backwards by it: the archive read short and
        # the refusal said "tree lacks N files" instead of naming the member
        members = self.genuine_members()
        neg = tarfile.TarInfo("MPRGP/neg.bin")
        neg.pax_headers = {"size": "-512"}
        archive = os.path.join(self.root, "pax_negative.tar.gz")
        with tarfile.open(archive, "w:gz", format=tarfile.PAX_FORMAT) as t:
            t.addfile(neg, io.BytesIO(b""))
            for info, data in members:
                t.addfile(info, io.BytesIO(data) if data is not None else None)
        self.assert_refused(archive, f"{archive}: member 'MPRGP/neg.bin': a negative size (-512 bytes) in its "
                                     "header; refused before reading further")

    def test_too_many_members(self):
        with mock.patch.object(safe_extract, "MAX_MEMBERS", 20):
            archive = self.archive(self.genuine_members())
            self.assert_refused(archive, re.compile(r"member '[^']+': more than 20 members; refused before reading "
                                                    r"further$"))

    def test_a_second_member_for_a_wanted_file(self):
        again = tarfile.TarInfo("MPRGP/" + MESH)
        again.size = len(self.files[MESH])
        archive = self.archive(self.genuine_members() + [(again, self.files[MESH])])
        self.assert_refused(archive, f"{archive}: member 'MPRGP/{MESH}': a second member for {MESH}")

    def test_truncated_archive(self):
        whole = self.archive(self.genuine_members())
        with open(whole, "rb") as f:
            data = f.read()
        for cut in (len(data) // 2, 20, len(data) - 12):
            with self.subTest(cut=cut):
                archive = os.path.join(self.root, "truncated.tar.gz")
                with open(archive, "wb") as f:
                    f.write(data[:cut])
                self.assert_refused(archive, re.compile(r"^paper-data: error: " + re.escape(archive)
                                                        + r": (member '[^']+': )?damaged or truncated archive \("))

    def test_data_after_the_end_of_the_tar_is_bounded(self):
        plain = io.BytesIO()
        with tarfile.open(fileobj=plain, mode="w", format=tarfile.GNU_FORMAT) as t:
            for info, data in self.genuine_members():
                t.addfile(info, io.BytesIO(data) if data is not None else None)
        archive = os.path.join(self.root, "trailing.tar.gz")
        with open(archive, "wb") as f:
            f.write(gzip.compress(plain.getvalue() + bytes(2 * MiB)))
        self.assert_refused(archive, f"{archive}: more than {MiB} bytes after the end of the tar archive (after "
                                     f"member 'MPRGP/script/data/mprgp.txt')")

    def test_not_a_gzip_file(self):
        archive = os.path.join(self.root, "plain.tar.gz")
        with tarfile.open(archive, "w") as t:  # an uncompressed tar named .tar.gz
            t.add(self.tree, arcname="MPRGP")
        self.assert_refused(archive, f"{archive}: not a gzip file (expected a .tar.gz)")
        empty = os.path.join(self.root, "empty.tar.gz")
        open(empty, "w").close()
        self.assert_refused(empty, f"{empty}: not a gzip file (expected a .tar.gz)")

    def test_missing_and_odd_sources(self):
        missing = os.path.join(self.root, "nowhere.tar.gz")
        self.assert_refused(missing, f"{missing}: no such file or folder, and not a git URL")
        self.assert_refused("--upload-pack=touch x.git", "--upload-pack=touch x.git: a source cannot start with '-'")
        fifo = os.path.join(self.root, "fifo.tar.gz")
        os.mkfifo(fifo)
        self.assert_refused(fifo, f"{fifo}: not a regular file, a folder or a git URL")


class Destinations(Hostile):
    def test_destination_that_is_a_file(self):
        os.makedirs(os.path.dirname(self.dest))
        with open(self.dest, "w") as f:
            f.write("mine\n")
        self.assert_refused(self.archive(self.genuine_members()), f"{self.dest}: exists and is not a folder")

    def test_a_newline_in_the_destination_stays_on_one_line(self):
        dest = os.path.join(self.outside, "a\nb")
        with open(dest, "w") as f:
            f.write("mine\n")
        self.assert_refused(self.archive(self.genuine_members()),
                            f"{self.outside}/a\\x0ab: exists and is not a folder", dest=dest)

    def test_destination_below_a_file(self):
        dest = os.path.join(self.victim, "paper-data")
        self.assert_refused(self.archive(self.genuine_members()),
                            f"{dest}: cannot be made: {self.victim} is not a folder", dest=dest)

    def test_destination_that_is_a_symlink(self):
        os.makedirs(os.path.dirname(self.dest))
        os.symlink(self.outside, self.dest)
        self.assert_refused(self.archive(self.genuine_members()),
                            f"{self.dest}: is a symbolic link; name the folder it points to, or another folder")

    def test_a_folder_with_files_it_did_not_write_is_never_replaced(self):
        os.makedirs(self.dest)
        with open(os.path.join(self.dest, "notes.txt"), "w") as f:
            f.write("mine\n")
        self.assert_refused(self.archive(self.genuine_members()),
                            f"{self.dest}: exists, is not empty and holds no record of an earlier run; refusing to "
                            "replace it (move it away or name another folder)")
        archive = self.archive(self.genuine_members())
        os.remove(os.path.join(self.dest, "notes.txt"))
        self.assertEqual(self.run_main(archive)[0], 0)  # an empty folder is fine
        os.makedirs(os.path.join(self.dest, "meshes", "extra"))
        with open(os.path.join(self.dest, "meshes", "extra", "mine.obj"), "w") as f:
            f.write("mine\n")
        self.assert_refused(archive, f"{self.dest}: holds 'meshes/extra' and 1 more, which the earlier run did "
                                     "not write; refusing to replace it (move it away or name another folder)")

    def test_rerun_replaces_its_own_output_and_nothing_else(self):
        archive = self.archive(self.genuine_members())
        old = self.dest + ".old"
        os.makedirs(old)
        with open(os.path.join(old, "keep.txt"), "w") as f:
            f.write("mine\n")
        self.assertEqual(self.run_main(archive)[0], 0)
        self.write_tree(MESH, self.files[MESH])
        first = snapshot(self.dest)
        status, err = self.run_main(archive)
        self.assertEqual(status, 0, err)
        self.assertEqual(snapshot(self.dest), first)
        # the sibling DEST.old (not written by this command) is still there, and no temporary is left
        self.assertEqual(sorted(os.listdir(os.path.dirname(self.dest))), ["paper-data", "paper-data.old"])
        with open(os.path.join(old, "keep.txt")) as f:
            self.assertEqual(f.read(), "mine\n")

    def test_leftover_of_an_interrupted_run_is_named_not_removed(self):
        leftover = os.path.join(os.path.dirname(self.dest), ".paper-data-abcd1234")
        os.makedirs(leftover)
        status, err = self.run_main(self.archive(self.genuine_members()))
        self.assertEqual(status, 0, err)
        self.assertIn(f"paper-data: {leftover}: left by an interrupted run (not removed: remove it if it is not "
                      "yours)\n", err)
        self.assertTrue(os.path.isdir(leftover))

    def test_interrupt_leaves_nothing(self):
        archive = self.archive(self.genuine_members())
        before = snapshot(self.root)
        with mock.patch.object(paper_data, "convert_figures", side_effect=KeyboardInterrupt):
            status, err = self.run_main(archive)
        self.assertEqual(status, 130)
        self.assertEqual(err.splitlines()[-1], f"paper-data: interrupted; {self.dest} left as it was")
        self.assertEqual(snapshot(self.root), before)


class HostileFolders(Hostile):
    def test_the_made_up_folder_itself_is_accepted(self):
        status, err = self.run_main(os.path.dirname(self.tree))
        self.assertEqual(status, 0, err)

    def test_a_setgid_folder_and_a_hard_linked_file_are_accepted(self):
        os.chmod(os.path.join(self.tree, "data"), 0o2755)  # common for a shared group folder
        os.link(os.path.join(self.tree, MESH), os.path.join(self.root, "second-name.abq"))
        status, err = self.run_main(self.tree)
        self.assertEqual(status, 0, err)

    def test_symlinked_file(self):
        path = os.path.join(self.tree, MESH)
        os.remove(path)
        os.symlink(self.victim, path)
        self.assert_refused(self.tree, f"{path}: symbolic link (only regular files and folders are accepted)")

    def test_symlinked_top_folder(self):
        src = os.path.dirname(self.tree)
        real = os.path.join(self.root, "real-MPRGP")
        os.rename(self.tree, real)
        os.symlink(real, self.tree)
        self.assert_refused(src, f"{self.tree}: the tree's top folder is a symbolic link (refused: only regular "
                                 "files and folders are accepted)")

    def test_fifo_in_the_folder_is_refused_without_blocking(self):
        fifo = os.path.join(self.tree, "data", "pipe")
        os.mkfifo(fifo)
        self.assert_refused(self.tree, f"{fifo}: FIFO (only regular files and folders are accepted)")

    def test_setuid_file_in_the_folder(self):
        path = os.path.join(self.tree, "script", "run.sh")
        with open(path, "w") as f:
            f.write("#!/bin/sh\n")
        os.chmod(path, 0o4755)
        self.assert_refused(self.tree, f"{path}: setuid/setgid bit (mode 4755; only plain files are accepted)")

    def test_files_swapped_after_the_check_fail_on_the_bytes_copied(self):
        """Old code hashed the folder, then copied it: a swap in between passed. Now the hash is of the
        bytes written, and each path is opened without following links."""
        raw = os.path.join(self.tree, "script", "data", "mprgp.txt")
        mesh = os.path.join(self.tree, MESH)
        real_check = paper_data.check_folder

        def check_then_swap(root, **kw):
            real_check(root, **kw)
            with open(raw, "r+b") as f:  # same size, other bytes
                f.write(b"9")

        with mock.patch.object(paper_data, "check_folder", check_then_swap):
            self.assert_refused(self.tree, f"{self.tree}: SHA-256 differs from manifest.sha256 (not commit 57fdd2c?): "
                                           "script/data/mprgp.txt", skip=self.tree)
        self.write_tree("script/data/mprgp.txt", self.files["script/data/mprgp.txt"])

        def check_then_link(root, **kw):
            real_check(root, **kw)
            os.remove(mesh)
            os.symlink(self.victim, mesh)

        with mock.patch.object(paper_data, "check_folder", check_then_link):
            self.assert_refused(self.tree, f"{mesh}: symbolic link (only regular files and folders are accepted)",
                                skip=self.tree)


@unittest.skipUnless(shutil.which("git"), "git is not installed")
class HostileGit(Hostile):
    def repo(self):
        git = ["git", "-c", "user.name=t", "-c", "user.email=t@example.org", "-C", self.tree]
        subprocess.run(git[:1] + ["init", "--quiet", self.tree], check=True)
        subprocess.run(git + ["add", "-A"], check=True)
        subprocess.run(git + ["commit", "--quiet", "-m", "made-up tree"], check=True)
        return subprocess.run(git + ["rev-parse", "HEAD"], check=True, capture_output=True,
                              text=True).stdout.strip()

    def test_a_git_source_follows_the_folder_rules(self):
        os.symlink(self.victim, os.path.join(self.tree, "data", "link"))
        with mock.patch.object(paper_data, "COMMIT", self.repo()):
            self.assert_refused("file://" + self.tree, re.compile(
                r"^paper-data: error: .*/cb-paper-data-[^/]+/MPRGP/data/link: symbolic link \(only regular files "
                r"and folders are accepted\)$"))

    def test_a_clean_git_source_is_accepted(self):
        with mock.patch.object(paper_data, "COMMIT", self.repo()):
            status, err = self.run_main("file://" + self.tree)
        self.assertEqual(status, 0, err)
        self.assertEqual(temp_leftovers(), self.temp_before)


@unittest.skipUnless(shutil.which("make"), "make is not installed")
class MakeTarget(unittest.TestCase):
    def test_source_and_dest_never_reach_the_shell_line(self):
        with tempfile.TemporaryDirectory() as tmp:
            stub = os.path.join(tmp, "python")
            with open(stub, "w") as f:
                f.write(f'#!/bin/sh\nprintf "%s\\n" "$@" > {tmp}/args\n')
            os.chmod(stub, 0o755)
            source = f'x"; touch {tmp}/pwned1; "`touch {tmp}/pwned2`'
            dest = f"{tmp}/d d'$$(touch {tmp}/pwned3)"  # make reads $$ as a literal $
            subprocess.run(["make", "-s", "-C", ROOT, "paper-data", f"PY={stub}", f"PAPER_DATA_SOURCE={source}",
                            f"DATA={dest}"], check=True, capture_output=True)
            with open(os.path.join(tmp, "args")) as f:
                self.assertEqual(f.read().splitlines(),
                                 ["-m", "plots.paper_data", "--source", source, "--dest", dest.replace("$$", "$")])
            self.assertEqual(sorted(os.listdir(tmp)), ["args", "python"])


if __name__ == "__main__":
    unittest.main()
