#!/usr/bin/env python3
"""Compare two evaluation matrices (before / after a change) run by run.

Usage: bench/closed_loop/compare.py BEFORE_DIR AFTER_DIR [--threshold-cm 1.5]

Each DIR holds `pepper_app evaluate --json` files named after their configuration (matrix.sh
writes DIR/NAME.json). Only configurations present in both are compared. Per disturbance suffix
of the generated worlds' names (`_none`, `_light0.7`) and for all other configurations together it
prints success, the mean lateral RMS over the successes, the runs over 5 cm RMS and those with
a maximum over 15 cm (issue 26's targets); then every run whose outcome changed or whose lateral
RMS moved by more than --threshold-cm.

Example (the generated set before and after a change, QVGA, 2 starts):
  bench/closed_loop/matrix.sh --out /tmp/before --app OLD_BIN --size 320x240 --gen-starts 2 --only '^gen_'
  bench/closed_loop/matrix.sh --out /tmp/after --size 320x240 --gen-starts 2 --only '^gen_'
  bench/closed_loop/compare.py /tmp/before /tmp/after
(copy BEFORE_DIR/worlds to AFTER_DIR/worlds first so that both evaluate the same world files).
"""
import argparse
import glob
import json
import os
import sys


def load(directory):
    out = {}
    for path in sorted(glob.glob(os.path.join(directory, "*.json"))):
        try:
            with open(path) as f:
                j = json.load(f)
        except (OSError, json.JSONDecodeError) as e:
            sys.exit(f"compare.py: cannot read {path}: {e}")
        if "evaluations" in j:
            runs = [r for e in j["evaluations"] for r in e.get("runs", [])]
        elif "runs" in j:
            runs = j["runs"]
        else:
            continue  # not an evaluate file
        name = os.path.basename(path)[: -len(".json")]
        # A failed run has no accuracy figures (null): NaN keeps it out of the means.
        cm = lambda v: float("nan") if v is None else v * 100.0
        out[name] = [(bool(r["success"]), cm(r.get("lateral_rms_m")), cm(r.get("lateral_max_m")),
                      r.get("outcome", "?")) for r in runs]
    return out


def stats(runs):
    ok = [r for r in runs if r[0]]
    rms = [r[1] for r in ok]
    mean = sum(rms) / len(rms) if rms else float("nan")
    return (f"{len(ok)}/{len(runs)}, lateral RMS mean {mean:.2f} cm, "
            f"{sum(1 for r in ok if r[1] > 5)} over 5 cm, {sum(1 for r in ok if r[2] > 15)} with max > 15 cm")


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("before")
    p.add_argument("after")
    p.add_argument("--threshold-cm", type=float, default=1.5)
    a = p.parse_args()
    for d in (a.before, a.after):
        if not os.path.isdir(d):
            sys.exit(f"compare.py: {d} is not a directory")
    before, after = load(a.before), load(a.after)
    common = sorted(set(before) & set(after))
    if not common:
        sys.exit("compare.py: no configuration is in both directories")
    groups = {}
    for name in common:
        key = "generated" + name[name.rfind("_"):] if name.startswith("gen_") else "shipped"
        groups.setdefault(key, []).append(name)
    print(f"{len(common)} configurations in both")
    for key, names in sorted(groups.items()):
        rb = [r for n in names for r in before[n]]
        ra = [r for n in names for r in after[n]]
        print(f"{key}: before {stats(rb)} | after {stats(ra)}")
    print("changed runs:")
    for name in common:
        for i, (rb, ra) in enumerate(zip(before[name], after[name])):
            moved = abs(rb[1] - ra[1]) > a.threshold_cm  # False when either is NaN
            if rb[0] != ra[0] or moved:
                print(f"  {name} run {i + 1}: {rb[3]} {rb[1]:.1f} / {rb[2]:.1f} cm -> "
                      f"{ra[3]} {ra[1]:.1f} / {ra[2]:.1f} cm")


if __name__ == "__main__":
    main()
