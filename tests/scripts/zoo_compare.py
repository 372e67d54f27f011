#!/usr/bin/env python3
"""Compares the outputs of every zoo scene between two output trees (e.g. the
engine before and after a restructuring): every CSV cell and every JSON number
must agree to a relative 1e-12 (timings and the keys the newer run adds are
skipped; warnings must be identical).

usage: zoo_compare.py BEFORE_DIR AFTER_DIR
"""
import json
import math
import sys
from pathlib import Path

SKIP_KEYS = {"timing_s", "steps_per_second", "time_s", "wall_s"}
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
            errs.append(f"{path}: list length {len(a)} -> {len(b) if isinstance(b, list) else '?'}")
            return
        for i, (x, y) in enumerate(zip(a, b)):
            cmp_json(x, y, f"{path}[{i}]", errs)
    elif isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
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
    time_cols = {i for i, h in enumerate(header) if h.endswith("_s") or h == "steps"}
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


def main():
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
                cmp_json(json.loads(f.read_text()), json.loads(g.read_text()), f.name, errs)
            elif f.suffix == ".csv" and f.name != "report.csv":
                cmp_csv(f, g, f.name, errs)
        total += len(errs)
        print(f"{scene.name}: {'identical' if not errs else f'{len(errs)} differences'}")
        for e in errs[:10]:
            print("   ", e)
    print(f"{total} differences")
    return 1 if total else 0


if __name__ == "__main__":
    sys.exit(main())
