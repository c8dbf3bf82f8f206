#!/usr/bin/env python3
"""clayfit batch under hostile conditions: a library never loses a good
entry (docs/batch.md, "What a batch does on each failure").

usage: check_batch_hostile.py CLAYFIT WORK_DIR [--memory-limit]

  - -o naming a file, for batch and library compare: exit 2; a lock whose
    owner.json has no pid is named as such, not "process 0";
  - captures that are not regular files (/dev/zero, a FIFO, a capture or an
    image that is a symbolic link to either): refused or failed, never a
    hang; SIGINT while the captures are read leaves no lock;
  - the main process SIGKILLed while a worker runs: the worker dies with
    it, and the next run leaves every entry fitted and library.json agreeing;
  - failures that are not the capture's (a file-size limit: "File too
    large", as a full disk; with --memory-limit, out of memory under
    ulimit -v, which the sanitizers do not allow) keep the earlier entry
    whole, and an entry that had none is fitted by the next run.
Nothing about timing is asserted (the timeouts only catch a hang)."""
import json
import os
import resource
import shutil
import signal
import socket
import subprocess
import sys
import time

from batch_captures import SYNTH, check, clayfit_runner, finish

CLAYFIT, WORK = sys.argv[1], sys.argv[2]
MEMORY_LIMIT = "--memory-limit" in sys.argv[3:]
run = clayfit_runner(CLAYFIT)
HANG = 60  # seconds: a run this long has hung

shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)


def synth(name, size="96x72", *spec):
    out = os.path.join(WORK, "captures", name)
    args = [a if a != "96x72" else size for a in SYNTH]
    r = run("--quiet", "synth", "-o", out, *args, "--model", "M0", *spec)
    assert r.returncode == 0, r.stderr
    return os.path.join(out, "capture.json")


def manifest(path, entries):
    json.dump({"clayfit_manifest": 1, "captures": [
        {"name": n, "capture": c} for n, c in entries]}, open(path, "w"))
    return path


def batch(manifest_path, library, *extra, **kw):
    return run("batch", manifest_path, "-o", library, "--threads", "1", *extra, timeout=HANG, **kw)


def tree(folder):
    """{relative path: bytes} of every file under folder."""
    files = {}
    for root, _, names in os.walk(folder):
        for n in names:
            p = os.path.join(root, n)
            files[os.path.relpath(p, folder)] = open(p, "rb").read()
    return files


def states(library):
    doc = json.load(open(os.path.join(library, "library.json")))
    return {e["name"]: e["state"] for e in doc["entries"]}


def reading(pid, path):
    """True when process pid has path open (the real path)."""
    try:
        fds = os.listdir(f"/proc/{pid}/fd")
    except OSError:
        return False
    for fd in fds:
        try:
            if os.readlink(f"/proc/{pid}/fd/{fd}") == path:
                return True
        except OSError:
            pass
    return False


