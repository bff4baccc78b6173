#!/usr/bin/env python3
"""How far the heading from lines is from the truth, per segment, by the segment's taught turn.

For every frame with a heading from lines (telemetry line_yaw_rad: the robot's yaw relative to
IN, read from the lines matched with IN), its error is that reading minus the truth's yaw
relative to IN's taught yaw (the trace header's taught_key_images[IN].yaw_rad; traces written
before the header carried yaws are refused). A segment's frames share IN, so their errors are
averaged per segment (the error the estimator's line-yaw model calls the segment's shared one)
and the segments binned by their taught turn |yaw(IN) - yaw(IP)|. Prints per bin: segments,
frames, the RMS and max over segments of the per-segment mean error, and the RMS of the errors
about their segment's mean (docs/method/navigator.md, "Right fixes refused after a blind turn").

Usage: bench/closed_loop/line_yaw_error.py TRACE.jsonl... [--bins B1,B2,...] [--worst N]
                                            [--frames]
  --bins     upper edges of the turn bins in rad (0.05,0.15,0.3; a last bin takes the rest)
  --worst N  also list the N segments with the largest mean error (trace, IN, turn, frames)
  --frames   also the frames' error RMS (mrad) and count by the truth's distance from IN's
             taught position (0.25, 0.5 m) and its yaw relative to IN (0.1, 0.3 rad)
Example:
  build/pepper_app/pepper_app evaluate --world worlds/robotics_room.yaml --starts 5 --run 1 \\
      --size 640x480 --trace /tmp/tr
  bench/closed_loop/line_yaw_error.py /tmp/tr/*.jsonl --worst 5
"""
import argparse
import collections
import json
import math
import sys


def wrap(a):
    return math.remainder(a, 2.0 * math.pi)


def is_number(v):
    return isinstance(v, (int, float)) and not (isinstance(v, float) and math.isnan(v))


def load_with_yaws(path):
    with open(path) as f:
        rows = [json.loads(line) for line in f if line.strip()]
    if not rows or 'taught_key_images' not in rows[0]:
        sys.exit(f'{path}: not an evaluate --trace file (no taught_key_images header)')
    keys = rows[0]['taught_key_images']
    if not keys or any('yaw_rad' not in k for k in keys):
        sys.exit(f'{path}: the header has no taught yaws (a trace of an older build?)')
    return keys, [r for r in rows[1:] if 'telemetry' in r and 'gt' in r]


def segments(path, frames=None):
    """{(path, IP, IN): [line yaw error rad, ...]} and each segment's taught turn; `frames`, a
    list, gets (distance from IN m, |yaw relative to IN| rad, error rad) per frame."""
    keys, rows = load_with_yaws(path)
    yaws = [k['yaw_rad'] for k in keys]
    errs = collections.defaultdict(list)
    turn = {}
    for r in rows:
        t, gt = r['telemetry'], r['gt']
        ly, ip, nxt = t.get('line_yaw_rad'), t.get('ip'), t.get('in')
        if not is_number(ly) or ip is None or nxt is None or not 0 <= ip < nxt < len(yaws):
            continue
        truth = wrap(gt['yaw_rad'] - yaws[nxt])
        key = (path, ip, nxt)
        errs[key].append(wrap(ly - truth))
        turn[key] = abs(wrap(yaws[nxt] - yaws[ip]))
        if frames is not None:
            d = math.hypot(gt['x_m'] - keys[nxt]['x_m'], gt['y_m'] - keys[nxt]['y_m'])
            frames.append((d, abs(truth), wrap(ly - truth)))
    return errs, turn


def frame_grid(frames):
    """Prints the frames' error RMS and count by distance from IN and relative yaw."""
    d_edges, y_edges = [0.25, 0.5], [0.1, 0.3]

    def cell(v, edges):
        return next((i for i, hi in enumerate(edges) if v < hi), len(edges))

    grid = collections.defaultdict(list)
    for d, y, e in frames:
        grid[(cell(d, d_edges), cell(y, y_edges))].append(e)
    print('frames by distance from IN (rows, m) and |yaw relative to IN| (columns, rad): '
          'error RMS mrad / frames')
    print('distance m    yaw 0 - 0.1       0.1 - 0.3         0.3 -')
    for i, label in enumerate(['0 - 0.25  ', '0.25 - 0.5', '0.5 -     ']):
        cells = []
        for j in range(3):
            v = grid.get((i, j), [])
            rms = math.sqrt(sum(x * x for x in v) / len(v)) * 1000 if v else float('nan')
            cells.append(f'{rms:7.1f} / {len(v):5d}')
        print(f'{label}  ' + '   '.join(cells))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('traces', nargs='+')
    ap.add_argument('--bins', default='0.05,0.15,0.3')
    ap.add_argument('--worst', type=int, default=0)
    ap.add_argument('--frames', action='store_true')
    a = ap.parse_args()
    try:
        edges = [float(x) for x in a.bins.split(',')]
    except ValueError:
        sys.exit(f'--bins {a.bins}: give increasing angles in rad, e.g. 0.05,0.15,0.3')
    if not edges or any(e <= 0 for e in edges) or edges != sorted(edges):
        sys.exit(f'--bins {a.bins}: give increasing angles in rad, e.g. 0.05,0.15,0.3')
    errs, turn, per_frame = {}, {}, []
    for path in a.traces:
        e, t = segments(path, per_frame)
        errs.update(e)
        turn.update(t)
    if not errs:
        sys.exit('no frame with a heading from lines in these traces')
    labels = [f'{lo:.2f} - {hi:.2f}' for lo, hi in zip([0.0] + edges, edges)]
    labels.append(f'{edges[-1]:.2f} -     ')
    binned = collections.defaultdict(list)
    for key, e in errs.items():
        k = next((i for i, hi in enumerate(edges) if turn[key] < hi), len(edges))
        binned[k].append(key)
    frames = sum(len(e) for e in errs.values())
    print(f'{frames} frames of {len(errs)} segments in {len(a.traces)} traces; '
          f'segments by their taught turn (rad)')
    print('turn rad      segments  frames  mean RMS mrad  mean max mrad  within RMS mrad')
    for k in sorted(binned):
        keys = binned[k]
        means = [sum(errs[s]) / len(errs[s]) for s in keys]
        rms = math.sqrt(sum(m * m for m in means) / len(means))
        within = [x - m for s, m in zip(keys, means) for x in errs[s]]
        w_rms = math.sqrt(sum(x * x for x in within) / len(within))
        n = sum(len(errs[s]) for s in keys)
        print(f'{labels[k]}  {len(keys):8d}  {n:6d}  {1000 * rms:13.1f}  '
              f'{1000 * max(abs(m) for m in means):13.1f}  {1000 * w_rms:15.1f}')
    if a.worst > 0:
        print('largest per-segment mean errors:')
        ranked = sorted(errs, key=lambda s: -abs(sum(errs[s]) / len(errs[s])))
        for path, ip, nxt in ranked[:a.worst]:
            e = errs[(path, ip, nxt)]
            print(f'  {path} IN {nxt}: mean {1000 * sum(e) / len(e):+.1f} mrad over {len(e)} '
                  f'frames, taught turn {turn[(path, ip, nxt)]:.3f} rad')
    if a.frames:
        frame_grid(per_frame)


if __name__ == '__main__':
    main()
