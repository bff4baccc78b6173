#!/usr/bin/env python3
"""Combine `pepper_app evaluate --json` files (shards of one measurement) into one Markdown table.

Usage: bench/closed_loop/combine.py SHARD.json [SHARD.json ...] [--out combined.json]

One row per (world, features, controller, size, disturbances): success, the mean of the per-run
lateral RMS and the largest per-run maximum over the runs that succeeded (cm), the longest
distance any run drove before it first came within 5 cm of the path, the range of the per-run
median step times, and every failed run with how and where it ended. Definitions:
docs/evaluation.md. Evaluations of the same configuration in several shards (e.g. `--run 1 2 3`
and `--run 4 5 6`) are merged run by run.

Generated worlds (`gen_<kind>_<seed>`, from `pepper_app world generate`) get a second table, one
row per disturbance over all of them, as issue 26 states its targets: success over all runs,
lateral RMS on the successes, and every failure with its world seed and how it ended.
"""
import argparse
import json
import math
import sys


def key_of(e):
    return (e["world"], e["features"], e["controller"], e["size"],
            "+".join(e["disturbances"]) or "none")


def fmt(x, scale=1.0, digits=1):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    return f"{x * scale:.{digits}f}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="+")
    ap.add_argument("--out", help="also write the merged evaluations as one JSON file")
    a = ap.parse_args()
    merged = {}
    for f in a.files:
        with open(f) as fh:
            doc = json.load(fh)
        for e in doc["evaluations"]:
            k = key_of(e)
            if k not in merged:
                merged[k] = dict(e, runs=[])
            known = {r["index"] for r in merged[k]["runs"]}
            merged[k]["runs"] += [r for r in e["runs"] if r["index"] not in known]
    print("| world | disturbance | success | lateral RMS / max (cm) | within 5 cm after | "
          "step ms (per-run medians) | failures |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for k in sorted(merged):
        e = merged[k]
        runs = sorted(e["runs"], key=lambda r: r["index"])
        ok = [r for r in runs if r["success"]]
        rms = [r["lateral_rms_m"] for r in ok if r["lateral_rms_m"] is not None]
        mx = [r["lateral_max_m"] for r in ok if r["lateral_max_m"] is not None]
        first = [r["first_under_5cm_m"] for r in runs if r.get("first_under_5cm_m") is not None
                 and r["first_under_5cm_m"] >= 0]
        steps = [r["step_ms_median"] for r in runs if r["step_ms_median"] is not None]
        fails = [f"run {r['index'] + 1} {r['outcome']} at {r['travelled_m']:.1f} m"
                 + (f" ({r['detail']})" if r.get("detail") else "")
                 for r in runs if not r["success"]]
        world = k[0] + ("" if k[1] == "lines+points" else f" [{k[1]}]")
        print(f"| {world} | {k[4]} | {len(ok)}/{len(runs)} | "
              f"{fmt(sum(rms) / len(rms) if rms else None, 100)} / "
              f"{fmt(max(mx) if mx else None, 100)} | "
              f"{fmt(max(first) if first else None)} m | "
              f"{fmt(min(steps)) if steps else '-'}-{fmt(max(steps)) if steps else '-'} | "
              f"{'; '.join(fails) if fails else 'none'} |")
    gen = {}
    for k, e in merged.items():
        if k[0].startswith("gen_"):
            gen.setdefault(k[1:], []).append(e)
    if gen:
        print()
        print("Generated worlds (all seeds together):")
        print()
        print("| features / controller / size | disturbance | worlds | success | "
              "lateral RMS mean / max of RMS (cm) | failures (world: run, outcome, where) |")
        print("| --- | --- | --- | --- | --- | --- |")
        for g in sorted(gen):
            evals = sorted(gen[g], key=lambda e: e["world"])
            runs = [(e["world"], r) for e in evals for r in e["runs"]]
            ok = [r for _, r in runs if r["success"]]
            rms = [r["lateral_rms_m"] for r in ok if r["lateral_rms_m"] is not None]
            fails = [f"{w}: run {r['index'] + 1} {r['outcome']} at {r['travelled_m']:.1f} m"
                     + (f" ({r['detail']})" if r.get("detail") else "")
                     for w, r in runs if not r["success"]]
            print(f"| {g[0]} / {g[1]} / {g[2]} | {g[3]} | {len(evals)} | {len(ok)}/{len(runs)} "
                  f"({fmt(100.0 * len(ok) / len(runs) if runs else None, 1, 0)} %) | "
                  f"{fmt(sum(rms) / len(rms) if rms else None, 100)} / "
                  f"{fmt(max(rms) if rms else None, 100)} | "
                  f"{'; '.join(fails) if fails else 'none'} |")
    if a.out:
        with open(a.out, "w") as fh:
            json.dump({"format": "pepper.evaluation", "version": 1,
                       "evaluations": list(merged.values())}, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
