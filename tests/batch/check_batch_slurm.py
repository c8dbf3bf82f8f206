#!/usr/bin/env python3
"""clayfit batch --executor slurm on the private cluster (docs/batch.md).

usage: check_batch_slurm.py CLAYFIT SCHEMA_DIR WORK_DIR   (SLURM_CONF set)

The six small synthetic captures of check_batch.py, one broken on purpose,
into a library whose path holds a space and a quote (the job script must
quote it):
  - through Slurm: five fitted, each fit.json's model and parameters equal,
    to the bit, to a direct `clayfit fit` with the same --threads; one
    failed with its reason; library.json valid;
  - the local executor with the same --threads gives the same library.json
    and the same fit.json files, apart from timestamps, timings, hosts, pids;
  - the same command again submits nothing;
  - --dry-run prints a job script that `bash -n` accepts and submits nothing;
  - scancel of a running array element (a slow capture) leaves no partial
    entry but failed.json naming the Slurm task, and the next run fits it;
  - Ctrl-C cancels the job and leaves no partial entry;
  - sbatch failing or missing: exit 1 with its message.
Exits 77 without Slurm. Nothing about timing is asserted."""
import json
import os
import re
import shutil
import subprocess
import sys
import time

import jsonschema

from batch_captures import CAPTURES, check, clayfit_runner, finish, make_captures

CLAYFIT, SCHEMA, WORK = sys.argv[1], sys.argv[2], os.path.abspath(sys.argv[3])
if not shutil.which("sbatch"):
    print("skipped: slurm-wlm is not installed (scripts/install-deps.sh)")
    sys.exit(77)
if not os.path.exists(os.environ.get("SLURM_CONF", "")):
    print("FAIL: SLURM_CONF names no cluster (the slurm_start test sets it up)")
    sys.exit(1)
THREADS = "1"
run = clayfit_runner(CLAYFIT)


def synth(name, *extra):
    out = os.path.join(WORK, "captures", name)
    shutil.rmtree(out, ignore_errors=True)
    r = run("--quiet", "synth", "-o", out, *extra)
    assert r.returncode == 0, r.stderr
    return os.path.join(out, "capture.json")


def jobs():
    """The ids of the jobs that run in the library (finished ones too, for
    MinJobAge); other tests submit to the same cluster at the same time."""
    r = subprocess.run(["squeue", "-h", "-t", "all", "-o", "%F|%Z"], capture_output=True,
                       text=True)
    assert r.returncode == 0, r.stderr
    return {line.split("|", 1)[0] for line in r.stdout.splitlines()
            if line.split("|", 1)[1] == LIBRARY}


def batch(library, *extra):
    return run("batch", MANIFEST, "-o", library, "--threads", THREADS, *extra)


def slurm(*extra):
    return batch(LIBRARY, "--executor", "slurm", *extra)


VARYING = {"created", "timing", "seconds", "host", "pid", "started", "ended", "wall_seconds",
           "cpu_seconds"}


def steady(doc):
    """doc without what differs from run to run: times, timings, hosts, pids."""
    if isinstance(doc, dict):
        return {k: steady(v) for k, v in doc.items() if k not in VARYING}
    if isinstance(doc, list):
        return [steady(v) for v in doc]
    return doc


shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)
MANIFEST = os.path.join(WORK, "manifest.json")
LIBRARY = os.path.join(WORK, "library x'y")
LOCAL = os.path.join(WORK, "local")
manifest = make_captures(run, WORK, MANIFEST)

# ---- through Slurm: 5 fitted, 1 failed ----
r = slurm()
print(r.stdout, r.stderr)
first_job = (re.findall(r"submitted Slurm job (\d+)", r.stdout) or [None])[0]
check(r.returncode == 1, f"a failed entry: exit 1 (got {r.returncode})")
check("6 to fit" in r.stdout and "submitted Slurm job" in r.stdout, "six to fit, one job")
check("failed: broken:" in r.stderr and "no such file" in r.stderr, "the failure named")
fitted = [n for n in CAPTURES if n != "broken"]
for name in fitted:
    flags = CAPTURES[name][2]
    direct = os.path.join(WORK, "direct", name)
    d = run("--quiet", "fit", os.path.join(WORK, "captures", name, "capture.json"), "-o", direct,
            "--threads", THREADS, *flags)
    assert d.returncode == 0, d.stderr
    path = os.path.join(LIBRARY, name, "fit.json")
    a = json.load(open(path)) if os.path.exists(path) else {}
    b = json.load(open(os.path.join(direct, "fit.json")))
    check(a.get("model") == b["model"] and a.get("params") == b["params"],
          f"{name}: parameters equal to clayfit fit's, to the bit")
    check(os.path.exists(os.path.join(LIBRARY, name, "report", "index.html")), f"{name}: report")
