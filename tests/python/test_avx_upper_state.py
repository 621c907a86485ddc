"""No AVX kernel of the contactbench binary hands a dirty upper register state to SSE code.

The project is built for plain x86-64 (SSE2) and its hot kernels are AVX2 functions chosen at run
time. A function that leaves the upper halves of the ymm registers dirty when it calls or returns
into SSE code makes that code slower: on this project's machine the SSE code after such a kernel ran
up to 1.5x slower (docs/a_product.md, "The passes around the product, once more"; `make test`'s
monitor timing caught it as a monitored `cg` run 1.5x slower than an unmonitored one). GCC 12
emitted no vzeroupper before a call out of two kernels; they clear the upper halves themselves now.

The scan reads each function of `objdump -d` in address order: an instruction on a %ymm register
makes the state dirty, vzeroupper clean; a call or jump to another function, or a return, while
dirty is reported. It does not follow branches, so a path that never runs can be reported too: then
clear the state (`_mm256_zeroupper()`) before the call anyway.
"""
import os
import platform
import re
import shutil
import subprocess
import unittest

CONTACTBENCH = os.environ.get("CB_CONTACTBENCH", "")

FUNCTION = re.compile(r"^([0-9a-f]+) <(.*)>:$")
BRANCH = re.compile(r"\s(call|jmp)\s+([0-9a-f]+) <")
RETURN = re.compile(r"\sret\s*$")


def dirty_exits(listing):
    """{function name: sorted exits (call, jmp, ret) taken with a dirty upper state} of an objdump -d listing."""
    lines = listing.split("\n")
    starts = sorted(int(m.group(1), 16) for m in map(FUNCTION.match, lines) if m)

    def owner(address):
        low, high = 0, len(starts)
        while low < high:
            mid = (low + high) // 2
            if starts[mid] <= address:
                low = mid + 1
            else:
                high = mid
        return starts[low - 1] if low else None

    found = {}
    start, name, dirty = None, "", False
    for line in lines:
        m = FUNCTION.match(line)
        if m:
            start, name, dirty = int(m.group(1), 16), m.group(2), False
            continue
        if start is None:
            continue
        if "vzeroupper" in line or "vzeroall" in line:
            dirty = False
            continue
        if "%ymm" in line:
            dirty = True
        branch = BRANCH.search(line)
        if dirty and branch and owner(int(branch.group(2), 16)) != start:
            found.setdefault(name, set()).add(branch.group(1))
        if dirty and RETURN.search(line):
            found.setdefault(name, set()).add("ret")
    return {k: sorted(v) for k, v in found.items()}


PLANTED = """
0000000000001000 <kernel_avx2>:
    1000:\tvmovupd (%rdi),%ymm0
    1004:\tvmaxpd %ymm1,%ymm0,%ymm1
    1008:\tcall   2000 <tail_sse>
    100d:\tret
0000000000002000 <tail_sse>:
    2000:\tmaxsd  %xmm1,%xmm0
    2004:\tret
0000000000003000 <kernel_clean>:
    3000:\tvmovupd (%rdi),%ymm0
    3004:\tjmp    3010 <kernel_clean+0x10>
    3010:\tvzeroupper
    3013:\tjmp    2000 <tail_sse>
"""


class Scanner(unittest.TestCase):
    def test_a_call_and_a_return_after_ymm_without_vzeroupper_are_reported(self):
        self.assertEqual(dirty_exits(PLANTED), {"kernel_avx2": ["call", "ret"]})

    def test_a_jump_inside_the_function_and_a_call_after_vzeroupper_are_not(self):
        self.assertNotIn("kernel_clean", dirty_exits(PLANTED))


@unittest.skipUnless(CONTACTBENCH and os.path.isfile(CONTACTBENCH), "CB_CONTACTBENCH is not set to the binary")
@unittest.skipUnless(shutil.which("objdump"), "objdump (binutils) is not installed")
@unittest.skipUnless(platform.machine() == "x86_64", "the AVX2 kernels are x86-64's")
class Binary(unittest.TestCase):
    def test_no_function_leaves_the_upper_halves_dirty(self):
        listing = subprocess.run(["objdump", "-d", "--no-show-raw-insn", "-C", CONTACTBENCH], capture_output=True,
                                 text=True, check=True).stdout
        self.assertIn("vzeroupper", listing)  # the AVX2 kernels are in this binary
        self.assertEqual(dirty_exits(listing), {})


if __name__ == "__main__":
    unittest.main()
