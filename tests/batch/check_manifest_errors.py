#!/usr/bin/env python3
"""clayfit batch refuses a bad manifest before any work: exit 2, the
message naming the manifest file and the JSON path, no library written.

usage: check_manifest_errors.py CLAYFIT WORK_DIR"""
import json
import os
import shutil
import subprocess
import sys

CLAYFIT, WORK = sys.argv[1], sys.argv[2]
shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)
open(os.path.join(WORK, "capture.json"), "w").write("{}")  # exists; never loaded here
good = {"name": "a", "capture": "capture.json"}

# (what, the captures, the message that must appear after "manifest.json: ")
CASES = [
    ("a name with a slash", [{**good, "name": "../x"}], "captures[0].name: '../x' is not a name"),
    ("a name starting with '.'", [{**good, "name": ".hidden"}], "captures[0].name"),
    ("a name too long", [{**good, "name": "n" * 65}], "captures[0].name"),
    ("a duplicate", [good, {**good}], "captures[1].name: 'a' is also the name of captures[0]"),
    ("a duplicate but for case", [good, {**good, "name": "A"}], "captures[1].name"),
    ("a missing capture", [{**good, "capture": "nowhere/capture.json"}],
     "captures[0].capture: "),
    ("the library's own library.json", [good, {**good, "name": "library.json"}],
     "captures[1].name: 'library.json' is a name the library folder uses"),
    ("the library's own index.html, in capitals", [{**good, "name": "INDEX.html"}],
     "captures[0].name: 'INDEX.html' is a name the library folder uses"),
    ("library.json's temporary", [{**good, "name": "Library.Json.tmp-42"}],
     "captures[0].name: 'Library.Json.tmp-42' is a name the library folder uses"),
    ("a number for a name", [{**good, "name": 3}], "captures[0].name: expected a string"),
    ("a string for a bool", [{**good, "options": {"fit_exposures": "yes"}}],
     "captures[0].options.fit_exposures"),
    ("an unknown model", [{**good, "options": {"model": "M9"}}], "captures[0].options.model"),
    ("a budget too small", [{**good, "options": {"budget": 5}}], "captures[0].options.budget"),
    ("a budget word", [{**good, "options": {"budget": "most"}}], "captures[0].options.budget"),
    ("a hold of two numbers", [{**good, "options": {"hold": {"albedo": [1, 2]}}}],
     "captures[0].options.hold.albedo"),
    ("a hold no model has", [{**good, "options": {"hold": {"nonsense": 1}}}],
     "captures[0].options: --hold nonsense: no model of the ladder"),
    ("a hold the forced model lacks", [{**good, "options": {"model": "M0", "hold": {"f0": 0.04}}}],
     "captures[0].options: model M0 (lambert) has no parameter 'f0'"),
    ("a hold out of range", [{**good, "options": {"model": "M1", "hold": {"diffuse_roughness": 70}}}],
     "captures[0].options: "),
    ("an unknown option", [{**good, "options": {"modle": "M1"}}], "captures[0].options"),
    ("a tag not a string", [{**good, "tags": {"state": 1}}], "captures[0].tags.state"),
    ("no captures", [], "captures: no captures"),
]
failures = 0
for what, captures, message in CASES:
    manifest = os.path.join(WORK, "manifest.json")
    json.dump({"clayfit_manifest": 1, "captures": captures}, open(manifest, "w"))
    library = os.path.join(WORK, "library")
    shutil.rmtree(library, ignore_errors=True)  # one case failing does not fail the next
    r = subprocess.run([CLAYFIT, "batch", manifest, "-o", library], capture_output=True, text=True)
    ok = r.returncode == 2 and f"manifest.json: {message}" in r.stderr and not os.path.exists(library)
    print(("ok   " if ok else "FAIL ") + f"{what}: exit {r.returncode}: {r.stderr.strip()}")
    failures += not ok
sys.exit(1 if failures else 0)
