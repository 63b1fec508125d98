#!/usr/bin/env python3
"""Opens DIR/index.html (tailsim's result page) in Debian's headless chromium and prints how long it
took until the results table was drawn, the page's size on disk and its rows in the DOM.

usage: scripts/page_load_time.py DIR [REPEATS]   (needs chromium, chromium-driver, python3-selenium)
"""
import os
import shutil
import sys
import tempfile
import time

from selenium import webdriver
from selenium.webdriver.chrome.options import Options
from selenium.webdriver.chrome.service import Service


def size(path):
    if os.path.isfile(path):
        return os.path.getsize(path)
    return sum(os.path.getsize(os.path.join(d, f)) for d, _, fs in os.walk(path) for f in fs)


def main():
    folder = os.path.abspath(sys.argv[1])
    repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 3
    opts = Options()
    opts.binary_location = "/usr/bin/chromium"
    profile = tempfile.mkdtemp(prefix="tailsim-page-profile-")
    for a in ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
              "--disable-background-networking", "--disable-component-update", "--disable-sync",
              "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--window-size=1400,1000",
              "--user-data-dir=" + profile]:
        opts.add_argument(a)
    driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=opts)
    try:
        for _ in range(repeats):
            t0 = time.time()
            driver.get("file://" + os.path.join(folder, "index.html"))
            while not driver.execute_script("return !!(window.tailsim && tailsim.tableRows && tailsim.tableRows() > 0)"):
                time.sleep(0.01)
            t1 = time.time()
            nav = driver.execute_script("return performance.now()")
            count = driver.execute_script("return document.getElementById('count').textContent")
            rows = driver.execute_script("return tailsim.tableRows()")
            # sorting the whole table by a column: a click on its header
            t2 = time.time()
            driver.execute_script("document.querySelectorAll('#thead .cell')[1].click()")
            t3 = time.time()
            print("load %.2f s (page clock %.0f ms), sort %.2f s; %s, %d rows in the DOM" % (t1 - t0, nav, t3 - t2, count, rows))
    finally:
        driver.quit()
        shutil.rmtree(profile, ignore_errors=True)
    print("size: data.js %.1f MB, page/ %.1f MB (three.js %.2f MB), index.html %d B" % (
        size(os.path.join(folder, "page", "data.js")) / 1e6, size(os.path.join(folder, "page")) / 1e6,
        size(os.path.join(folder, "page", "three.min.js")) / 1e6, size(os.path.join(folder, "index.html"))))


if __name__ == "__main__":
    main()
