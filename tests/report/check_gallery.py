#!/usr/bin/env python3
"""Checks the gallery page that test_gallery wrote into DIR (index.html, and
expected.tsv: each entry's name, thumbnail path and relative RMSE):

- the HTML is well formed (every element closed in order, html.parser);
- the page has exactly one <script> (its own) and no element a name, tag or
  reason could have made: every hostile string shows as text;
- a card per entry, in order, each card's data-entry JSON names it; the
  failed one is marked failed with its reason; every thumbnail path is
  referenced and exists; every link and image is a relative path (no
  scheme, nothing fetched from the network);
- the sort and filter controls are there (name, RMSE, model, parameter;
  text, state, tag, parameter range).

With --browser SCREENSHOT (exit 77 without Chromium, as the report's browser
test): in headless Chromium every thumbnail loads (naturalWidth > 0), and,
through a harness page that drives the gallery in a frame, clicking "sort
by relative RMSE" orders the cards by RMSE (a second click reverses it,
the failed entry stays last), the text and tag filters hide the right
cards; a screenshot of the page is taken.

usage: check_gallery.py DIR [--browser SCREENSHOT]"""
import html.parser
import json
import os
import re
import shutil
import subprocess
import sys
import urllib.parse

VOID = {"meta", "img", "input", "br", "hr", "link", "area", "base", "col", "embed", "source",
        "track", "wbr"}


class Page(html.parser.HTMLParser):
    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.stack, self.errors, self.tags = [], [], []
        self.cards, self.text, self.ids = [], [], set()
        self.card = None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        self.tags.append((tag, a))
        if "id" in a:
            self.ids.add(a["id"])
        if tag == "article":
            self.card = {"attrs": a, "h2": "", "text": "", "imgs": [], "links": []}
            self.cards.append(self.card)
        if self.card is not None and tag == "img":
            self.card["imgs"].append(a.get("src"))
        if self.card is not None and tag == "a":
            self.card["links"].append(a.get("href"))
        if tag not in VOID:
            self.stack.append(tag)

    def handle_endtag(self, tag):
        if tag in VOID:
            return
        if not self.stack or self.stack[-1] != tag:
            self.errors.append(f"</{tag}> closes <{self.stack[-1] if self.stack else None}>")
            return
        self.stack.pop()
        if tag == "article":
            self.card = None

    def handle_data(self, data):
        self.text.append(data)
        if self.card is not None:
            self.card["text"] += data
            if self.stack and self.stack[-1] == "h2":
                self.card["h2"] += data


