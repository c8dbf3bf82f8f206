"""What check_batch.py (the local executor) and check_batch_slurm.py (Slurm)
share, since they compare against each other's results: the six small
synthetic captures, one broken on purpose (its first image deleted), and
their manifest; the checks' tally (check, finish) and the clayfit runner."""
import json
import os
import subprocess
import sys

failures = 0


def check(ok, what):
    """Print the check's outcome and count it if it failed (finish says)."""
    global failures
    print(("ok   " if ok else "FAIL ") + what)
    failures += not ok


def finish():
    """Exit 1 if a check failed, else 0, saying which."""
    print("FAILED" if failures else "all ok")
    sys.exit(1 if failures else 0)


def clayfit_runner(clayfit):
    """run(*args, **kw): clayfit with args, its output captured as text."""
    def run(*args, **kw):
        return subprocess.run([clayfit, *args], capture_output=True, text=True, **kw)
    return run


SYNTH = ["--images", "4", "--size", "96x72", "--format", "exr", "--no-noise",
         "--supersample", "1"]
# name: (synth model and params, manifest options, clayfit fit's flags)
CAPTURES = {
    "lambert": (["--model", "M0"], {}, []),
    "oren": (["--model", "M1"], {"model": "M1"}, ["--model", "M1"]),
    "glossy": (["--model", "M2", "--param", "roughness=0.3", "--param", "f0=0.05"],
               {"model": "M2", "hold": {"f0": 0.05}}, ["--model", "M2", "--hold", "f0=0.05"]),
    "exposed": (["--model", "M0", "--seed", "3"], {"model": "M0", "fit_exposures": True},
                ["--model", "M0", "--fit-exposures"]),
    "budget": (["--model", "M1", "--seed", "4"], {"budget": 2000}, ["--budget", "2000"]),
    "broken": (["--model", "M0", "--seed", "5"], {}, []),
}


def make_captures(run, work, manifest_path):
    """Synthesise the captures into WORK/captures with run(*clayfit_args),
    break "broken", write the manifest (tagged by body and index) to
    manifest_path and return it."""
    for name, (spec, _, _) in CAPTURES.items():
        r = run("--quiet", "synth", "-o", os.path.join(work, "captures", name), *SYNTH, *spec)
        assert r.returncode == 0, r.stderr
    images = os.path.join(work, "captures", "broken", "images")
    os.remove(os.path.join(images, sorted(os.listdir(images))[0]))
    manifest = {"clayfit_manifest": 1, "captures": [
        {"name": n, "capture": f"captures/{n}/capture.json", "options": o,
         "tags": {"body": "stoneware" if i % 2 else "porcelain", "index": str(i)}}
        for i, (n, (_, o, _)) in enumerate(CAPTURES.items())]}
    with open(manifest_path, "w") as f:
        json.dump(manifest, f, indent=1)
    return manifest
