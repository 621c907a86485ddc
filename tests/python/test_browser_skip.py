"""The browser test without Chromium (issue 46): it exits 77, which ctest's SKIP_RETURN_CODE reports
as skipped, and never 0 (passed).

Run from tests/python: /usr/bin/python3 -m unittest test_browser_skip
"""
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(os.path.dirname(HERE), "browser", "test_report_browser.py")


class TestBrowserSkip(unittest.TestCase):
    def test_missing_chromium_is_a_skip(self):
        with tempfile.TemporaryDirectory() as tmp:
            for key in ("CB_CHROMIUM", "CB_CHROMEDRIVER"):
                env = {**os.environ, key: os.path.join(tmp, "absent")}
                done = subprocess.run([sys.executable, SCRIPT, tmp], capture_output=True, text=True, env=env,
                                      timeout=120)
                self.assertEqual(done.returncode, 77, done.stdout + done.stderr)
                self.assertEqual(done.stdout, f"SKIP: {os.path.join(tmp, 'absent')} not installed (Debian packages "
                                              "chromium, chromium-driver: `make deps`)\n")
                self.assertEqual(os.listdir(tmp), [])  # no screenshot, nothing run


if __name__ == "__main__":
    unittest.main()
