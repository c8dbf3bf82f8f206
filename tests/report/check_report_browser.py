#!/usr/bin/env python3
"""Opens a `clayfit report` page in headless Chromium, takes a screenshot,
and checks that every image on the page loaded (the page's own script
counts them into #loaded once the load event has fired). Exits 77 (skipped)
with a message where Chromium is not installed.

usage: check_report_browser.py DIR SCREENSHOT"""
import os
import re
import shutil
import subprocess
import sys


def main():
    folder, screenshot = sys.argv[1], sys.argv[2]
    browser = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which(
        "google-chrome")
    if not browser:
        print("SKIP: no Chromium on this machine (apt-get install chromium)")
        return 77
    url = "file://" + os.path.abspath(os.path.join(folder, "index.html"))
    common = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
              "--virtual-time-budget=20000", "--window-size=1400,2400"]
    shot = subprocess.run(common + [f"--screenshot={screenshot}", url], capture_output=True,
                          text=True, timeout=180)
    if shot.returncode != 0 or not os.path.isfile(screenshot) or os.path.getsize(screenshot) < 10000:
        print("FAIL: no screenshot:", shot.stderr[-2000:])
        return 1
    dom = subprocess.run(common + ["--dump-dom", url], capture_output=True, text=True, timeout=180)
    match = re.search(r"images loaded: (\d+) of (\d+)", dom.stdout)
    if not match:
        print("FAIL: the page's image count did not run:", dom.stderr[-2000:])
        return 1
    loaded, total = int(match.group(1)), int(match.group(2))
    print(f"screenshot {screenshot} ({os.path.getsize(screenshot)} bytes); "
          f"images loaded: {loaded} of {total}")
    if total == 0 or loaded != total:
        print("FAIL: not every image loaded")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