def check_static(folder):
    failures = []
    raw = open(os.path.join(folder, "index.html"), encoding="utf-8").read()
    expected = [line.rstrip("\n").split("\t") for line in
                open(os.path.join(folder, "expected.tsv"), encoding="utf-8")]
    page = Page()
    page.feed(raw)
    page.close()
    if page.errors or page.stack:
        failures.append(f"malformed HTML: {page.errors[:5]}, unclosed {page.stack}")
    scripts = [t for t, _ in page.tags if t == "script"]
    if len(scripts) != 1 or len(re.findall(r"<script", raw, re.I)) != 1:
        failures.append(f"{len(scripts)} script elements, {len(re.findall('<script', raw, re.I))} "
                        "'<script' in the source (expected the page's one)")
    allowed = {"html", "head", "meta", "title", "style", "body", "h1", "p", "span", "form",
               "noscript", "div", "button", "label", "select", "option", "input", "main",
               "article", "img", "h2", "ul", "li", "b", "table", "tr", "th", "td", "a", "script"}
    stray = {t for t, _ in page.tags} - allowed
    if stray:
        failures.append(f"elements the writer never writes (from a name?): {stray}")
    if "<!--" in raw:
        failures.append("a comment opener '<!--' in the source (from a name?)")
    if len(page.cards) != len(expected):
        failures.append(f"{len(page.cards)} cards for {len(expected)} entries")
    text = "".join(page.text)
    for card, (name, thumb, rmse) in zip(page.cards, expected):
        data = json.loads(card["attrs"].get("data-entry", "{}"))
        if card["h2"] != name or data.get("name") != name:
            failures.append(f"card {card['h2']!r} (data {data.get('name')!r}) for {name!r}")
        want_rmse = None if rmse == "nan" else float(rmse)
        if data.get("rmse") != want_rmse:
            failures.append(f"{name!r}: rmse {data.get('rmse')} for {want_rmse}")
        if thumb:
            srcs = [urllib.parse.unquote(s) for s in card["imgs"]]
            if srcs != [thumb]:
                failures.append(f"{name!r}: images {card['imgs']} for {thumb!r}")
            if not os.path.isfile(os.path.join(folder, thumb)):
                failures.append(f"{thumb!r} does not exist")
        failed = "failed" in card["attrs"].get("class", "").split()
        if failed != (not thumb):
            failures.append(f"{name!r}: class {card['attrs'].get('class')!r}")
        if failed and ("failed" not in card["text"] or "</script><script>alert(3)" not in
                       card["text"]):
            failures.append(f"{name!r}: the failure and its reason are not shown as text")
        for url in card["imgs"] + card["links"]:
            parsed = urllib.parse.urlsplit(url)
            if parsed.scheme or parsed.netloc or url.startswith("/"):
                failures.append(f"{name!r}: {url!r} is not a relative path")
            if not os.path.exists(os.path.join(folder, urllib.parse.unquote(url))):
                failures.append(f"{name!r}: {url!r} names no file")
    for hostile in ["</script><script>x", "wet </script>", "porcelain -->", "'y'",
                    "Library </title><script>t</script>"]:
        if hostile not in text:
            failures.append(f"{hostile!r} is not shown as text")
    if re.search(r"(src|href)=\"(https?:)?//", raw):
        failures.append("something is fetched from the network")
    for control in ["sort-param", "filter-text", "filter-state", "filter-param", "filter-min",
                    "filter-max", "loaded"]:
        if control not in page.ids:
            failures.append(f"no #{control}")
    sorts = {a.get("data-sort") for t, a in page.tags if t == "button"}
    if not {"name", "rmse", "model"} <= sorts:
        failures.append(f"sort buttons {sorts}")
    tag_keys = {a.get("data-key") for t, a in page.tags if t == "select" and
                a.get("class") == "tag-filter"}
    if tag_keys != {"clay body", "state", "</script><script>x"}:
        failures.append(f"tag filters {tag_keys}")
    options = {a.get("value") for t, a in page.tags if t == "option"}
    if not {"albedo", "albedo r", "film_roughness", "dry"} <= options:
        failures.append("parameter or tag options missing")
    print(f"{len(page.cards)} cards, {len(page.tags)} elements, controls present")
    return failures, expected


HARNESS = """<!DOCTYPE html><html><head><meta charset="utf-8"></head><body>
<pre id="result">not run</pre>
<iframe id="g" src="%s" width="1400" height="2000"></iframe>
<script>
var frame = document.getElementById('g'), out = {};
function order(d) {
  return Array.prototype.slice.call(d.querySelectorAll('article.card'))
      .filter(function (c) { return !c.hidden; })
      .map(function (c) { return JSON.parse(c.getAttribute('data-entry')).name; });
}
frame.addEventListener('load', function () {
  try {
    var d = frame.contentDocument, w = frame.contentWindow;
    var imgs = d.images, ok = 0;
    for (var i = 0; i < imgs.length; ++i) if (imgs[i].complete && imgs[i].naturalWidth > 0) ++ok;
    out.images = [ok, imgs.length];
    out.initial = order(d);
    var rmse = d.querySelector('button[data-sort="rmse"]');
    rmse.click(); out.rmse_up = order(d);
    rmse.click(); out.rmse_down = order(d);
    var text = d.getElementById('filter-text');
    text.value = 'PORCELAIN'; text.dispatchEvent(new w.Event('input'));
    out.text_filter = order(d);
    text.value = ''; text.dispatchEvent(new w.Event('input'));
    var state = d.querySelector('select.tag-filter[data-key="state"]');
    state.value = 'dry'; state.dispatchEvent(new w.Event('change'));
    out.tag_filter = order(d);
    out.shown = d.getElementById('shown').textContent;
  } catch (e) { out.error = String(e); }
  document.getElementById('result').textContent = 'RESULT' + JSON.stringify(out) + 'END';
});
</script></body></html>
"""


