#!/usr/bin/python3
"""The HTML report in a real browser (issue 46): headless Chromium from Debian, driven by selenium.

A small suite is run with contactbench (its end writes the report), one record is then given a
hostile label and message, and `contactbench report` rewrites the page. In Chromium the test checks:
no console error; one table row per run record; every plot's SVG holds a drawn, non-empty line;
sorting by time orders the rows by time (ascending, then descending: the order changes); the filter
keeps only matching rows; the hostile strings show as text and no script of theirs runs (no alert,
no global set). The screenshot is kept at ARTIFACT_DIR/report_browser.png.

usage: test_report_browser.py ARTIFACT_DIR     (CB_CONTACTBENCH: the binary)
Exit 0 passed, 1 failed, 77 skipped (Chromium, chromedriver or selenium missing: ctest reports SKIP).
"""
import importlib.util
import json
import os
import shutil
import subprocess
import sys
import tempfile

SKIP = 77
# Debian's paths (CB_CHROMIUM / CB_CHROMEDRIVER override them: the skip path is tested that way)
CHROMIUM = os.environ.get("CB_CHROMIUM", "/usr/bin/chromium")
DRIVER = os.environ.get("CB_CHROMEDRIVER", "/usr/bin/chromedriver")
HOSTILE_LABEL = "<script>window.__cb_pwned=1;alert(1)</script>"
HOSTILE_MESSAGE = "<img src=x onerror=\"window.__cb_pwned=2;alert(2)\"></script><b>bold</b>"

SUITE = {
    "name": "browser",
    "generate": [
        {"id": "plane-a", "family": "plane", "seed": 1, "params": {"nx": 3, "ny": 3, "nz": 3}},
        {"id": "plane-b", "family": "plane", "seed": 2, "params": {"nx": 4, "ny": 3, "nz": 4, "tilt_deg": 20}},
    ],
    "solvers": [{"label": "mprgp", "solver": "mprgp"}, {"label": "pgs", "solver": "pgs"},
                {"label": "active-set", "solver": "active-set"},
                {"label": "cg-short", "solver": "cg", "settings": {"max_iterations": 2}}],
    "tol": 1e-6, "time_limit_s": 30, "history_max": 500,
}


class Failure(Exception):
    pass


def check(condition, what):
    if not condition:
        raise Failure(what)
    print(f"ok: {what}")


def skip(reason):
    print(f"SKIP: {reason}")
    sys.exit(SKIP)


def browser(profile):
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    # as root Chromium needs --no-sandbox; nothing may reach the network or update itself
    for arg in ("--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                "--disable-component-update", "--disable-sync", "--no-first-run", "--disable-extensions",
                "--window-size=1400,1800", f"--user-data-dir={profile}"):
        options.add_argument(arg)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    return webdriver.Chrome(service=Service(DRIVER), options=options)


def column(driver, key):
    """The texts of one column of the runs table, in the order shown."""
    return driver.execute_script(
        "var keys = Array.from(document.querySelectorAll('#runs-table thead th')).map(function (t) {"
        "  return t.getAttribute('data-key'); });"
        "var i = keys.indexOf(arguments[0]);"
        "return Array.from(document.querySelectorAll('#runs-table tbody tr')).map(function (r) {"
        "  return r.children[i].textContent; });", key)


