#!/usr/bin/env python3
"""Compares the outputs of every zoo scene between two output trees (e.g. the
engine before and after a restructuring): every CSV cell and every JSON number
must agree to a relative 1e-12 (timings and the keys the newer run adds are
skipped; warnings must be identical).

usage: zoo_compare.py BEFORE_DIR AFTER_DIR
       zoo_compare.py --run ENGINE OUT_DIR   (every zoo scene into OUT_DIR/<scene>,
                                              each summary checked against
                                              docs/summary.schema.json)

The data scenes (`*_data.toml`) run first and also write into the
repository's `out/`, where the NAR scenes read their signals.
"""

import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

# timings, ratios of timings, and where the plugin libraries were built
SKIP_KEYS = {
    "timing_s",
    "steps_per_second",
    "time_s",
    "wall_s",
    "seconds",
    "speedup",
    "file",
}
TOL = 1e-12


def close(a, b):
    if isinstance(a, float) or isinstance(b, float):
        if math.isnan(a) and math.isnan(b):
            return True
        return abs(a - b) <= TOL * max(1.0, abs(a), abs(b))
    return a == b


def cmp_json(a, b, path, errs):
    if isinstance(a, dict):
        if not isinstance(b, dict):
            errs.append(f"{path}: type changed")
            return
        for k, v in a.items():
            if k in SKIP_KEYS or k.endswith("_s"):
                continue
            if k not in b:
                errs.append(f"{path}.{k}: missing after")
                continue
            cmp_json(v, b[k], f"{path}.{k}", errs)
    elif isinstance(a, list):
        if not isinstance(b, list) or len(a) != len(b):
            errs.append(
                f"{path}: list length {len(a)} -> {len(b) if isinstance(b, list) else '?'}"
            )
            return
        for i, (x, y) in enumerate(zip(a, b)):
            cmp_json(x, y, f"{path}[{i}]", errs)
    elif (
        isinstance(a, (int, float))
        and isinstance(b, (int, float))
        and not isinstance(a, bool)
    ):
        if not close(float(a), float(b)):
            errs.append(f"{path}: {a} -> {b}")
    elif a != b:
        errs.append(f"{path}: {a!r} -> {b!r}")


def cmp_csv(a, b, name, errs):
    la, lb = a.read_text().splitlines(), b.read_text().splitlines()
    if len(la) != len(lb):
        errs.append(f"{name}: {len(la)} -> {len(lb)} lines")
        return
    header = la[0].split(",")
    time_cols = {
        i for i, h in enumerate(header) if h.endswith("_s") or h in ("steps", "speedup")
    }
    for n, (x, y) in enumerate(zip(la, lb)):
        fx, fy = x.split(","), y.split(",")
        if len(fx) != len(fy):
            errs.append(f"{name}:{n + 1}: columns differ")
            continue
        for i, (u, v) in enumerate(zip(fx, fy)):
            if i in time_cols and n > 0:
                continue
            try:
                if not close(float(u), float(v)):
                    errs.append(f"{name}:{n + 1} col {header[i]}: {u} -> {v}")
            except ValueError:
                if u != v:
                    errs.append(f"{name}:{n + 1} col {i}: {u!r} -> {v!r}")


def run(engine, out):
    root = Path(__file__).resolve().parents[2]
    scenes = sorted(
        (root / "zoo").glob("*.toml"),
        key=lambda p: (not p.stem.endswith("_data"), p.stem),
    )
    failed = 0
    for scene in scenes:
        dest = out / scene.stem
        if scene.stem.endswith("_data"):
            # where the NAR scenes read it, then copied beside the others
            target = root / "out" / scene.stem
        else:
            target = dest
        r = subprocess.run(
            [engine, str(scene), "--out", str(target)],
            check=False,
            capture_output=True,
            text=True,
        )
        if r.returncode != 0:
            failed += 1
            print(f"{scene.stem}: exit {r.returncode}: {r.stderr.strip()[-300:]}")
            continue
        if target != dest:
            if dest.exists():
                shutil.rmtree(dest)
            shutil.copytree(target, dest)
        print(f"{scene.stem}: ok")
    # every summary against the engine's JSON Schema
    check = subprocess.run(
        [
            sys.executable,
            str(root / "tests/scripts/validate_summary.py"),
            str(root / "docs/summary.schema.json"),
            *sorted(str(p) for p in out.glob("*/summary.json")),
        ],
        check=False,
    )
    if check.returncode != 0:
        failed += 1
    else:
        print("every summary follows docs/summary.schema.json")
    return 1 if failed else 0


def main():
    if sys.argv[1] == "--run":
        return run(Path(sys.argv[2]).resolve(), Path(sys.argv[3]).resolve())
    before, after = Path(sys.argv[1]), Path(sys.argv[2])
    total = 0
    for scene in sorted(p for p in before.iterdir() if p.is_dir()):
        errs = []
        other = after / scene.name
        for f in sorted(scene.iterdir()):
            g = other / f.name
            if not g.exists():
                errs.append(f"{f.name}: missing after")
            elif f.suffix == ".json":
                cmp_json(
                    json.loads(f.read_text()), json.loads(g.read_text()), f.name, errs
                )
            elif f.suffix == ".csv" and f.name != "report.csv":
                cmp_csv(f, g, f.name, errs)
        total += len(errs)
        print(
            f"{scene.name}: {'identical' if not errs else f'{len(errs)} differences'}"
        )
        for e in errs[:10]:
            print("   ", e)
    print(f"{total} differences")
    return 1 if total else 0


if __name__ == "__main__":
    sys.exit(main())
