#!/usr/bin/env python3
"""The material library's gallery and `clayfit library compare` (docs/batch.md),
on the library batch_local leaves (five fitted entries, one failed):

- every fitted entry has LIBRARY/<name>/thumbnail.png, a 256 x 256 PNG,
  named by library.json's `thumbnail` (schema-valid; null for the failed
  one) and shown on its card in LIBRARY/index.html;
- index.html has one card per manifest entry, in order, built from the same
  records as library.json (model, relative RMSE, report link); the failed
  entry's card is marked failed and shows the reason of its failed.json,
  with a link to it;
- `library compare` of an entry with itself: every difference 0, an all-zero
  difference image (compare.json, difference.png all neutral), and its A
  render is the thumbnail, pixel for pixel;
- of two different entries: the differences printed and in compare.json
  equal (valueA - valueB) / sqrt(sdA^2 + sdB^2) from their fit.json;
  different models: the shared parameters compared, the others marked;
- unknown entry, failed entry, not a library, bad usage: exit 2, named.

With --browser: index.html in headless Chromium, every thumbnail loaded
(exit 77 without Chromium).

usage: check_library.py CLAYFIT SCHEMA_DIR LIBRARY WORK_DIR [--browser]"""
import html.parser
import json
import math
import os
import re
import shutil
import struct
import subprocess
import sys
import urllib.parse
import zlib

CLAYFIT, SCHEMA, LIBRARY, WORK = sys.argv[1:5]
BROWSER = "--browser" in sys.argv[5:]
failures = 0


def check(ok, what):
    global failures
    print(("ok   " if ok else "FAIL ") + what)
    failures += not ok


def run(*args):
    return subprocess.run([CLAYFIT, *args], capture_output=True, text=True)


def read_png(path):
    """(width, height, channels, rows of bytes) of an 8-bit, non-interlaced PNG."""
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", f"{path}: not a PNG"
    pos, idat, header = 8, b"", None
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    width, height, depth, colour, _, _, interlace = header
    assert depth == 8 and interlace == 0 and colour in (0, 2, 4, 6), f"{path}: {header}"
    channels = {0: 1, 2: 3, 4: 2, 6: 4}[colour]
    raw, stride, rows = zlib.decompress(idat), width * channels, []
    prev = bytearray(stride)
    for y in range(height):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b, c = prev[i], prev[i - channels] if i >= channels else 0
            if f == 1: line[i] = (line[i] + a) & 255
            elif f == 2: line[i] = (line[i] + b) & 255
            elif f == 3: line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(line))
        prev = line
    return width, height, channels, rows


def rgb(png):
    width, height, channels, rows = png
    return [bytes(r[i] for i in range(len(r)) if i % channels < 3) for r in rows]


class Page(html.parser.HTMLParser):
    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.cards, self.card, self.depth, self.all_imgs = [], None, 0, []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "article":
            self.card = {"attrs": a, "text": "", "imgs": [], "links": []}
            self.cards.append(self.card)
        if tag == "img":
            self.all_imgs.append(a.get("src"))
        if self.card is not None and tag == "img":
            self.card["imgs"].append(urllib.parse.unquote(a.get("src")))
        if self.card is not None and tag == "a":
            self.card["links"].append(urllib.parse.unquote(a.get("href")))

    def handle_endtag(self, tag):
        if tag == "article":
            self.card = None

    def handle_data(self, data):
        if self.card is not None:
            self.card["text"] += data


def chromium():
    return shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which(
        "google-chrome")


if BROWSER and not chromium():
    print("SKIP: no Chromium on this machine (apt-get install chromium)")
    sys.exit(77)
shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)

library = json.load(open(os.path.join(LIBRARY, "library.json")))
records = {e["name"]: e for e in library["entries"]}
fitted = [n for n, e in records.items() if e["state"] == "fitted"]
failed = [n for n, e in records.items() if e["state"] == "failed"]
check(len(fitted) == 5 and failed == ["broken"], f"the library: fitted {fitted}, failed {failed}")

if BROWSER:
    browser = chromium()
    url = "file://" + os.path.abspath(os.path.join(LIBRARY, "index.html"))
    dom = subprocess.run([browser, "--headless", "--no-sandbox", "--disable-gpu",
                          "--virtual-time-budget=20000", "--dump-dom", url],
                         capture_output=True, text=True, timeout=180)
    match = re.search(r"images loaded: (\d+) of (\d+)", dom.stdout)
    print("browser:", match.group(0) if match else dom.stderr[-2000:])
    check(match is not None and match.group(1) == match.group(2) == str(len(fitted)),
          f"headless Chromium: every thumbnail loaded ({len(fitted)})")
    print("FAILED" if failures else "all ok")
    sys.exit(1 if failures else 0)

