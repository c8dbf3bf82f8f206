#!/usr/bin/env python3
"""clayfit batch with the local executor, end to end (docs/batch.md).

usage: check_batch.py CLAYFIT SCHEMA_DIR WORK_DIR

Six small synthetic captures, one broken on purpose (an image deleted):
  - five fitted, each fit.json's model and parameters equal, to the bit, to
    a direct `clayfit fit` of the same capture, options and --threads;
  - one failed, its reason in failed.json; library.json valid;
  - the same command again fits nothing and touches no entry;
  - after one capture's images change, exactly that entry is re-fitted;
  - a worker SIGKILLed mid-fit leaves no partial entry and no leftover
    once the next run, which completes it, has cleaned;
  - a stale lock (a dead pid of this host) is taken over, a live one
    refused;
  - Ctrl-C kills the workers and leaves no partial entry.
Nothing about timing is asserted."""
import json
import os
import shutil
import socket
import subprocess
import sys
import time

import jsonschema

from batch_captures import CAPTURES, SYNTH, check, clayfit_runner, finish, make_captures

CLAYFIT, SCHEMA, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
THREADS = "1"
run = clayfit_runner(CLAYFIT)


def synth(name, extra=()):
    spec = CAPTURES[name][0]
    out = os.path.join(WORK, "captures", name)
    r = run("--quiet", "synth", "-o", out, *SYNTH, *spec, *extra)
    assert r.returncode == 0, r.stderr
    return os.path.join(out, "capture.json")


def batch(*extra):
    return run("batch", MANIFEST, "-o", LIBRARY, "--jobs", "2", "--threads", THREADS, *extra)


def entry_stamp(name):
    """entry.json's (mtime, key, pid) or failed.json's, None when absent."""
    for file in ("entry.json", "failed.json"):
        path = os.path.join(LIBRARY, name, file)
        if os.path.exists(path):
            doc = json.load(open(path))
            return (os.stat(path).st_mtime_ns, doc["key"], doc["pid"])
    return None


def leftovers():
    return sorted(f for f in os.listdir(LIBRARY) if f.startswith((".tmp.", ".old.", ".lock.")))


shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)
MANIFEST = os.path.join(WORK, "manifest.json")
LIBRARY = os.path.join(WORK, "library")
manifest = make_captures(run, WORK, MANIFEST)
jsonschema.validate(manifest, json.load(open(os.path.join(SCHEMA, "manifest.schema.json"))))

# ---- the first run: 5 fitted, 1 failed ----
r = batch()
print(r.stdout, r.stderr)
check(r.returncode == 1, f"a failed entry: exit 1 (got {r.returncode})")
check("failed: broken:" in r.stderr and "no such file" in r.stderr, "the failure named")
check("6 to fit" in r.stdout, "six to fit")
fitted = [n for n in CAPTURES if n != "broken"]
for name in fitted:
    check(os.path.exists(os.path.join(LIBRARY, name, "entry.json")), f"{name}: entry.json")
    for f in ("fit.json", "report/index.html", "presets/preset.json", "presets/material.mtlx",
              "presets/material.openpbr.mtlx", "presets/material.gltf", "presets/material.py",
              "presets/material.xml"):
        check(os.path.exists(os.path.join(LIBRARY, name, f)), f"{name}: {f}")
failed = json.load(open(os.path.join(LIBRARY, "broken", "failed.json")))
check("no such file" in failed["reason"] and failed["log"], "broken: failed.json has reason and log")
check(not os.path.exists(os.path.join(LIBRARY, "broken", "fit.json")), "broken: no fit.json")

# to the bit: the same capture through clayfit fit with the same threads
for name in fitted:
    flags = CAPTURES[name][2]
    direct = os.path.join(WORK, "direct", name)
    r = run("--quiet", "fit", os.path.join(WORK, "captures", name, "capture.json"), "-o", direct,
            "--threads", THREADS, *flags)
    assert r.returncode == 0, r.stderr
    a = json.load(open(os.path.join(LIBRARY, name, "fit.json")))
    b = json.load(open(os.path.join(direct, "fit.json")))
    check(a["model"] == b["model"] and a["params"] == b["params"],
          f"{name}: parameters equal to clayfit fit's ({a['model']['code']})")