def chromium():
    return shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which(
        "google-chrome")


def check_browser(folder, screenshot, expected):
    browser = chromium()
    failures = []
    common = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
              "--virtual-time-budget=20000", "--window-size=1400,1100"]
    url = "file://" + os.path.abspath(os.path.join(folder, "index.html"))
    shot = subprocess.run(common + [f"--screenshot={screenshot}", url], capture_output=True,
                          text=True, timeout=180)
    if shot.returncode != 0 or not os.path.isfile(screenshot) or os.path.getsize(screenshot) < 10000:
        failures.append(f"no screenshot: {shot.stderr[-2000:]}")
    dom = subprocess.run(common + ["--dump-dom", url], capture_output=True, text=True, timeout=180)
    match = re.search(r"images loaded: (\d+) of (\d+)", dom.stdout)
    thumbs = sum(1 for _, t, _ in expected if t)
    if not match or int(match.group(1)) != thumbs or int(match.group(2)) != thumbs:
        failures.append(f"the page's own count: {match.group(0) if match else 'did not run'} "
                        f"(expected {thumbs} of {thumbs})")
    harness = os.path.join(folder, "harness.html")
    with open(harness, "w", encoding="utf-8") as f:
        f.write(HARNESS % "index.html")
    dom = subprocess.run(common + ["--allow-file-access-from-files", "--dump-dom",
                                   "file://" + os.path.abspath(harness)],
                         capture_output=True, text=True, timeout=180)
    match = re.search(r'<pre id="result">RESULT(.*?)END</pre>', dom.stdout, re.S)
    if not match:
        return failures + [f"the harness did not run: {dom.stderr[-2000:]}"]
    got = json.loads(html.unescape(match.group(1)))  # the <pre>'s text, serialised
    print("browser:", json.dumps(got, ensure_ascii=False))
    if got.get("error"):
        return failures + [f"harness: {got['error']}"]
    names = [n for n, _, _ in expected]
    rmse = {n: (None if r == "nan" else float(r)) for n, _, r in expected}
    known = sorted([n for n in names if rmse[n] is not None], key=lambda n: rmse[n])
    missing = [n for n in names if rmse[n] is None]
    if got["images"] != [thumbs, thumbs]:
        failures.append(f"thumbnails loaded {got['images']}, expected {thumbs} of {thumbs}")
    if got["initial"] != names:
        failures.append(f"initial order {got['initial']}")
    if got["rmse_up"] != known + missing:
        failures.append(f"sorted by RMSE: {got['rmse_up']}, expected {known + missing}")
    if got["rmse_down"] != known[::-1] + missing:
        failures.append(f"sorted by RMSE descending: {got['rmse_down']}")
    if got["rmse_up"] == got["initial"]:
        failures.append("sorting by RMSE did not reorder the cards")
    if got["text_filter"] != [names[1]]:
        failures.append(f"text filter 'PORCELAIN': {got['text_filter']}")
    if sorted(got["tag_filter"]) != sorted([names[0], names[3]]):
        failures.append(f"tag filter state=dry: {got['tag_filter']}")
    return failures


def main():
    folder = sys.argv[1]
    browser = len(sys.argv) == 4 and sys.argv[2] == "--browser"
    if browser and not chromium():
        print("SKIP: no Chromium on this machine (apt-get install chromium)")
        return 77
    failures, expected = check_static(folder)
    if browser:
        failures += check_browser(folder, sys.argv[3], expected)
    for f in failures:
        print("FAIL:", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
