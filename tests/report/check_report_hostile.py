#!/usr/bin/env python3
"""Hostile names through fit and report (issue 16, item 2).

A small synthetic capture (clayfit synth) is rewritten so that its name, its
folder, its image names (a binary COLMAP model, whose names may hold
newlines) and the fit's folder hold markup: `</script><script>`, quotes,
`&amp;`, `-->`, triple quotes, backslashes, newlines and controls. It is fitted (M0)
and reported. Asserted on index.html (html.parser):
  - one <script> element (the page's own) and only the page's tags, no
    on* attribute;
  - the capture's name, both paths and every image name appear in the
    page's text as they are once the character references are read (a
    control character as U+FFFD), and each picture's alt text is its image
    name and kind;
  - the title holds the name;
and every SVG plot parses as XML. A capture name holding \\u0000 is refused
(exit 2) by fit, naming the file and the \\u0000; so is a fit.json holding
one by report (in clayfit's words, not Jansson's JSON_ALLOW_NUL).

usage: check_report_hostile.py CLAYFIT OUTDIR
"""
import html.parser
import json
import os
import re
import shutil
import struct
import subprocess
import sys
import xml.etree.ElementTree as ET

NAME = ('capture\n</title></script><script>alert("name")</script>\r\t"\' &amp; &lt; '
        '--> <!-- """ \\ \x1b[31m end-')
FOLDER = 'cap "q" \'q\' <b>&amp;</b> --> \\'
FIT_FOLDER = 'fit\n<script>alert("fit")</script> & "'
IMAGE_NAMES = ['i0\n<script>alert(0)</script>.png', 'i1 "dq" \'sq\' &amp; <b>.png',
               'i2 --> <!-- \\ """.png', 'i3 onerror=alert(3) x=".png']
PAGE_TAGS = {"html", "head", "meta", "title", "style", "body", "h1", "h2", "p", "code", "b",
             "table", "tr", "th", "td", "div", "img", "br", "svg", "defs", "lineargradient",
             "stop", "rect", "text", "script", "canvas", "a"}
# the material's view (docs/report.md): its two scripts, by these names only
VIEWER_SCRIPTS = ["viewer/material.js", "viewer/three_viewer.js"]
COLMAP_MODELS = {"SIMPLE_PINHOLE": 0, "PINHOLE": 1, "SIMPLE_RADIAL": 2, "RADIAL": 3, "OPENCV": 4}


def run(*args):
    r = subprocess.run(list(args), capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"{' '.join(map(str, args))}: exit {r.returncode}: {r.stderr}")
    return r


def data_lines(path):
    with open(path) as f:
        return [line.split() for line in f if line.strip() and not line.startswith("#")]


def write_binary_colmap(text_dir, out_dir, names):
    """The text model as COLMAP's binary one, the images renamed."""
    os.makedirs(out_dir)
    cameras = data_lines(os.path.join(text_dir, "cameras.txt"))
    with open(os.path.join(out_dir, "cameras.bin"), "wb") as f:
        f.write(struct.pack("<Q", len(cameras)))
        for c in cameras:
            f.write(struct.pack("<iiQQ", int(c[0]), COLMAP_MODELS[c[1]], int(c[2]), int(c[3])))
            f.write(struct.pack(f"<{len(c) - 4}d", *map(float, c[4:])))
    # images.txt: a line of pose and name, then a (here empty) line of points
    with open(os.path.join(text_dir, "images.txt")) as f:
        lines = [line.rstrip("\n") for line in f if not line.startswith("#")]
    images = [line.split() for line in lines[0::2] if line.strip()]
    with open(os.path.join(out_dir, "images.bin"), "wb") as f:
        f.write(struct.pack("<Q", len(images)))
        for k, im in enumerate(images):
            f.write(struct.pack("<i7di", int(im[0]), *map(float, im[1:8]), int(im[8])))
            f.write(names[k].encode() + b"\0")
            f.write(struct.pack("<Q", 0))
    with open(os.path.join(out_dir, "points3D.bin"), "wb") as f:
        f.write(struct.pack("<Q", 0))


def hostile_capture(clayfit, outdir):
    synth = os.path.join(outdir, "synth")
    run(clayfit, "--quiet", "synth", "-o", synth, "--model", "M0", "--images", "4", "--size",
        "64x48", "--format", "png16", "--no-noise", "--supersample", "1")
    cap = os.path.join(outdir, FOLDER)
    os.makedirs(os.path.join(cap, "images"))
    with open(os.path.join(synth, "capture.json")) as f:
        doc = json.load(f)
    for old, new in zip(doc["images"]["files"], IMAGE_NAMES):
        target = os.path.join(cap, "images", new)  # a '/' in a name: a subfolder
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.copy(os.path.join(synth, "images", old), target)
    write_binary_colmap(os.path.join(synth, "sparse", "0"), os.path.join(cap, "sparse", "0"),
                        IMAGE_NAMES)
    doc["name"] = NAME
    doc["images"]["files"] = IMAGE_NAMES
    path = os.path.join(cap, "capture.json")
    with open(path, "w") as f:
        json.dump(doc, f)
    return path, doc