# ---- thumbnails and library.json ----
import jsonschema  # noqa: E402 (not needed by the browser check)

errors = list(jsonschema.Draft202012Validator(
    json.load(open(os.path.join(SCHEMA, "library.schema.json")))).iter_errors(library))
for e in errors:
    print("  schema:", "/".join(map(str, e.path)), e.message)
check(not errors, "library.json valid against its schema")
for name in fitted:
    thumb = records[name]["thumbnail"]
    path = os.path.join(LIBRARY, name, "thumbnail.png")
    check(thumb == f"{name}/thumbnail.png" and os.path.isfile(path),
          f"{name}: library.json's thumbnail {thumb!r} exists")
    w, h, _, _ = read_png(path) if os.path.isfile(path) else (0, 0, 0, 0)
    check((w, h) == (256, 256), f"{name}: thumbnail.png is 256 x 256 ({w} x {h})")
    timing = json.load(open(os.path.join(LIBRARY, name, "entry.json"))).get("timing", {})
    check(set(timing) == {"load", "fit", "presets", "report", "thumbnail"}
          and all(v >= 0 for v in timing.values()), f"{name}: entry.json's timing {timing}")
check(records["broken"]["thumbnail"] is None, "broken: no thumbnail")
# each entry's report has the interactive view when the three.js bundle was
# built beside clayfit (the tasks pass it on as `clayfit report` does)
if os.path.isfile(os.path.join(os.path.dirname(os.path.abspath(CLAYFIT)),
                               "clayfit-report-viewer.js")):
    for name in fitted:
        viewer = os.path.join(LIBRARY, name, "report", "viewer", "three_viewer.js")
        check(os.path.isfile(viewer), f"{name}: the report has its three.js view ({viewer})")

# ---- index.html: the same records ----
page = Page()
page.feed(open(os.path.join(LIBRARY, "index.html"), encoding="utf-8").read())
page.close()
check([json.loads(c["attrs"]["data-entry"])["name"] for c in page.cards] == list(records),
      "index.html: one card per entry, in the manifest's order")
for card in page.cards:
    data = json.loads(card["attrs"]["data-entry"])
    e = records[data["name"]]
    if e["state"] == "fitted":
        check(card["imgs"] == [e["thumbnail"]] and e["paths"]["report"] in card["links"]
              and data.get("rmse") == e["relative_rmse"] and e["model"] in card["text"],
              f"{e['name']}: card shows the thumbnail, model, RMSE, report link")
        for p in e["params"]:
            check(p in card["text"], f"{e['name']}: card shows {p}")
    else:
        reason = json.load(open(os.path.join(LIBRARY, e["name"], "failed.json")))["reason"]
        check("failed" in card["attrs"].get("class", "").split() and reason in card["text"]
              and "broken/failed.json" in card["links"] and not card["imgs"],
              f"{e['name']}: card marked failed, with its reason and failed.json")

# ---- compare: an entry with itself ----
out = os.path.join(WORK, "self")
r = run("library", "compare", LIBRARY, "glossy", "glossy", "-o", out)
print(r.stdout, r.stderr)
check(r.returncode == 0, "compare glossy glossy: exit 0")
doc = json.load(open(os.path.join(out, "compare.json")))
check(all(p["difference_sd"] == 0 for p in doc["params"]) and len(doc["params"]) >= 4,
      "itself: every parameter's difference 0")
check(doc["render"]["max_abs_difference"] == 0 and doc["render"]["rms_difference"] == 0,
      "itself: the renders' difference 0")
diff = rgb(read_png(os.path.join(out, "difference.png")))
check(all(row == bytes([247]) * len(row) for row in diff), "itself: difference.png all neutral")
check(rgb(read_png(os.path.join(out, "a.png"))) ==
      rgb(read_png(os.path.join(LIBRARY, "glossy", "thumbnail.png"))),
      "the compared render is the thumbnail, pixel for pixel")
for f in ("a.exr", "b.exr", "difference.exr", "compare.html", "b.png"):
    check(os.path.isfile(os.path.join(out, f)), f"-o wrote {f}")
printed = [line.split() for line in r.stdout.splitlines()]
check(all(row[-1] == "0" for row in printed if row and row[0].split(".")[0] in
          {p["name"] for p in doc["params"]}), "itself: printed differences 0")