failed = json.load(open(os.path.join(LIBRARY, "broken", "failed.json")))
check("no such file" in failed["reason"], f"broken: its reason ({failed['reason']})")
library = json.load(open(os.path.join(LIBRARY, "library.json")))
errors = list(jsonschema.Draft202012Validator(
    json.load(open(os.path.join(SCHEMA, "library.schema.json")))).iter_errors(library))
for e in errors:
    print("  schema:", "/".join(map(str, e.path)), e.message)
check(not errors, "library.json valid against its schema")
states = {e["name"]: e["state"] for e in library["entries"]}
check(states == {**{n: "fitted" for n in fitted}, "broken": "failed"}, f"states {states}")
logs = os.listdir(os.path.join(LIBRARY, ".slurm", "logs"))
check(len(logs) == 6 and all(re.fullmatch(r"\d+_\d\.out", f) for f in logs),
      f"a log per task in LIBRARY/.slurm/logs ({logs})")

# ---- the local executor: the same library ----
r = batch(LOCAL, "--jobs", "2")
check(r.returncode == 1 and "6 to fit" in r.stdout, "local: the same six, one failed")
local = json.load(open(os.path.join(LOCAL, "library.json")))
check(steady(local) == steady(library), "local: the same library.json")
for name in fitted:
    a = json.load(open(os.path.join(LIBRARY, name, "fit.json")))
    b = json.load(open(os.path.join(LOCAL, name, "fit.json")))
    check(steady(a) == steady(b), f"local: {name}/fit.json the same but for times")

# ---- again: nothing submitted ----
known = jobs()
check(known == {first_job}, f"squeue lists the first run's job {first_job} ({known})")
r = slurm()
check(r.returncode == 1 and "0 to fit" in r.stdout and "submitted" not in r.stdout,
      "again: 0 to fit, nothing submitted")
check(jobs() == known, "again: no new job in squeue")

# ---- --dry-run: a script bash accepts, nothing submitted ----
r = slurm("--force", "--dry-run", "--partition", "local", "--time", "10:00",
          "--sbatch-arg", "--comment=a b")
print(r.stdout, r.stderr)
script = r.stdout.split("\n")[1].removeprefix("# ") if r.returncode == 0 else ""
check(r.returncode == 0 and os.path.isfile(script) and script.startswith(
    os.path.join(LIBRARY, ".slurm", "job-")), f"dry run: the script in .slurm ({script})")
check("'--comment=a b'" in r.stdout and "--partition=local" in r.stdout
      and "--array=0-5%16" in r.stdout, "dry run: the sbatch command, quoted")
n = subprocess.run(["bash", "-n", script], capture_output=True, text=True) if script else None
check(n is not None and n.returncode == 0, f"dry run: bash -n accepts the script")
check(jobs() == known, "dry run: no new job in squeue")
check(not os.path.exists(os.path.join(LIBRARY, ".lock")), "dry run: the lock released")

# ---- scancel of a running element ----
# glossy, made slow (16 images of 640x480, every observation, auto): gone,
# then fitted alone; its element cancelled once it runs and has started.
synth("glossy", "--images", "16", "--format", "exr", "--no-noise", "--supersample", "1",
      "--model", "M2", "--param", "roughness=0.3")
