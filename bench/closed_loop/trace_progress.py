#!/usr/bin/env python3
"""Where along the taught path a replay switched key images, from an `evaluate --trace` file.

For every key-image switch: how far past the IN it left the robot truly was (metres along the
taught path, from the simulator's truth projected on the taught key images' true positions), and
what the odometry estimate said (telemetry odom_past_next_m, with its sigma odom_along_sigma_m).
A switch far past IN is a late one: the robot went on along IP -> IN where the path turned.
With --every N it also prints every N-th frame's true and estimated progress.

Usage: bench/closed_loop/trace_progress.py TRACE.jsonl [--every N] [--late M]
  --late M   list only switches more than M metres past IN (default: all)
Example:
  build/pepper_app/pepper_app evaluate --world worlds/robotics_room.yaml --starts 2 --run 1 \\
      --size 320x240 --trace /tmp/tr
  bench/closed_loop/trace_progress.py /tmp/tr/robotics_room_lines+points_none_run1.jsonl --late 0.1
"""
import argparse
import json
import math
import sys


def load(path):
    with open(path) as f:
        rows = [json.loads(line) for line in f if line.strip()]
    if not rows or 'taught_key_images' not in rows[0]:
        sys.exit(f'{path}: not an evaluate --trace file (no taught_key_images header)')
    keys = [(k['x_m'], k['y_m']) for k in rows[0]['taught_key_images']]
    return keys, [r for r in rows[1:] if 'telemetry' in r and 'gt' in r]


def cumulative(keys):
    s = [0.0]
    for a, b in zip(keys, keys[1:]):
        s.append(s[-1] + math.dist(a, b))
    return s


def project(keys, s_keys, x, y, near):
    """Distance along the key polyline of the point nearest (x, y), searching pieces near `near`."""
    best = None
    for i in range(max(0, near - 4), min(len(keys) - 1, near + 8)):
        (ax, ay), (bx, by) = keys[i], keys[i + 1]
        ux, uy = bx - ax, by - ay
        l2 = ux * ux + uy * uy
        f = 0.0 if l2 < 1e-12 else max(0.0, min(1.0, ((x - ax) * ux + (y - ay) * uy) / l2))
        d = math.hypot(ax + f * ux - x, ay + f * uy - y)
        if best is None or d < best[0]:
            best = (d, i, s_keys[i] + f * math.sqrt(l2))
    return best


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('trace')
    ap.add_argument('--every', type=int, default=0)
    ap.add_argument('--late', type=float, default=-1e9)
    a = ap.parse_args()
    keys, rows = load(a.trace)
    s_keys = cumulative(keys)
    near = 0
    prev_in = None
    late = []
    for n, r in enumerate(rows):
        gt, t = r['gt'], r['telemetry']
        p = project(keys, s_keys, gt['x_m'], gt['y_m'], near)
        if p is None:
            continue
        near = p[1]
        s_true = p[2]
        if a.every and n % a.every == 0:
            est = t.get('odom_past_next_m')
            nxt = t.get('in')
            past = s_true - s_keys[nxt] if isinstance(nxt, int) and 0 <= nxt < len(keys) else float('nan')
            print(f'frame {n:5d} IP/IN {t.get("ip")}/{nxt}: true past IN {past:+.3f} m, '
                  f'estimate {est if est is not None else float("nan"):+.3f} m')
        cur_in = t.get('in')
        if prev_in is not None and isinstance(cur_in, int) and cur_in != prev_in and prev_in >= 0:
            past = s_true - s_keys[prev_in]
            if past > a.late:
                late.append((n, prev_in, cur_in, past))
        prev_in = cur_in if isinstance(cur_in, int) else prev_in
    print(f'{len(late)} switch(es)' + (f' more than {a.late} m past IN' if a.late > -1e9 else ''))
    for n, old, new, past in late:
        print(f'  frame {n:5d}: IN {old} -> {new}, {past:+.3f} m past IN {old}')


if __name__ == '__main__':
    main()