# ---- compare: two entries ----
def flat(fit):
    """{name or name.channel: (value, sd)} of a fit.json."""
    out = {}
    for name, p in fit["params"].items():
        if isinstance(p["value"], list):
            for k, ch in enumerate("rgb"):
                out[f"{name}.{ch}"] = (p["value"][k], p["sd"][k])
        else:
            out[name] = (p["value"], p["sd"])
    return out


def expected_z(a, b):
    (va, sa), (vb, sb) = a, b
    sa, sb = sa or 0.0, sb or 0.0
    sd = math.sqrt(sa * sa + sb * sb)
    return (va - vb) / sd if sd > 0 else (0.0 if va == vb else None)


for A, B in (("oren", "budget"), ("glossy", "lambert"), ("lambert", "exposed")):
    out = os.path.join(WORK, f"{A}-{B}")
    r = run("library", "compare", LIBRARY, A, B, "-o", out)
    print(r.stdout, r.stderr)
    check(r.returncode == 0, f"compare {A} {B}: exit 0")
    fa = flat(json.load(open(os.path.join(LIBRARY, A, "fit.json"))))
    fb = flat(json.load(open(os.path.join(LIBRARY, B, "fit.json"))))
    doc = json.load(open(os.path.join(out, "compare.json")))
    lines = {row[0]: row for row in (l.split() for l in r.stdout.splitlines()) if row}
    for p in doc["params"]:
        key = p["name"] + (f".{p['channel']}" if p["channel"] else "")
        if key in fa and key in fb:
            want = expected_z(fa[key], fb[key])
            got = p["difference_sd"]
            same = got == want if want is None or got is None else \
                abs(got - want) <= 1e-12 * max(1.0, abs(want))
            shown = lines.get(key, [""])[-1]
            shown_ok = want is None or abs(float(shown) - want) <= 1e-5 * max(1.0, abs(want))
            check(same and shown_ok and p["in_a"] and p["in_b"],
                  f"{A}-{B} {key}: (a-b)/sd {got} printed {shown}, from fit.json {want}")
        else:
            check(p["in_a"] == (key in fa) and p["in_b"] == (key in fb)
                  and p["difference_sd"] is None and "(not in" in " ".join(lines.get(key, [])),
                  f"{A}-{B} {key}: only in {'A' if key in fa else 'B'}, marked")
    check({k for k in fa} | {k for k in fb} ==
          {p["name"] + (f".{p['channel']}" if p["channel"] else "") for p in doc["params"]},
          f"{A}-{B}: every parameter of both")
    if fa.keys() == fb.keys() and all(abs(fa[k][0] - fb[k][0]) <= 1e-9 * max(1.0, abs(fa[k][0]))
                                      for k in fa):
        # (lambert and exposed: one noise-free M0 sphere, the same albedo to
        # 1e-13 since every image's gain is found to be 1 exactly)
        check(doc["render"]["max_abs_difference"] <= 1e-6,
              f"{A}-{B}: the same material, the same renders "
              f"({doc['render']['max_abs_difference']:.3g})")
        continue
    check(doc["render"]["max_abs_difference"] > 0 and doc["render"]["difference_scale"] > 0,
          f"{A}-{B}: the renders differ ({doc['render']['max_abs_difference']:.3g})")
    diff = rgb(read_png(os.path.join(out, "difference.png")))
    check(any(row != bytes([247]) * len(row) for row in diff), f"{A}-{B}: difference.png not blank")

# ---- errors: exit 2, named ----
os.makedirs(os.path.join(WORK, "empty"), exist_ok=True)
for args, words in ((("nosuch", "glossy"), ["no entry 'nosuch'"]),
                    (("glossy", "broken"), ["'broken' failed", "no such file"]),
                    (("glossy", "../x"), ["not an entry name"]),):
    r = run("library", "compare", LIBRARY, *args)
    check(r.returncode == 2 and all(w in r.stderr for w in words) and r.stdout == "",
          f"compare {' '.join(args)}: exit 2, {r.stderr.strip()}")
r = run("library", "compare", os.path.join(WORK, "empty"), "a", "b")
check(r.returncode == 2 and "not a clayfit library" in r.stderr and "library.json" in r.stderr,
      f"not a library: {r.stderr.strip()}")
r = run("library", "compare", LIBRARY, "glossy")
check(r.returncode == 2, f"one entry only: exit 2 ({r.stderr.strip()})")
r = run("library", "frobnicate")
check(r.returncode == 2, f"unknown subcommand: exit 2 ({r.stderr.strip()})")

print("FAILED" if failures else "all ok")
sys.exit(1 if failures else 0)