class Page(html.parser.HTMLParser):
    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.tags, self.alts, self.text, self.title = [], [], [], ""
        self.in_title = False
        self.bad_attributes = []
        self.script_srcs = []

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        self.in_title = tag == "title"
        for key, value in attrs:
            if key.startswith("on"):
                self.bad_attributes.append((tag, key, value))
            if tag == "img" and key == "alt":
                self.alts.append(value)
            if tag == "script" and key == "src":
                self.script_srcs.append(value)

    def handle_endtag(self, tag):
        self.in_title = False

    def handle_data(self, data):
        self.text.append(data)
        if self.in_title:
            self.title += data


def shown(text):
    """What the page can show of a text: controls but tab, LF, CR as U+FFFD."""
    return re.sub("[\x00-\x08\x0b\x0c\x0e-\x1f\x7f-\x9f]", "\ufffd", text)


def check_page(report, fit_path, capture_path):
    failures = []
    with open(os.path.join(report, "index.html"), encoding="utf-8") as f:
        raw = f.read()
    page = Page()
    page.feed(raw)
    page.close()
    text = "".join(page.text)
    # the page's own inline script, and the material view's two (or none
    # when clayfit was built without the three.js bundle)
    viewer = VIEWER_SCRIPTS if page.script_srcs else []
    if page.tags.count("script") != 1 + len(viewer) or page.script_srcs not in ([], viewer):
        failures.append(f"{page.tags.count('script')} <script> elements "
                        f"({page.script_srcs}), expected the page's and {VIEWER_SCRIPTS}")
    # the glsl export as a classic script still parses with the hostile
    # names in its header's comments
    node = shutil.which("node")
    material = os.path.join(report, "viewer", "material.js")
    if node and subprocess.run([node, "--check", material], capture_output=True).returncode:
        failures.append("node --check refuses viewer/material.js")
    unknown = sorted(set(page.tags) - PAGE_TAGS)
    if unknown:
        failures.append(f"tags that are not the page's: {unknown}")
    if page.bad_attributes:
        failures.append(f"event attributes: {page.bad_attributes}")
    if re.search(r"[\x00-\x08\x0b\x0c\x0e-\x1f\x7f]", raw):
        failures.append("a control character in the page")
    for label, value in [("name", NAME), ("fit path", fit_path), ("capture path", capture_path)]:
        if shown(value) not in text:
            failures.append(f"{label} {value!r} not in the page's text")
    if shown(NAME) not in page.title:
        failures.append(f"the title {page.title!r} lacks the name")
    for name in IMAGE_NAMES:
        if shown(name) not in text:
            failures.append(f"image name {name!r} not in the page's text")
        for kind in ("photo", "render", "residual"):
            if f"{name} {kind}" not in page.alts:
                failures.append(f"no picture with alt {name + ' ' + kind!r}")
    return failures


def check_plots(report):
    failures = []
    for svg in sorted(os.listdir(os.path.join(report, "plots"))):
        if svg.endswith(".svg"):
            try:
                ET.parse(os.path.join(report, "plots", svg))
            except ET.ParseError as e:
                failures.append(f"plots/{svg}: {e}")
    return failures


def check_nul(clayfit, outdir, capture_doc, fit_path):
    failures = []
    bad = os.path.join(outdir, "nul")
    os.makedirs(bad)
    capture = os.path.join(bad, "capture.json")
    with open(capture, "w") as f:
        json.dump(dict(capture_doc, name="a\u0000b"), f)
    r = subprocess.run([clayfit, "--quiet", "fit", capture, "-o", os.path.join(bad, "fit")],
                       capture_output=True, text=True)
    if r.returncode != 2 or capture not in r.stderr or "\\u0000" not in r.stderr \
            or "JSON_ALLOW_NUL" in r.stderr:
        failures.append(f"fit of a capture named with a NUL: exit {r.returncode}: {r.stderr}")
    with open(fit_path) as f:
        fit = json.load(f)
    fit["capture"]["name"] = "a\u0000b"
    nul_fit = os.path.join(bad, "fit.json")
    with open(nul_fit, "w") as f:
        json.dump(fit, f)
    r = subprocess.run([clayfit, "--quiet", "report", nul_fit, "-o", os.path.join(bad, "report")],
                       capture_output=True, text=True)
    if r.returncode != 2 or nul_fit not in r.stderr or "\\u0000" not in r.stderr \
            or "JSON_ALLOW_NUL" in r.stderr:
        failures.append(f"report of a fit.json with a NUL: exit {r.returncode}: {r.stderr}")
    return failures


def main():
    clayfit, outdir = sys.argv[1], os.path.abspath(sys.argv[2])
    shutil.rmtree(outdir, ignore_errors=True)
    os.makedirs(outdir)
    capture_path, capture_doc = hostile_capture(clayfit, outdir)
    fit_dir = os.path.join(outdir, FIT_FOLDER)
    run(clayfit, "--quiet", "fit", capture_path, "-o", fit_dir, "--model", "M0")
    fit_path = os.path.join(fit_dir, "fit.json")
    report = os.path.join(outdir, "report")
    run(clayfit, "--quiet", "report", fit_path, "-o", report)
    with open(fit_path) as f:  # the capture as fit.json names it, from its folder
        written = json.load(f)["capture"]["path"]
    failures = check_page(report, fit_path, os.path.join(fit_dir, written))
    failures += check_plots(report)
    failures += check_nul(clayfit, outdir, capture_doc, fit_path)
    for f in failures:
        print(f)
    print(f"hostile report: {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