manifest["captures"][2]["options"] = {"budget": "all"}
json.dump(manifest, open(MANIFEST, "w"), indent=1)
shutil.rmtree(os.path.join(LIBRARY, "glossy"))
proc = subprocess.Popen([CLAYFIT, "batch", MANIFEST, "-o", LIBRARY, "--threads", THREADS,
                         "--executor", "slurm"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                        text=True)
job = None
for line in proc.stdout:
    m = re.match(r"submitted Slurm job (\d+)", line)
    if m:
        job = m.group(1)
        break
cancelled = False
deadline = time.monotonic() + 120
while job and not cancelled and proc.poll() is None and time.monotonic() < deadline:
    states = subprocess.run(["squeue", "-h", "-r", "-t", "all", "-j", job, "-o", "%K %T"],
                            capture_output=True, text=True).stdout.split()
    started = any(f.startswith(".tmp.glossy.") for f in os.listdir(LIBRARY))
    if states == ["0", "RUNNING"] and started:
        subprocess.run(["scancel", f"{job}_0"], check=True)
        cancelled = True
    time.sleep(0.05)
out, err = proc.communicate()
print(out, err)
check(cancelled, f"scancel {job}_0 while it ran")
check(proc.returncode == 1 and "glossy killed" in err, "scancel: exit 1, glossy named killed")
left = sorted(f for f in os.listdir(LIBRARY) if f.startswith((".tmp.", ".old.", ".lock")))
check(left == [], f"scancel: no leftover ({left})")
glossy = os.path.join(LIBRARY, "glossy")
died = json.load(open(os.path.join(glossy, "failed.json"))) if os.path.exists(
    os.path.join(glossy, "failed.json")) else {}
check(sorted(os.listdir(glossy)) == ["failed.json"] and f"Slurm task {job}_0" in died["reason"]
      and ".slurm/logs/" in died["reason"] and died.get("retry") is True,
      f"scancel: no partial entry, failed.json says why ({died.get('reason')})")
library = json.load(open(os.path.join(LIBRARY, "library.json")))
check(next(e for e in library["entries"] if e["name"] == "glossy")["state"] == "failed",
      "scancel: library.json says failed")
r = slurm()
print(r.stdout, r.stderr)
check("1 to fit" in r.stdout and os.path.exists(os.path.join(glossy, "entry.json"))
      and os.path.exists(os.path.join(glossy, "report", "index.html")),
      "scancel: the next run fits it whole")

# ---- Ctrl-C: the job cancelled, no partial entry ----
proc = subprocess.Popen([CLAYFIT, "batch", MANIFEST, "-o", LIBRARY, "--threads", THREADS,
                         "--executor", "slurm", "--force"], stdout=subprocess.PIPE,
                        stderr=subprocess.PIPE, text=True)
job = next((m.group(1) for line in proc.stdout
            for m in [re.match(r"submitted Slurm job (\d+)", line)] if m), None)
deadline = time.monotonic() + 120
while job and proc.poll() is None and time.monotonic() < deadline and not any(
        f.startswith(".tmp.glossy.") for f in os.listdir(LIBRARY)):
    time.sleep(0.05)
proc.send_signal(2)
out, err = proc.communicate()
live = subprocess.run(["squeue", "-h", "-r", "-j", job or "0", "-t", "PENDING,RUNNING,COMPLETING",
                       "-o", "%K %T"], capture_output=True, text=True).stdout.strip()
check(job and proc.returncode == 1 and "interrupted: Slurm job" in err and live == "",
      f"Ctrl-C: exit 1, the job cancelled ({err.strip()}; still live: '{live}')")
left = sorted(f for f in os.listdir(LIBRARY) if f.startswith((".tmp.", ".old.", ".lock")))
check(left == [] and os.path.exists(os.path.join(glossy, "report", "index.html")),
      f"Ctrl-C: no leftover, glossy whole ({left})")

# ---- sbatch failing, or missing: exit 1 with its message ----
r = slurm("--force", "--partition", "no-such-partition")
check(r.returncode == 1 and "sbatch failed" in r.stderr and "partition" in r.stderr,
      f"sbatch failing: exit 1, its stderr ({r.stderr.strip()})")
r = run("batch", MANIFEST, "-o", LIBRARY, "--executor", "slurm", "--force",
        env={**os.environ, "PATH": "/nonexistent"})
check(r.returncode == 1 and "cannot run sbatch" in r.stderr, f"no sbatch: exit 1 ({r.stderr.strip()})")

finish()
