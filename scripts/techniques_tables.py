#!/usr/bin/env python3
"""Prints the measured tables of docs/techniques.md from `meso render --techniques all` results.

Usage: techniques_tables.py OUT  (OUT/<scene>/results.csv as written by scripts/measure-techniques.sh)

The effect table follows the rules stated in docs/techniques.md: a technique shows an effect
when, on the scene that isolates it, it beats the baseline lacking that effect by a margin.
"""
import csv
import os
import sys

OCCLUSION_SCENE, SHADOW_SCENE, SILHOUETTE_SCENE = "occlusion-overhead-light", "shadow-top-view", "bumps-sphere"
MARGIN_DB = 3.0      # covered PSNR gain over bump that counts as showing the effect
MARGIN_IOU = 0.01    # coverage IoU gain over flat that counts as showing silhouettes


def load(out):
    results = {}
    for scene in sorted(os.listdir(out)):
        path = os.path.join(out, scene, "results.csv")
        if os.path.exists(path):
            with open(path) as f:
                results[scene] = {row["technique"]: row for row in csv.DictReader(f)}
    return results


def number(row, key):
    value = row.get(key, "") if row else ""
    return float(value) if value not in ("", None) else None


def effect(results, scene, technique, baseline, key, margin):
    rows = results.get(scene, {})
    mine, base = number(rows.get(technique), key), number(rows.get(baseline), key)
    if mine is None or base is None:
        return "—"
    unit = "dB" if key.startswith("psnr") else ""
    verdict = "yes" if mine - base >= margin else "no"
    return f"{verdict} ({mine:.3g}{unit and ' ' + unit}, {mine - base:+.2g})"


def main():
    results = load(sys.argv[1])
    techniques = [t for t in results.get("bricks-plane", {}) if t != "reference"]
    print("| technique | occlusion / parallax | self-shadow | silhouette | open boundary | non-height-field |")
    print("| --- | --- | --- | --- | --- | --- |")
    weave = results.get("weave-torus", {})
    for t in techniques:
        plane_iou = number(results.get("bricks-plane", {}).get(t), "coverage_iou")
        boundary = "—" if plane_iou is None else f"{'yes' if plane_iou >= 0.99 else 'no'} ({plane_iou:.3f})"
        solid = "yes" if t in weave and weave[t]["status"] == "ok" and t != "flat" else (
            "base mesh only" if t == "flat" else "not applicable")
        print(f"| {t} | {effect(results, OCCLUSION_SCENE, t, 'bump', 'psnr_covered_db', MARGIN_DB)} "
              f"| {effect(results, SHADOW_SCENE, t, 'bump', 'psnr_covered_db', MARGIN_DB)} "
              f"| {effect(results, SILHOUETTE_SCENE, t, 'flat', 'coverage_iou', MARGIN_IOU)} "
              f"| {boundary} | {solid} |")
    for scene, rows in results.items():
        print(f"\n### {scene}\n")
        print("| technique | frame ms | PSNR dB | covered dB | SSIM | IoU |")
        print("| --- | ---: | ---: | ---: | ---: | ---: |")
        for t, row in rows.items():
            cells = [row.get(k) or "—" for k in ("frame_ms", "psnr_db", "psnr_covered_db", "ssim", "coverage_iou")]
            if row["status"] != "ok":
                cells = ["—"] * 5
            print(f"| {t} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
