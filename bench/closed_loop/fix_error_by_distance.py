#!/usr/bin/env python3
"""How far a VNHV fix is from the truth, by the fix's distance from IN, from `evaluate --trace`.

A fix resects the current view against IN's points, triangulated from IP and IN; beyond IP it
extrapolates that reconstruction. For every frame with a fix (accepted or refused) on a segment
of two consecutive key images, the fix's lateral position (telemetry vnhv_fix_lateral_m) minus
the true one (the simulator's pose against the chord IP -> IN of the taught key images' true
positions), binned by the fix's own distance from IN in segment lengths (vnhv_fix_r_units; with
--true-distance, the true distance instead). Prints per bin: segments, fixes, RMS, p90 and max
of the lateral error (docs/method/navigator.md, "A fix's error and its distance from IN").

Usage: bench/closed_loop/fix_error_by_distance.py TRACE.jsonl... [--bin B] [--true-distance]
  --bin B           bin width in segment lengths (0.25)
  --true-distance   bin by the true distance from IN instead of the fix's own
Example:
  build/pepper_app/pepper_app evaluate --world worlds/robotics_room.yaml --starts 5 --run 1 \\
      --size 640x480 --trace /tmp/tr
  bench/closed_loop/fix_error_by_distance.py /tmp/tr/*.jsonl
"""
import argparse
import collections
import math
import sys

from trace_progress import load  # the same trace reader (same directory)


def is_number(v):
    return isinstance(v, (int, float)) and not (isinstance(v, float) and math.isnan(v))


def fixes(path):
    """(lateral error m, fix distance units, true distance units, segment id) per fix."""
    keys, rows = load(path)
    out = []
    for r in rows:
        t, gt = r['telemetry'], r['gt']
        lat_fix, r_fix = t.get('vnhv_fix_lateral_m'), t.get('vnhv_fix_r_units')
        ip, nxt = t.get('ip'), t.get('in')
        if not is_number(lat_fix) or not is_number(r_fix) or ip is None or nxt != ip + 1:
            continue
        if nxt >= len(keys):
            continue
        (ax, ay), (bx, by) = keys[ip], keys[nxt]
        length = math.hypot(bx - ax, by - ay)
        if length < 0.05:
            continue
        ux, uy = (bx - ax) / length, (by - ay) / length
        dx, dy = gt['x_m'] - bx, gt['y_m'] - by
        lat_true = -dx * uy + dy * ux  # left of the chord positive, as the telemetry
        out.append((lat_fix - lat_true, r_fix, math.hypot(dx, dy) / length, (path, nxt)))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('traces', nargs='+')
    ap.add_argument('--bin', type=float, default=0.25)
    ap.add_argument('--true-distance', action='store_true')
    a = ap.parse_args()
    if not a.bin > 0:
        sys.exit('--bin must be > 0')
    bins = collections.defaultdict(list)
    for path in a.traces:
        for err, r_fix, r_true, seg in fixes(path):
            r = r_true if a.true_distance else r_fix
            bins[int(r / a.bin)].append((err, seg))
    if not bins:
        sys.exit('no fixes with vnhv_fix_r_units in these traces (a trace of an older build?)')
    total = sum(len(v) for v in bins.values())
    segments = len({seg for v in bins.values() for _, seg in v})
    print(f'{total} fixes of {segments} segments in {len(a.traces)} traces; '
          f'by the {"true" if a.true_distance else "fix"}\'s distance from IN (segment lengths)')
    print('distance        segments  fixes  lateral RMS cm  p90 cm  max cm')
    for k in sorted(bins):
        errs = sorted(abs(e) for e, _ in bins[k])
        rms = math.sqrt(sum(e * e for e in errs) / len(errs))
        p90 = errs[int(0.9 * (len(errs) - 1))]
        segs = len({seg for _, seg in bins[k]})
        print(f'{k * a.bin:5.2f} - {(k + 1) * a.bin:5.2f}  {segs:8d}  {len(errs):5d}  '
              f'{100 * rms:14.1f}  {100 * p90:6.1f}  {100 * errs[-1]:6.1f}')


if __name__ == '__main__':
    main()
