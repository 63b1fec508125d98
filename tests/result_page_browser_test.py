#!/usr/bin/env python3
"""The result page (DIR/index.html) in a real browser: Debian's chromium, headless, driven by
python3-selenium through chromedriver.

Builds a small suite result folder (a 2-key analytic + per-foot sweep with a 2-link tail, and one
analytic + MuJoCo case), writes the page with `tailsim plot`, opens index.html from file:// and
asserts: no console error; the hostile description is shown as text; the table keeps only the
visible rows in the DOM; clicking a heat-map cell opens that case; the replay at the time of a CSV
row mid-stroke shows that row's body yaw and tail angles (read back from the page's state and from
the drawn 3D objects); the MuJoCo case's replay too; a screenshot is not blank (pixel variance).

usage: result_page_browser_test.py SOURCE_DIR BUILD_DIR [SCREENSHOT_DIR]
"""
import csv
import math
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import zlib

from selenium import webdriver
from selenium.webdriver.chrome.options import Options
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.action_chains import ActionChains

SRC, BUILD = sys.argv[1], sys.argv[2]
SHOTS = sys.argv[3] if len(sys.argv) > 3 else None
TAILSIM = os.path.join(BUILD, "tailsim")

# Text from the inputs that must reach the page as text: a script end tag, quotes, U+2028, and
# 10 kB of it.
HOSTILE = "</script><script>window.pwned=1</script> \"quoted\" 'single' & <b>bold</b> \u2028 line \u2029 end " + "x" * 10000

# An experiment name may hold markup characters, quotes and U+2028 (not '/' or control characters).
SWEEP_NAME = "sweep2 <img src=x onerror=window.pwned=1> \"q\" 'a' &amp; \u2028 end"
SWEEP = """name: %s
description: %s
robot: paper
tail: {links: 2}
trajectory:
  theta0_deg: 0
  dtheta_deg: {sweep: [-30, -60]}
  dT_s: {sweep: [0.2, 0.3]}
  w_ss: 0.25
models: [analytic, perfoot]
output: {sample_dt_s: 0.002, settle_s: 0.1}
"""
MUJOCO = """name: mujoco1
description: "one case, analytic and MuJoCo"
robot: paper
tail: {links: 1}
trajectory: {theta0_deg: 0, dtheta_deg: -90, dT_s: 0.2, w_ss: 0.25}
models: [analytic, mujoco]
output: {sample_dt_s: 0.002, settle_s: 0.1}
mujoco: {settle_s: 0.05}
"""


def yaml_string(s):
    # YAML double-quoted scalar (JSON's escapes are YAML's)
    import json
    return json.dumps(s)