library = json.load(open(os.path.join(LIBRARY, "library.json")))
errors = list(jsonschema.Draft202012Validator(
    json.load(open(os.path.join(SCHEMA, "library.schema.json")))).iter_errors(library))
for e in errors:
    print("  schema:", "/".join(map(str, e.path)), e.message)
check(not errors, "library.json valid against its schema")
states = {e["name"]: e["state"] for e in library["entries"]}
check(states == {**{n: "fitted" for n in fitted}, "broken": "failed"}, f"states {states}")
glossy = next(e for e in library["entries"] if e["name"] == "glossy")
fit_glossy = json.load(open(os.path.join(LIBRARY, "glossy", "fit.json")))
check(glossy["params"]["f0"]["value"] == fit_glossy["params"]["f0"]["value"] == 0.05
      and glossy["params"]["f0"]["status"] == "held", "library.json: the held f0")
check(glossy["tags"]["body"] == "porcelain" and glossy["thumbnail"] == "glossy/thumbnail.png",
      "tags, thumbnail")

# ---- the same command again: nothing to do ----
before = {n: entry_stamp(n) for n in CAPTURES}
r = batch()
check("0 to fit" in r.stdout, "again: 0 to fit")
check(r.returncode == 1 and "failed: broken:" in r.stderr, "again: the failed one still named")
check({n: entry_stamp(n) for n in CAPTURES} == before, "again: no entry touched")

# ---- one capture changed: exactly it re-fitted ----
synth("budget", ["--param", "diffuse_roughness=0.5"])
r = batch()
check("1 to fit" in r.stdout, "changed: 1 to fit")
after = {n: entry_stamp(n) for n in CAPTURES}
check(after["budget"] != before["budget"] and after["budget"][1] != before["budget"][1],
      "changed: its key and entry new")
check(all(after[n] == before[n] for n in CAPTURES if n != "budget"), "changed: others untouched")

# ---- the COLMAP model's files and the options are in the key too ----
with open(os.path.join(WORK, "captures", "lambert", "sparse", "0", "cameras.txt"), "a") as f:
    f.write("# a comment: the file changed, the model not\n")
r = batch()
check("1 to fit" in r.stdout and entry_stamp("lambert") != after["lambert"],
      "a COLMAP file changed: exactly that entry re-fitted")
manifest["captures"][1]["options"]["fit_exposures"] = False
json.dump(manifest, open(MANIFEST, "w"), indent=1)
r = batch()
check("1 to fit" in r.stdout and entry_stamp("oren") != after["oren"],
      "an option changed: exactly that entry re-fitted")