def main(argv):
    artifacts = os.path.abspath(argv[1] if len(argv) > 1 else ".")
    for path in (CHROMIUM, DRIVER):
        if not os.path.isfile(path):
            skip(f"{path} not installed (Debian packages chromium, chromium-driver: `make deps`)")
    if importlib.util.find_spec("selenium") is None:
        skip("python3-selenium not installed (`make deps`)")
    cb = os.environ.get("CB_CONTACTBENCH")
    if not cb or not os.path.isfile(cb):
        raise Failure("CB_CONTACTBENCH (the contactbench binary) not set or missing: ctest sets it")
    work = tempfile.mkdtemp(prefix="cb-browser-")
    try:
        suite = os.path.join(work, "suite.json")
        with open(suite, "w", encoding="utf-8") as f:
            json.dump(SUITE, f)
        out = os.path.join(work, "results")
        env = dict(os.environ)
        env.pop("CB_REPORT", None)
        ran = subprocess.run([cb, "run", suite, "--out", out], capture_output=True, text=True, env=env, timeout=600)
        if ran.returncode != 0:
            raise Failure(f"contactbench run exited {ran.returncode}: {ran.stderr[-2000:]}")
        print("ok: contactbench run exits 0")
        index = os.path.join(out, "report", "index.html")
        check(f"report: {index}" in ran.stdout, "run prints the report's path at its end")
        check("summary: solved" in ran.stdout and "\n  mprgp " in ran.stdout, "run prints the table per solver")
        records = sorted(n for n in os.listdir(os.path.join(out, "runs")) if n.endswith(".json"))
        check(len(records) == 8, f"8 run records ({len(records)})")
        # a record from elsewhere (merged, edited) may carry any string: the page must show it as text
        hostile = os.path.join(out, "runs", "plane-b__pgs.json")
        with open(hostile, encoding="utf-8") as f:
            record = json.load(f)
        record["label"], record["message"] = HOSTILE_LABEL, HOSTILE_MESSAGE
        with open(hostile, "w", encoding="utf-8") as f:
            json.dump(record, f)
        # A folder of `run` (with jobs.json) holds each job's own record only, and a label with '/'
        # cannot name a run file: without jobs.json the folder reads as a hand-assembled one, whose
        # records may carry any label (plots/loader.py's rules).
        os.remove(os.path.join(out, "jobs.json"))
        rep = subprocess.run([cb, "report", out], capture_output=True, text=True, timeout=600)
        check(rep.returncode == 0 and rep.stdout.strip() == index,
              f"contactbench report prints the page's path (stdout {rep.stdout!r}, stderr {rep.stderr[-2000:]!r})")
        with open(index, encoding="utf-8") as f:
            page = f.read()
        check("http://" not in page and "https://" not in page and "//cdn" not in page,
              "the page loads nothing from the network")
        check("<script>window.__cb_pwned" not in page and "<img src=x" not in page,
              "the hostile strings are escaped in the page's source")

        driver = browser(os.path.join(work, "profile"))
        try:
            from selenium.common.exceptions import NoAlertPresentException
            driver.get("file://" + index)
            try:
                text = driver.switch_to.alert.text
                raise Failure(f"an alert ran: {text!r}")
            except NoAlertPresentException:
                print("ok: no alert")
            check(driver.execute_script("return window.__cb_pwned === undefined"), "no hostile script ran")
            errors = [e for e in driver.get_log("browser") if e.get("level") == "SEVERE"]
            check(not errors, f"no console error ({errors})")
            rows = driver.find_elements("css selector", "#runs-table tbody tr")
            check(len(rows) == len(records), f"one table row per run ({len(rows)} rows, {len(records)} runs)")
            labels = column(driver, "label")
            check(HOSTILE_LABEL in labels, "the hostile label is shown as text")
            check(HOSTILE_MESSAGE in column(driver, "message"), "the hostile message is shown as text")
            plots = driver.execute_script(
                "return Array.from(document.querySelectorAll('.plot svg')).map(function (svg) {"
                "  var drawn = Array.from(svg.querySelectorAll('path.series')).filter(function (p) {"
                "    var b = p.getBBox(); return (p.getAttribute('d') || '').length > 2 && b.width + b.height > 0; });"
                "  var r = svg.getBoundingClientRect();"
                "  return [drawn.length, r.width, r.height]; });")
            # two snapshots x (e vs time, e vs iterations) + the performance profile
            check(len(plots) == 5, f"5 plots ({len(plots)})")
            check(all(n > 0 and w > 0 and h > 0 for n, w, h in plots), f"every plot draws a line ({plots})")
            before = column(driver, "label")
            driver.find_element("css selector", "#runs-table th[data-key='time_s']").click()
            asc_times = [float(t) if t != "\u2014" else float("inf") for t in column(driver, "time_s")]
            asc = column(driver, "label")
            check(asc_times == sorted(asc_times), f"sorted by time, ascending ({asc_times})")
            driver.find_element("css selector", "#runs-table th[data-key='time_s']").click()
            desc_times = [float(t) for t in column(driver, "time_s")]
            check(desc_times == sorted(desc_times, reverse=True), "sorted by time, descending")
            check(column(driver, "label") != asc and (asc != before or column(driver, "label") != before),
                  "sorting by time changes the order of the rows")
            box = driver.find_element("id", "filter")
            box.send_keys("active-set")
            check(len(driver.find_elements("css selector", "#runs-table tbody tr")) == 2,
                  "the filter keeps the 2 active-set runs")
            box.clear()
            box.send_keys(" ")
            box.clear()
            os.makedirs(artifacts, exist_ok=True)
            shot = os.path.join(artifacts, "report_browser.png")
            check(driver.save_screenshot(shot) and os.path.getsize(shot) > 10000, f"screenshot kept: {shot}")
            errors = [e for e in driver.get_log("browser") if e.get("level") == "SEVERE"]
            check(not errors, f"no console error after the clicks ({errors})")
        finally:
            driver.quit()
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print("PASS")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main(sys.argv))
    except Failure as err:
        print(f"FAIL: {err}")
        sys.exit(1)
