#!/usr/bin/env python3
"""Where the key-image switches that the image decided left the robot, from `evaluate --trace` files.

For every switch: how far past the IN it left the robot truly was (the simulator's truth
projected on the taught key images, as trace_progress.py) and how far the odometry estimate was
from the truth along the path just before it. A switch "the image decided" has a paper rule in
telemetry switch_criterion (bit 1 or 2) and neither "passed IN by travel" bit (16, 32); in traces
written before switch_criterion was recorded, a switch taken while the estimate was still before
IN stands in for it (the odometry cannot have wanted it). Prints quantiles and RMS.

Usage: bench/closed_loop/switch_errors.py TRACE.jsonl [TRACE.jsonl ...]
Example:
  build/pepper_app/pepper_app evaluate --world worlds/robotics_room.yaml --starts 5 --run 1 \\
      --seed 1 --size 320x240 --trace /tmp/tr
  bench/closed_loop/switch_errors.py /tmp/tr/*.jsonl
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import trace_progress as tp  # noqa: E402

PAPER_RULES, BY_TRAVEL = 1 | 2, 16 | 32


def switches(path):
    keys, rows = tp.load(path)
    s_keys = tp.cumulative(keys)
    near, prev = 0, None
    for r in rows:
        gt, t = r['gt'], r['telemetry']
        p = tp.project(keys, s_keys, gt['x_m'], gt['y_m'], near)
        if p is None:
            continue
        near = p[1]
        if (t.get('switched') and prev is not None and isinstance(t.get('in'), int)
                and t['in'] == prev.get('in', -2) + 1):
            old = prev['in']
            crit = t.get('switch_criterion')
            est = prev.get('odom_past_next_m')
            if crit is not None:
                by_image = bool(crit & PAPER_RULES) and not crit & BY_TRAVEL
            else:
                by_image = est is not None and est < 0.0
            true_past = p[2] - s_keys[old]
            yield by_image, true_past, (est - true_past) if est is not None else None
        prev = t


def summary(name, xs):
    xs = sorted(xs)
    if not xs:
        print(f'{name}: none')
        return
    q = lambda f: xs[min(len(xs) - 1, int(f * len(xs)))]  # noqa: E731
    rms = math.sqrt(sum(x * x for x in xs) / len(xs))
    print(f'{name}: n={len(xs)} p05={q(.05):+.3f} median={q(.5):+.3f} p95={q(.95):+.3f} '
          f'rms={rms:.3f} m')


def main():
    if len(sys.argv) < 2 or sys.argv[1] in ('-h', '--help'):
        print(__doc__)
        sys.exit(0 if len(sys.argv) > 1 else 2)
    by_image = [s for path in sys.argv[1:] for s in switches(path) if s[0]]
    summary('decided by the image: true position past IN', [s[1] for s in by_image])
    summary('decided by the image: estimate minus truth', [s[2] for s in by_image
                                                          if s[2] is not None])


if __name__ == '__main__':
    main()
