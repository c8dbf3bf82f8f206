#!/usr/bin/env python3
"""The report's interactive view of the material (docs/report.md, "The
material, interactive") in headless Chromium, WebGL 2 through SwiftShader
(--use-angle=swiftshader --enable-unsafe-swiftshader, as
tests/export/check_shader_threejs.py).

For a `clayfit report` folder: the page loads from file:// with its view
present (no "absent" notice), the view's status line says it drew (no shader
or script failure), and in a screenshot the canvas' region (the rectangle the
page writes into the status line's data-rect) holds the sphere: at least 60 %
of the disc's area differs from the background, and the picture agrees with
clayfit's own rendering of the same view (viewer/clayfit.png), mean absolute
difference at most 3 of 255 per channel.

It can be rotated: in a copy of the page whose added script drags the
mouse 48 px across the canvas after loading (OrbitControls: about 67
degrees), the sphere is still drawn and the picture is no longer clayfit's
starting view (mean difference above the limit).

Then it shows that it can fail: two copies of the report with the material
broken on purpose (the fragment shader does not compile; the material
renders black) must each be caught.

Exit 77 (skipped) without Chromium or oiiotool, or when clayfit was built
without the three.js bundle (no clayfit-report-viewer.js beside CLAYFIT).

With --absent, instead: a copy of clayfit without the bundle beside it
writes a report whose page says plainly that the interactive view is absent
and why, with clayfit's rendering still there and no viewer script.

usage: check_report_viewer.py CLAYFIT REPORT_DIR WORKDIR
       check_report_viewer.py --absent CLAYFIT FIT_JSON WORKDIR"""
import os
import re
import shutil
import subprocess
import sys

MEAN_LIMIT = 3.0  # of 255; measured 0.4 on the small M2 fit (silhouette pixels)
COVER_LIMIT = 0.6  # of the disc's area
WINDOW = (1400, 1200)
# (name, text in viewer/material.js, replacement): each must fail the check
BROKEN = [
    ("shader-does-not-compile", "radiance += cf_radiance(p, n, l, v, e);",
     "radiance += cf_radiance(p, n, l, v);"),
    ("material-renders-black", "clayfitFragColor = vec4(radiance * clayfitExposure, 1.0);",
     "clayfitFragColor = vec4(radiance * 0.0, 1.0);"),
]


def chromium(browser, args, url):
    cmd = [browser, "--headless", "--no-sandbox", "--use-angle=swiftshader",
           "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist", "--hide-scrollbars",
           "--virtual-time-budget=20000", f"--window-size={WINDOW[0]},{WINDOW[1]}"] + args + [url]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=180)


def read_ppm(path):
    """(width, height, bytes) of a binary P6 file with maxval 255."""
    data = open(path, "rb").read()
    m = re.match(rb"P6\s+(\d+)\s+(\d+)\s+255\s", data)
    if not m:
        raise RuntimeError(f"{path}: not an 8-bit P6 file")
    return int(m.group(1)), int(m.group(2)), data[m.end():]


def to_ppm(source, target, cut=None):
    cmd = ["oiiotool", source, "--ch", "R,G,B"]
    if cut:
        cmd += ["--cut", cut]
    subprocess.run(cmd + ["-o", target], check=True, capture_output=True)
    return read_ppm(target)


def check(browser, report, work):
    """The failures of the report's view (an empty list when it works), and
    the measurements."""
    page = open(os.path.join(report, "index.html"), encoding="utf-8").read()
    if 'id="viewer-absent"' in page:
        return ["the page says the interactive view is absent"], {}
    url = "file://" + os.path.abspath(os.path.join(report, "index.html"))
    dom = chromium(browser, ["--dump-dom"], url).stdout
    m = re.search(r'<p id="clayfit-view-status"(?: data-rect="([\d,]+)")?>([^<]*)</p>', dom)
    if not m:
        return ["no status line of the view in the page"], {}
    status = m.group(2)
    failures = []
    if not status.startswith("interactive view: drawn"):
        failures.append(f"the view's status: {status!r}")
    if "absent" in dom or "failed" in status:
        failures.append("the page says something is missing or failed")
    if not m.group(1):
        return failures + ["the view did not write where its canvas is"], {"status": status}
    x, y, w, h = map(int, m.group(1).split(","))
    shot = os.path.join(work, "screenshot.png")
    chromium(browser, [f"--screenshot={shot}"], url)
    if not os.path.isfile(shot):
        return failures + ["no screenshot"], {"status": status}
    width, height, got = to_ppm(shot, os.path.join(work, "canvas.ppm"), f"{w}x{h}+{x}+{y}")
    rw, rh, ref = to_ppm(os.path.join(report, "viewer", "clayfit.png"),
                         os.path.join(work, "clayfit.ppm"))
    if (width, height) != (rw, rh):
        return failures + [f"canvas {width}x{height}, clayfit's rendering {rw}x{rh}"], {}
    background = ref[0:3]  # the corner: the view's background
    n = width * height
    differs = sum(1 for i in range(n)
                  if max(abs(got[3 * i + c] - background[c]) for c in range(3)) > 8)
    disc = 3.14159265 * (0.92 * width / 2) ** 2
    mean = sum(abs(a - b) for a, b in zip(got, ref)) / (3 * n)
    numbers = {"status": status, "non_background": differs, "disc": round(disc),
               "mean_abs_diff": round(mean, 3)}
    if differs < COVER_LIMIT * disc:
        failures.append(f"{differs} pixels differ from the background, fewer than "
                        f"{COVER_LIMIT} of the disc's {disc:.0f}")
    if mean > MEAN_LIMIT:
        failures.append(f"mean absolute difference from clayfit's rendering {mean:.3g} > "
                        f"{MEAN_LIMIT}")
    return failures, numbers