# ---- a worker killed in mid-fit ----
synth("glossy", ["--seed", "7"])
old_key = entry_stamp("glossy")[1]
proc = subprocess.Popen([CLAYFIT, "batch", MANIFEST, "-o", LIBRARY, "--jobs", "1", "--threads",
                         THREADS], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
killed = None
deadline = time.monotonic() + 60
while killed is None and proc.poll() is None and time.monotonic() < deadline:
    for f in os.listdir(LIBRARY):
        if f.startswith(".tmp.glossy."):
            killed = int(f.rsplit(".", 1)[1])
            os.kill(killed, 9)
            break
    time.sleep(0.001)
out, err = proc.communicate()
print(out, err)
check(killed is not None, "killed the worker of glossy mid-task")
check(proc.returncode == 1 and "glossy killed" in err, "killed: exit 1, glossy named")
check(leftovers() == [], f"killed: no leftover after the run ({leftovers()})")
stamp = entry_stamp("glossy")
check(stamp is None or (stamp[1] == old_key and
                        os.path.exists(os.path.join(LIBRARY, "glossy", "fit.json"))),
      "killed: the old entry whole (or none), never a partial one")
r = batch()
check("1 to fit" in r.stdout and entry_stamp("glossy")[1] != old_key, "killed: the next run completes it")
check(os.path.exists(os.path.join(LIBRARY, "glossy", "report", "index.html")), "killed: whole now")

# ---- leftovers of dead tasks, by their exact pattern only ----
os.makedirs(os.path.join(LIBRARY, ".tmp.lambert.999999999"))
os.makedirs(os.path.join(LIBRARY, ".tmp.not a name.1"))
shutil.move(os.path.join(LIBRARY, "oren"), os.path.join(LIBRARY, ".old.oren.999999999"))
r = batch()
check("0 to fit" in r.stdout, f"a kill between the renames: the old entry back, 0 to fit")
check(not os.path.exists(os.path.join(LIBRARY, ".tmp.lambert.999999999"))
      and os.path.exists(os.path.join(LIBRARY, ".tmp.not a name.1")), "only the pattern cleaned")
shutil.rmtree(os.path.join(LIBRARY, ".tmp.not a name.1"))

# ---- the lock ----
dead = subprocess.Popen(["true"])
dead.wait()
os.makedirs(os.path.join(LIBRARY, ".lock"))
json.dump({"host": socket.gethostname(), "pid": dead.pid, "start_ticks": 1},
          open(os.path.join(LIBRARY, ".lock", "owner.json"), "w"))
r = batch()
check("took over the stale lock" in r.stderr and "0 to fit" in r.stdout, "a dead owner's lock taken over")
check(not os.path.exists(os.path.join(LIBRARY, ".lock")), "the lock released")
with open(f"/proc/{os.getpid()}/stat") as f:
    start = int(f.read().rsplit(")", 1)[1].split()[19])
os.makedirs(os.path.join(LIBRARY, ".lock"))
json.dump({"host": socket.gethostname(), "pid": os.getpid(), "start_ticks": start},
          open(os.path.join(LIBRARY, ".lock", "owner.json"), "w"))
r = batch()
check(r.returncode == 1 and f"locked by process {os.getpid()}" in r.stderr and r.stdout == "",
      f"a live owner's lock refused: {r.stderr.strip()}")
shutil.rmtree(os.path.join(LIBRARY, ".lock"))

# ---- Ctrl-C: the workers killed, no partial entry, the next run completes ----
proc = subprocess.Popen([CLAYFIT, "batch", MANIFEST, "-o", LIBRARY, "--jobs", "2", "--threads",
                         THREADS, "--force"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                        text=True)
workers = set()
deadline = time.monotonic() + 60
while not workers and proc.poll() is None and time.monotonic() < deadline:
    workers = {int(f.rsplit(".", 1)[1]) for f in os.listdir(LIBRARY) if f.startswith(".tmp.")}
    time.sleep(0.001)
proc.send_signal(2)
out, err = proc.communicate()
check(workers and proc.returncode == 1 and "interrupted" in err, f"Ctrl-C: exit 1 ({err.strip()})")
check(not any(os.path.exists(f"/proc/{pid}") for pid in workers), "Ctrl-C: the workers gone")
check(leftovers() == [] and not os.path.exists(os.path.join(LIBRARY, ".lock")),
      f"Ctrl-C: no leftover, no lock ({leftovers()})")
whole = all(os.path.exists(os.path.join(LIBRARY, n, "failed.json")) or
            (os.path.exists(os.path.join(LIBRARY, n, "entry.json")) and
             os.path.exists(os.path.join(LIBRARY, n, "report", "index.html")))
            for n in CAPTURES if os.path.exists(os.path.join(LIBRARY, n)))
check(whole, "Ctrl-C: every entry there is whole")
r = batch()
check(r.returncode == 1 and "failed: broken:" in r.stderr
      and all(entry_stamp(n) for n in CAPTURES), "Ctrl-C: the next run completes the library")

finish()
