#!/usr/bin/env python3
"""The damaged-file catalogue of issue 12: copies of real VDB assets with a few
random byte changes, and copies cut short at 5% to 99.9% of their length, each
opened by `vdbmarch info` (and `vdbmarch render`, tiny, for a sample of them).

Every run is classified:
  error   exit 1 with a message naming the file (the wanted outcome for cuts)
  loaded  exit 0 (fine for a byte change that only altered values; for a cut
          file it is a silent partial read: a failure)
  crash   killed by a signal or an abort
  hang    still running after the timeout (killed)

Usage: tools/damage_catalogue.py [--assets DIR] [--copies N] [--seed S] [--out DIR]
Prints a table and exits 1 when any crash, hang or silent partial read occurs.
"""
import argparse
import os
import random
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
VDBMARCH = os.path.join(ROOT, "build", "bin", "vdbmarch")
ASSETS = ["dragon_fog.vdb", "smoke1.vdb", "wdas_cloud_sixteenth.vdb"]
CUTS = [0.05, 0.25, 0.5, 0.75, 0.9, 0.97, 0.99, 0.999]


def run(cmd, timeout):
    try:
        p = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, timeout=timeout)
    except subprocess.TimeoutExpired:
        return "hang", ""
    err = p.stderr.decode(errors="replace").strip().splitlines()
    last = err[-1] if err else ""
    if p.returncode < 0 or p.returncode > 128:
        return "crash", last
    if p.returncode == 0:
        return "loaded", last
    return "error", last


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--assets", default=os.path.join(ROOT, "..", "shared", "assets"))
    ap.add_argument("--copies", type=int, default=20, help="byte-changed copies per asset")
    ap.add_argument("--bytes", type=int, default=4, help="bytes changed per copy")
    ap.add_argument("--seed", type=int, default=12)
    ap.add_argument("--timeout", type=float, default=120)
    ap.add_argument("--render-every", type=int, default=5, help="also render every N-th copy (0: never)")
    ap.add_argument("--out", default=None, help="keep the damaged copies here")
    ap.add_argument("--vdbmarch", default=VDBMARCH, help="the binary to try (default: build/bin/vdbmarch)")
    a = ap.parse_args()
    if not os.path.isdir(a.assets):
        print(f"no assets folder {a.assets}: nothing to do")
        return 0
    rng = random.Random(a.seed)
    work = a.out or tempfile.mkdtemp(prefix="vdbmarch_damage_")
    os.makedirs(work, exist_ok=True)
    counts = {}
    failures = []
    n = 0
    for asset in ASSETS:
        src = os.path.join(a.assets, asset)
        if not os.path.exists(src):
            continue
        data = open(src, "rb").read()
        cases = []
        for i in range(a.copies):
            d = bytearray(data)
            for _ in range(a.bytes):
                d[rng.randrange(len(d))] = rng.randrange(256)
            cases.append(("bytes", f"{asset[:-4]}_bytes{i:02d}.vdb", bytes(d)))
        for c in CUTS:
            cases.append(("cut", f"{asset[:-4]}_cut{c:g}.vdb", data[: int(len(data) * c)]))
        for kind, name, payload in cases:
            path = os.path.join(work, name)
            with open(path, "wb") as f:
                f.write(payload)
            outcomes = [("info",) + run([a.vdbmarch, "info", path], a.timeout)]
            n += 1
            if a.render_every and n % a.render_every == 0:
                exr = os.path.join(work, name + ".exr")
                outcomes.append(("render",) + run([a.vdbmarch, "render", path, "-o", exr, "--res", "16x12",
                                                   "--spp", "1", "-q"], a.timeout))
            for cmd, outcome, msg in outcomes:
                key = (kind, cmd, outcome)
                counts[key] = counts.get(key, 0) + 1
                bad = outcome in ("crash", "hang") or (kind == "cut" and outcome == "loaded") or \
                    (outcome == "error" and path not in msg)
                if bad:
                    failures.append(f"{cmd} {name}: {outcome} {msg}")
    print("| damage | command | error (named) | loaded | crash | hang |")
    print("|---|---|---|---|---|---|")
    for kind in ("bytes", "cut"):
        for cmd in ("info", "render"):
            row = [counts.get((kind, cmd, o), 0) for o in ("error", "loaded", "crash", "hang")]
            if sum(row):
                print(f"| {kind} | {cmd} | " + " | ".join(str(v) for v in row) + " |")
    for f in failures:
        print("FAIL", f)
    if not a.out:
        shutil.rmtree(work, ignore_errors=True)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