def absent(clayfit, fit, work):
    """A clayfit without its bundle: the page says the view is absent."""
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(os.path.join(work, "bin"))
    alone = os.path.join(work, "bin", "clayfit")
    shutil.copy(clayfit, alone)
    out = os.path.join(work, "report")
    run = subprocess.run([alone, "--quiet", "report", fit, "-o", out], capture_output=True,
                         text=True)
    if run.returncode != 0:
        print("FAIL: clayfit report without the bundle:", run.returncode, run.stderr)
        return 1
    page = open(os.path.join(out, "index.html"), encoding="utf-8").read()
    m = re.search(r'<p id="viewer-absent"[^>]*>(.*?)</p>', page, re.S)
    failures = []
    if not m or "The interactive view is absent" not in m.group(1):
        failures.append("no notice that the interactive view is absent")
    elif "clayfit-report-viewer.js" not in m.group(1):
        failures.append("the notice does not say which file is missing")
    if "three_viewer.js" in page or "<canvas" in page:
        failures.append("the page still loads the viewer")
    for name in ("clayfit.png", "material.mjs", "material.js"):
        if not os.path.isfile(os.path.join(out, "viewer", name)):
            failures.append(f"viewer/{name} is missing")
    print("notice:", re.sub(r"<[^>]+>", "", m.group(1)) if m else None)
    for f in failures:
        print("FAIL:", f)
    return 1 if failures else 0


# added to a copy of the page: a drag across the canvas once it has loaded
DRAG = """<script>
window.addEventListener('load', function () {
  var c = document.getElementById('clayfit-view'), r = c.getBoundingClientRect();
  var x = r.left + r.width / 2, y = r.top + r.height / 2;
  function send(type, dx) {
    c.dispatchEvent(new PointerEvent(type, {pointerId: 1, pointerType: 'mouse', isPrimary: true,
      bubbles: true, clientX: x + dx, clientY: y, button: 0, buttons: type === 'pointerup' ? 0 : 1}));
  }
  send('pointerdown', 0);
  for (var i = 1; i <= 4; ++i) send('pointermove', 12 * i);
  send('pointerup', 48);
});
</script>
</body>"""


def rotated(browser, report, work):
    """The failures of the rotated copy: it must differ from the start."""
    copy = os.path.join(work, "rotated")
    shutil.copytree(report, copy)
    path = os.path.join(copy, "index.html")
    page = open(path, encoding="utf-8").read()
    open(path, "w", encoding="utf-8").write(page.replace("</body>", DRAG, 1))
    failures, numbers = check(browser, copy, copy)
    print("rotated:", numbers)
    expected = [f for f in failures if f.startswith("mean absolute difference")]
    if failures != expected or not expected:
        return [f"rotated: {failures or 'the picture did not change'}"]
    return []


def main():
    if sys.argv[1] == "--absent":
        return absent(*sys.argv[2:5])
    clayfit, report, work = sys.argv[1:4]
    browser = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which(
        "google-chrome")
    if not browser or not shutil.which("oiiotool"):
        print("SKIP: no Chromium or oiiotool on this machine")
        return 77
    bundle = os.path.join(os.path.dirname(os.path.abspath(clayfit)), "clayfit-report-viewer.js")
    if not os.path.isfile(bundle):
        print(f"SKIP: no {bundle}: clayfit was built without the three.js bundle "
              "(scripts/install-deps.sh, then configure and build again)")
        return 77
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    failures, numbers = check(browser, report, work)
    print("view:", numbers)
    failures += rotated(browser, report, work)
    for name, old, new in BROKEN:
        copy = os.path.join(work, name)
        shutil.copytree(report, copy)
        path = os.path.join(copy, "viewer", "material.js")
        text = open(path, encoding="utf-8").read()
        if old not in text:
            failures.append(f"{name}: {old!r} is not in material.js")
            continue
        open(path, "w", encoding="utf-8").write(text.replace(old, new))
        caught, numbers = check(browser, copy, copy)
        print(f"{name}: {'caught' if caught else 'NOT CAUGHT'}: {caught[:2]} {numbers}")
        if not caught:
            failures.append(f"{name}: the broken material passed the check")
    for f in failures:
        print("FAIL:", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