def png_variance(png):
    """Variance of the grey levels of an 8-bit RGB/RGBA PNG (no PIL on the test machine)."""
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, w = 8, b"", 0
    while pos < len(png):
        n, kind = struct.unpack(">I4s", png[pos:pos + 8])
        body = png[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
            assert depth == 8 and ctype in (2, 6), (depth, ctype)
            bpp = 3 if ctype == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw, stride = zlib.decompress(idat), w * bpp
    prev, grey = bytearray(stride), []
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b, c = prev[i], prev[i - bpp] if i >= bpp else 0
            if f == 1: line[i] = (line[i] + a) & 255
            elif f == 2: line[i] = (line[i] + b) & 255
            elif f == 3: line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        prev = line
        grey.extend(sum(line[i:i + 3]) / 3 for i in range(0, stride, bpp * 4))  # every 4th pixel
    m = sum(grey) / len(grey)
    return sum((g - m) ** 2 for g in grey) / len(grey)


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return rows


def main():
    t_start = time.time()
    tmp = tempfile.mkdtemp(prefix="tailsim-page-")
    with open(os.path.join(tmp, "sweep2.yaml"), "w") as f:
        f.write(SWEEP % (yaml_string(SWEEP_NAME), yaml_string(HOSTILE)))
    with open(os.path.join(tmp, "mujoco1.yaml"), "w") as f:
        f.write(MUJOCO)
    with open(os.path.join(tmp, "suite.yaml"), "w") as f:
        f.write("experiments:\n  - sweep2.yaml\n  - mujoco1.yaml\n")
    out = os.path.join(tmp, "out")
    subprocess.run([TAILSIM, "run", os.path.join(tmp, "suite.yaml"), "--out", out, "--quiet"], check=True,
                   stdout=subprocess.DEVNULL)
    subprocess.run([TAILSIM, "plot", out], check=True, stdout=subprocess.DEVNULL)
    index = os.path.join(out, "index.html")
    assert os.path.isfile(index), "no index.html"
    with open(index, encoding="utf-8") as f:
        assert "</script><script>window.pwned" not in f.read()
    t_built = time.time()

    opts = Options()
    opts.binary_location = "/usr/bin/chromium"
    for a in ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
              "--disable-background-networking", "--disable-component-update", "--disable-sync",
              "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--window-size=1400,1300",
              "--user-data-dir=" + os.path.join(tmp, "profile")]:
        opts.add_argument(a)
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=opts)
    try:
        driver.get("file://" + index)
        wait(driver, "return !!(window.tailsim && document.getElementById('count').textContent)")
        t_loaded = time.time()

        names = driver.execute_script("return tailsim.experiments()")
        assert sorted(names) == ["mujoco1", SWEEP_NAME], names
        sweep, mj = names.index(SWEEP_NAME), names.index("mujoco1")
        driver.execute_script("tailsim.selectExperiment(arguments[0])", sweep)

        # Text from the inputs is shown as text, nothing of it runs.
        assert driver.execute_script("return window.pwned === undefined"), "text from the inputs ran as script"
        desc = driver.execute_script("return document.getElementById('expdesc').textContent")
        assert desc == HOSTILE, "description not shown verbatim: %r..." % desc[:80]
        assert driver.execute_script("return document.querySelectorAll('#expdesc *').length") == 0
        assert driver.execute_script("return document.getElementById('exptitle').textContent") == SWEEP_NAME
        assert driver.execute_script("return document.getElementById('expsel').selectedOptions[0].textContent") == SWEEP_NAME
        assert driver.execute_script("return document.querySelectorAll('img[src=x]').length") == 0

        # The table: 4 cases, rows only for what is visible.
        assert driver.execute_script("return document.getElementById('count').textContent") == "4 of 4 cases"
        assert 0 < driver.execute_script("return tailsim.tableRows()") <= 4
        # In a narrow window the case names keep a readable column: the value columns give way first
        # (with 3 models and 2 keys the name column had shrunk to one character).
        driver.set_window_size(1000, 1300)
        time.sleep(0.3)
        name_w = driver.execute_script("return document.querySelector('.row .cell.name').getBoundingClientRect().width")
        head_w = driver.execute_script("return document.querySelector('#thead .cell.name').getBoundingClientRect().width")
        assert name_w >= 120 and abs(name_w - head_w) < 1, "case name column %.0f px (header %.0f px)" % (name_w, head_w)
        driver.set_window_size(1400, 1300)
        time.sleep(0.3)

        # The heat map has the figures' colour maps: sequential white - dark orange (#7A4A00 at the
        # largest magnitude) for phi_net of one sign, diverging blue - vermillion centred on zero for both.
        phis = {r["case"]: float(r["phi_net_deg"]) for r in read_csv(os.path.join(out, SWEEP_NAME, "results.csv"))
                if r["model"] == "analytic"}
        lo, hi = min(phis.values()), max(phis.values())
        sc = driver.execute_script("return tailsim.mapScale()")
        assert sc and sc["kind"] == ("diverging" if lo < 0 < hi else "sequential"), (sc, lo, hi)
        top = max(phis, key=lambda c: abs(phis[c]))
        k_top = driver.execute_script("""
            return +Array.from(document.querySelectorAll('.row')).find(r => r.firstChild.textContent === arguments[0]).getAttribute('data-case');""", top)
        pt = driver.execute_script("return tailsim.mapPoint(arguments[0])", k_top)
        rgb = driver.execute_script("""
            const d = document.getElementById('map').getContext('2d').getImageData(arguments[0] - 20, arguments[1] + 8, 1, 1).data;
            return [d[0], d[1], d[2]];""", pt["x"], pt["y"])
        want = (122, 74, 0) if sc["kind"] == "sequential" else ((213, 94, 0) if phis[top] > 0 else (0, 114, 178))
        assert all(abs(a - b) <= 3 for a, b in zip(rgb, want)), "largest |phi_net| cell %s: %s, want %s" % (top, rgb, want)

        # A heat-map cell opens its case: pick dtheta = -60, dT = 0.3 (case index from the table data).
        names = driver.execute_script("return Array.from(document.querySelectorAll('.row')).map(r => r.firstChild.textContent)")
        k = driver.execute_script("""
            const rows = Array.from(document.querySelectorAll('.row'));
            const r = rows.find(r => r.firstChild.textContent.includes('dtheta_deg=-60') && r.firstChild.textContent.includes('dT_s=0.3'));
            return r ? +r.getAttribute('data-case') : -1;""")
        assert k >= 0, names
        p = driver.execute_script("return tailsim.mapPoint(arguments[0])", k)
        canvas = driver.find_element("id", "map")
        size = canvas.size
        ActionChains(driver).move_to_element_with_offset(canvas, p["x"] - size["width"] / 2,
                                                         p["y"] - size["height"] / 2).click().perform()
        wait(driver, "return tailsim.state().case === %d && Object.keys(tailsim.state().models).length === 2" % k)
        st = driver.execute_script("return tailsim.state()")
        case_name = st["case_name"]
        assert "dtheta_deg=-60" in case_name and "dT_s=0.3" in case_name, case_name
        assert st["webgl"], "no WebGL: the 3D view was not drawn"

        # The replay at a CSV row's time mid-stroke shows that row.
        case_dir = [d for d in os.listdir(os.path.join(out, SWEEP_NAME, "cases")) if "dtheta_deg=-60" in d and "dT_s=0.3" in d][0]
        for model in ("analytic", "perfoot"):
            rows = read_csv(os.path.join(out, SWEEP_NAME, "cases", case_dir, model + ".csv"))
            row = min(rows, key=lambda r: abs(float(r["t_s"]) - 0.15))  # mid-stroke (0..0.3 s)
            t = float(row["t_s"])
            driver.execute_script("tailsim.seek(arguments[0])", t)
            s = driver.execute_script("return tailsim.state()")["models"][model]
            check(model, "phi_deg", s["phi_deg"], float(row["phi_deg"]))
            check(model, "drawn yaw", angle(s["drawn_yaw_deg"] - float(row["phi_deg"])), 0.0, 1e-4)
            for i in (1, 2):
                check(model, "theta%d_deg" % i, s["theta_deg"][i - 1], float(row["theta%d_deg" % i]))
                check(model, "drawn theta%d" % i, s["drawn_theta_deg"][i - 1], float(row["theta%d_deg" % i]), 1e-4)
            assert abs(float(row["theta2_deg"])) > 1.0 and abs(float(row["phi_deg"])) > 1e-3, "not mid-stroke"
            if model == "perfoot":  # an arrow per loaded foot: N<k>_N up, F<k>x/y_N along the ground
                loaded = sum(float(row["N%d_N" % k]) > 1e-6 for k in range(1, 5))
                assert s["force_arrows"]["normal"] == loaded == 4, (s["force_arrows"], loaded)
                sliding = sum(math.hypot(float(row["F%dx_N" % k]), float(row["F%dy_N" % k])) > 1e-3 for k in range(1, 5))
                assert s["force_arrows"]["friction"] == sliding, (s["force_arrows"], sliding)
        # Play moves the time on; the scrub bar sets it; sorting and filtering the table.
        driver.execute_script("tailsim.seek(0); tailsim.play()")
        time.sleep(0.4)
        st = driver.execute_script("tailsim.pause(); return tailsim.state()")
        assert 0.05 < st["t"] and not st["playing"], st["t"]
        t_end = driver.execute_script(
            "const s = document.getElementById('scrub'); s.value = 1000; s.dispatchEvent(new Event('input')); return tailsim.state().t")
        t_last = max(float(r["t_s"]) for r in read_csv(os.path.join(out, SWEEP_NAME, "cases", case_dir, "perfoot.csv")))
        assert abs(t_end - t_last) < 1e-9, (t_end, t_last)
        first = "return document.querySelector('.row').firstChild.textContent"
        driver.execute_script("document.querySelectorAll('#thead .cell')[3].click()")  # analytic phi_net, ascending
        assert "dtheta_deg=-30,dT_s=0.3" in driver.execute_script(first)
        driver.execute_script("document.querySelectorAll('#thead .cell')[3].click()")  # descending
        assert "dtheta_deg=-60,dT_s=0.2" in driver.execute_script(first)
        driver.execute_script("const f = document.getElementById('filter'); f.value = 'dT_s=0.2'; f.dispatchEvent(new Event('input'))")
        assert driver.execute_script("return document.getElementById('count').textContent") == "2 of 4 cases"
        if SHOTS:
            driver.execute_script("document.getElementById('replaysec').scrollIntoView()")
            driver.save_screenshot(os.path.join(SHOTS, "result-page-replay.png"))
            driver.execute_script("window.scrollTo(0, 0)")
            driver.save_screenshot(os.path.join(SHOTS, "result-page-sweep.png"))
        driver.execute_script("document.getElementById('replaysec').scrollIntoView()")
        var = png_variance(driver.get_screenshot_as_png())
        assert var > 100, "screenshot looks blank (grey variance %.1f)" % var
        # Over the 3D view, the text of each model's angles now and the legend of the models do not
        # overlap, and both are inside the view.
        r = driver.execute_script("""
            const box = id => { const b = document.getElementById(id).getBoundingClientRect(); return [b.left, b.top, b.right, b.bottom]; };
            return [box('hud'), box('legend'), box('view3d')];""")
        (h, l, v) = r
        assert not (h[0] < l[2] and l[0] < h[2] and h[1] < l[3] and l[1] < h[3]), "the replay's text and legend overlap: %s" % r
        for b in (h, l):
            assert v[0] <= b[0] and b[2] <= v[2] and v[1] <= b[1] and b[3] <= v[3], "outside the 3D view: %s" % r

        # The MuJoCo case (second experiment): solid robot and foot forces.
        driver.execute_script("tailsim.openCase(arguments[0], 0)", mj)
        wait(driver, "return tailsim.state().experiment === 'mujoco1' && tailsim.state().case === 0 && 'mujoco' in tailsim.state().models")
        mj_dir = os.listdir(os.path.join(out, "mujoco1", "cases"))[0]
        rows = read_csv(os.path.join(out, "mujoco1", "cases", mj_dir, "mujoco.csv"))
        row = min((r for r in rows if sum(float(r["foot%d_Fn_N" % k]) > 1e-3 for k in range(1, 5)) >= 2),
                  key=lambda r: abs(float(r["t_s"]) - 0.1))
        driver.execute_script("tailsim.seek(arguments[0])", float(row["t_s"]))
        s = driver.execute_script("return tailsim.state()")["models"]["mujoco"]
        check("mujoco", "phi_deg", s["phi_deg"], float(row["phi_deg"]))
        check("mujoco", "drawn yaw", angle(s["drawn_yaw_deg"] - float(row["phi_deg"])), 0.0, 1e-4)
        check("mujoco", "drawn theta1", s["drawn_theta_deg"][0], float(row["theta1_deg"]), 1e-4)
        # an arrow for each foot the ground pushes (foot<k>_Fn_N); the CSV row must have some
        loaded = sum(float(row["foot%d_Fn_N" % k]) > 1e-3 for k in range(1, 5))
        assert s["force_arrows"]["normal"] == loaded, (s["force_arrows"], loaded)
        # The table gives MuJoCo's phi_net with its own uncertainty, and the verdict across the models.
        driver.execute_script("const f = document.getElementById('filter'); f.value = ''; f.dispatchEvent(new Event('input'))")
        heads = driver.execute_script("return Array.from(document.querySelectorAll('#thead .cell')).map(c => c.textContent)")
        cells = driver.execute_script("return Array.from(document.querySelector('.row').children).map(c => c.textContent)")
        mj_col = next(i for i, h in enumerate(heads) if h.startswith("MuJoCo") and "φ_net" in h)
        assert " ± " in cells[mj_col], (heads, cells)
        assert heads[-1] == "verdict" and cells[-1], (heads, cells)
        if SHOTS:
            driver.save_screenshot(os.path.join(SHOTS, "result-page-mujoco.png"))

        logs = driver.get_log("browser")
        errors = [e for e in logs if e["level"] == "SEVERE"]
        assert not errors, "console errors: %s" % errors
        warnings = [e["message"] for e in logs if e["level"] == "WARNING"]
        if warnings:
            print("console warnings:", warnings)
    finally:
        driver.quit()
        shutil.rmtree(tmp, ignore_errors=True)
    print("result page test: folder %.1f s, page loaded %.2f s, total %.1f s" %
          (t_built - t_start, t_loaded - t_built, time.time() - t_start))


def angle(d):
    return (d + 180.0) % 360.0 - 180.0


def check(model, what, got, want, tol=1e-6):
    assert got is not None and math.isfinite(got) and abs(got - want) <= tol * max(1.0, abs(want)), \
        "%s %s: page %r, CSV %r" % (model, what, got, want)


def wait(driver, script, timeout=15.0):
    end = time.time() + timeout
    while time.time() < end:
        if driver.execute_script(script):
            return
        time.sleep(0.05)
    logs = driver.get_log("browser")
    raise AssertionError("timed out waiting for: %s\nconsole: %s" % (script, logs))


if __name__ == "__main__":
    main()