def alive(pid):
    """True while process pid runs (not gone, not a zombie)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except (OSError, TypeError):
        return False


small = synth("small")
other = synth("other", "96x72", "--seed", "2")
MANIFEST = manifest(os.path.join(WORK, "manifest.json"), [("small", small), ("other", other)])
LIBRARY = os.path.join(WORK, "library")
r = batch(MANIFEST, LIBRARY)
check(r.returncode == 0, f"a library of two: exit 0 ({r.stderr.strip()})")

# ---- -o naming a file; a lock without a pid ----
a_file = os.path.join(WORK, "a_file")
open(a_file, "w").write("not a folder\n")
r = batch(MANIFEST, a_file)
check(r.returncode == 2 and "-o" in r.stderr and "not a folder" in r.stderr,
      f"batch -o FILE: exit 2 ({r.returncode}: {r.stderr.strip()})")
r = run("library", "compare", LIBRARY, "small", "other", "-o", a_file, timeout=HANG)
check(r.returncode == 2 and "-o" in r.stderr and "not a folder" in r.stderr,
      f"library compare -o FILE: exit 2 ({r.returncode}: {r.stderr.strip()})")
os.makedirs(os.path.join(LIBRARY, ".lock"))
json.dump({"host": socket.gethostname()}, open(os.path.join(LIBRARY, ".lock", "owner.json"), "w"))
r = batch(MANIFEST, LIBRARY)
check(r.returncode == 1 and "no process id" in r.stderr and "process 0" not in r.stderr,
      f"a lock with no pid named as such ({r.stderr.strip()})")
shutil.rmtree(os.path.join(LIBRARY, ".lock"))

# ---- captures that are not regular files ----
fifo = os.path.join(WORK, "fifo")
os.mkfifo(fifo)
os.symlink("/dev/zero", os.path.join(WORK, "zero_link"))
for what, capture in (("/dev/zero", "/dev/zero"), ("a FIFO", fifo),
                      ("a link to /dev/zero", os.path.join(WORK, "zero_link"))):
    m = manifest(os.path.join(WORK, "special.json"), [("small", small), ("special", capture)])
    try:
        r = batch(m, os.path.join(WORK, "special_library"))
        check(r.returncode == 2 and "captures[1].capture" in r.stderr
              and "not a regular file" in r.stderr and "special_library" not in os.listdir(WORK),
              f"a capture that is {what}: exit 2 before any work ({r.stderr.strip()})")
    except subprocess.TimeoutExpired:
        check(False, f"a capture that is {what}: hung")
# images that are links to /dev/zero or a FIFO: those entries fail, the others fit
for name, target in (("zero_image", "/dev/zero"), ("fifo_image", fifo)):
    capture = synth(name)
    images = os.path.join(os.path.dirname(capture), "images")
    first = os.path.join(images, sorted(os.listdir(images))[0])
    os.remove(first)
    os.symlink(target, first)
SPECIAL = manifest(os.path.join(WORK, "special.json"), [
    ("small", small), ("zero_image", os.path.join(WORK, "captures/zero_image/capture.json")),
    ("fifo_image", os.path.join(WORK, "captures/fifo_image/capture.json"))])
SPECIAL_LIBRARY = os.path.join(WORK, "special_library")
try:
    r = batch(SPECIAL, SPECIAL_LIBRARY)
    failed = {n: json.load(open(os.path.join(SPECIAL_LIBRARY, n, "failed.json")))["reason"]
              for n in ("zero_image", "fifo_image")
              if os.path.exists(os.path.join(SPECIAL_LIBRARY, n, "failed.json"))}
    check(r.returncode == 1 and len(failed) == 2
          and all("not a regular file" in why for why in failed.values())
          and states(SPECIAL_LIBRARY)["small"] == "fitted",
          f"images linked to /dev/zero and a FIFO: those two fail, the rest fits ({failed})")
except subprocess.TimeoutExpired:
    check(False, "images linked to /dev/zero and a FIFO: hung")
# SIGINT while the captures are read (a large sparse image to hash, sent once the
# batch has it open): no lock left
sparse = os.path.join(WORK, "sparse.exr")
with open(sparse, "wb") as f:
    f.truncate(2 << 30)
big = synth("sparse_image")
images = os.path.join(os.path.dirname(big), "images")
first = os.path.join(images, sorted(os.listdir(images))[0])
os.remove(first)
os.symlink(sparse, first)
m = manifest(os.path.join(WORK, "sparse.json"), [("sparse_image", big), ("small", small)])
proc = subprocess.Popen([CLAYFIT, "batch", m, "-o", SPECIAL_LIBRARY, "--threads", "1"],
                        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)

deadline = time.monotonic() + HANG
while (proc.poll() is None and not reading(proc.pid, os.path.realpath(sparse))
       and time.monotonic() < deadline):
    time.sleep(0.001)
proc.send_signal(signal.SIGINT)
try:
    out, err = proc.communicate(timeout=HANG)
except subprocess.TimeoutExpired:
    proc.kill()
    out, err = proc.communicate()
check(proc.returncode == 1 and "interrupted" in err
      and not os.path.exists(os.path.join(SPECIAL_LIBRARY, ".lock")),
      f"SIGINT while reading the captures: exit 1, no lock left ({proc.returncode}: {err.strip()})")
os.remove(sparse)

# ---- the main process SIGKILLed while a worker runs ----
mid = synth("mid", "640x480")  # a fit of seconds
KILLED = manifest(os.path.join(WORK, "killed.json"), [("small", small), ("mid", mid)])
KILLED_LIBRARY = os.path.join(WORK, "killed_library")
r = batch(KILLED, KILLED_LIBRARY)
check(r.returncode == 0, "killed: the library fitted first")
# (output to files: a pipe would be held open by a worker that survived)
proc = subprocess.Popen([CLAYFIT, "batch", KILLED, "-o", KILLED_LIBRARY, "--threads", "1",
                         "--force"], stdout=open(os.path.join(WORK, "killed.out"), "w"),
                        stderr=subprocess.STDOUT)
worker = None
deadline = time.monotonic() + HANG
while worker is None and proc.poll() is None and time.monotonic() < deadline:
    for f in os.listdir(KILLED_LIBRARY):
        if f.startswith(".tmp.mid."):
            worker = int(f.rsplit(".", 1)[1])
    time.sleep(0.001)
proc.kill()
proc.wait()
deadline = time.monotonic() + 2  # the parent-death signal; the fit takes longer
while alive(worker) and time.monotonic() < deadline:
    time.sleep(0.01)
check(worker is not None and not alive(worker), f"killed: the worker {worker} died with the batch")
r = batch(KILLED, KILLED_LIBRARY)  # takes over the lock, cleans; a live worker would go on
deadline = time.monotonic() + HANG
while alive(worker) and time.monotonic() < deadline:
    time.sleep(0.1)
r2 = batch(KILLED, KILLED_LIBRARY)
whole = all(os.path.exists(os.path.join(KILLED_LIBRARY, n, f))
            for n in ("small", "mid") for f in ("entry.json", "fit.json", "thumbnail.png"))
check(r.returncode == 0 and r2.returncode == 0 and "0 to fit" in r2.stdout and whole
      and states(KILLED_LIBRARY) == {"small": "fitted", "mid": "fitted"},
      f"killed: after the next run both entries are whole and fitted, as library.json says "
      f"({r.returncode} {r2.returncode}: {r.stderr.strip()} {r2.stderr.strip()})")


# ---- failures that are not the capture's ----
def limited(fsize=None, memory=None):
    def apply():
        if fsize:  # writes beyond it fail with EFBIG ("File too large"), as on a full disk
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
            resource.setrlimit(resource.RLIMIT_FSIZE, (fsize, fsize))
        if memory:
            resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
    return apply


def kept_whole(what, limit, library, name):
    """A run under `limit` with --force keeps the fitted entry whole."""
    before = tree(os.path.join(library, name))
    r = batch(os.path.join(WORK, f"{name}.json"), library, "--force", preexec_fn=limit)
    print(r.stdout, r.stderr)
    after = tree(os.path.join(library, name))
    check(r.returncode == 1 and "the earlier entry is kept" in r.stderr and after == before
          and "fit.json" in after and "thumbnail.png" in after,
          f"{what}: exit 1, the earlier entry kept whole ({len(after)} files)")
    check(states(library)[name] == "fitted", f"{what}: library.json says fitted")
    r = batch(os.path.join(WORK, f"{name}.json"), library)
    check(r.returncode == 0 and "0 to fit" in r.stdout and tree(os.path.join(library, name)) == before,
          f"{what}: the next run finds it up to date, exit 0 ({r.stderr.strip()})")


def retried(what, limit, library, name):
    """A run under `limit` of an entry never fitted: failed.json that the
    next run retries."""
    shutil.rmtree(os.path.join(library, name))
    r = batch(os.path.join(WORK, f"{name}.json"), library, preexec_fn=limit)
    check(r.returncode == 1 and states(library)[name] == "failed",
          f"{what}, no earlier entry: failed ({r.stderr.strip()})")
    r = batch(os.path.join(WORK, f"{name}.json"), library)
    check(r.returncode == 0 and "1 to fit" in r.stdout and states(library)[name] == "fitted",
          f"{what}: the next run fits it again ({r.stdout.strip()})")


FULL_LIBRARY = os.path.join(WORK, "full_library")
manifest(os.path.join(WORK, "small.json"), [("small", small)])
r = batch(os.path.join(WORK, "small.json"), FULL_LIBRARY)
check(r.returncode == 0, "file-size limit: the entry fitted first")
# 60 kB: fit.json (about 28 kB), library.json and index.html fit; a preset does not
kept_whole("a file-size limit (File too large)", limited(fsize=60000), FULL_LIBRARY, "small")
retried("a file-size limit (File too large)", limited(fsize=60000), FULL_LIBRARY, "small")
# 100 MB of address space: the batch starts (it needs 45 to 60 MB) and the fit of
# 640 x 480 runs out (it needs 250 to 350 MB)
if MEMORY_LIMIT:
    MEMORY_LIBRARY = os.path.join(WORK, "memory_library")
    manifest(os.path.join(WORK, "mid.json"), [("mid", mid)])
    r = batch(os.path.join(WORK, "mid.json"), MEMORY_LIBRARY)
    check(r.returncode == 0, "memory limit: the entry fitted first")
    kept_whole("out of memory", limited(memory=100 << 20), MEMORY_LIBRARY, "mid")
    retried("out of memory", limited(memory=100 << 20), MEMORY_LIBRARY, "mid")

finish()
