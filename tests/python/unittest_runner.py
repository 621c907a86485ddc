"""Runs one tests/python module as ctest runs it: verbose unittest, exit 0 when every test passed,
1 on a failure or error, SKIP_EXIT (77, the ctest property SKIP_RETURN_CODE of python.*) when none
failed but one or more were skipped, so that ctest reports "Skipped" instead of "Passed" for a
module that did not run in full; the reasons are printed last.

usage: unittest_runner.py MODULE
"""
import sys
import unittest

#: the exit status ctest reads as "skipped" (CMakeLists.txt: SKIP_RETURN_CODE of the python.* tests)
SKIP_EXIT = 77


def main(argv) -> int:
    if len(argv) != 1:
        print("usage: unittest_runner.py MODULE", file=sys.stderr)
        return 2
    suite = unittest.defaultTestLoader.loadTestsFromName(argv[0])
    result = unittest.TextTestRunner(verbosity=2, stream=sys.stderr).run(suite)
    if not result.wasSuccessful() or result.testsRun == 0 and not result.skipped:
        return 1
    if result.skipped:
        print(f"{argv[0]}: {len(result.skipped)} of {result.testsRun} test(s) skipped:", file=sys.stderr)
        for test, reason in result.skipped:
            print(f"  SKIPPED {test.id()}: {reason}", file=sys.stderr)
        return SKIP_EXIT
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
