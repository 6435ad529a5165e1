#!/usr/bin/env python3
"""Prints the A/B table of scripts/bench-ab.sh from its runs' JSON files.

Usage: bench_ab.py OUTDIR  (OUTDIR/base-R.json and OUTDIR/new-R.json as written by `meso bench --json`)

For each scene x technique x backend row: the median over the rounds of each side's median frame
time at N threads, their ratio (new / base; below 1 is faster), the new side's frames/s, its
one-thread median and its scaling (one-thread median / N-thread median, both over the rounds),
and the range of the load averages the runs started at.
"""
import glob
import json
import os
import statistics
import sys


def load(outdir):
    rows, loads, threads = {}, [], set()
    for path in sorted(glob.glob(os.path.join(outdir, "*-*.json"))):
        side = os.path.basename(path).split("-")[0]
        if side not in ("base", "new"):
            continue
        with open(path) as f:
            run = json.load(f)
        loads.append(run.get("load_average", float("nan")))
        threads.add(run.get("threads"))
        for r in run["runs"]:
            key = (r["scene"], r["technique"], r.get("backend", "cpu"))
            rows.setdefault(key, {}).setdefault(side, []).append(r)
    return rows, loads, threads


def median_of(runs, field):
    values = [r[field] for r in runs if r.get(field) is not None]
    return statistics.median(values) if values else None


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__.strip().splitlines()[2])
    rows, loads, threads = load(sys.argv[1])
    if not rows:
        sys.exit(f"bench_ab.py: {sys.argv[1]}: no base-R.json / new-R.json runs")
    n = "/".join(str(t) for t in sorted(threads))
    rounds = max(len(v.get("base", [])) for v in rows.values())
    print(f"{rounds} round(s), {n} thread(s), load average {min(loads):.2f}–{max(loads):.2f} at the runs' starts\n")
    print(f"| scene | technique | backend | base ms ({n} thr) | new ms ({n} thr) | new / base | new frames/s | new ms (1 thr) | scaling |")
    print("| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for key in sorted(rows):
        sides = rows[key]
        if "base" not in sides or "new" not in sides:
            continue
        base, new = median_of(sides["base"], "median_ms"), median_of(sides["new"], "median_ms")
        one = median_of(sides["new"], "median_ms_1_thread")
        one_text = f"{one:.2f}" if one else "—"
        scaling = f"{one / new:.2f}×" if one else "—"
        print(f"| {key[0]} | {key[1]} | {key[2]} | {base:.2f} | {new:.2f} | {new / base:.2f} | "
              f"{1000.0 / new:.1f} | {one_text} | {scaling} |")


if __name__ == "__main__":
    main()
