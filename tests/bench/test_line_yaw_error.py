#!/usr/bin/env python3
"""bench/closed_loop/line_yaw_error.py on a small synthetic trace: a frame's error is its heading
from lines minus the truth's yaw relative to IN's taught yaw; errors are averaged per segment and
the segments binned by their taught turn; frames without a heading from lines are left out, and
a trace without taught yaws is refused."""
import json
import os
import subprocess
import sys
import tempfile

TOOL = os.path.join(os.path.dirname(__file__), "..", "..", "bench", "closed_loop",
                    "line_yaw_error.py")


def frame(ip, yaw_true, line_yaw, x_m=0.0):
    t = {"ip": ip, "in": ip + 1, "line_yaw_rad": line_yaw}
    return {"t_s": 0.0, "gt": {"x_m": x_m, "y_m": 0.0, "yaw_rad": yaw_true, "s_m": 0.0,
                               "lateral_m": 0.0},
            "telemetry": t, "command": {"v_m_s": 0.1, "omega_rad_s": 0.0}}


def run(*args):
    return subprocess.run([sys.executable, TOOL, *args], capture_output=True, text=True)


def main():
    failures = []
    with tempfile.TemporaryDirectory() as d:
        trace = os.path.join(d, "t.jsonl")
        # Key images 0 -> 1 straight (yaw 0 to 0.01), 1 -> 2 a turn of 0.5 rad.
        keys = [{"x_m": 0.0, "y_m": 0.0, "yaw_rad": 0.0}, {"x_m": 1.0, "y_m": 0.0, "yaw_rad": 0.01},
                {"x_m": 1.5, "y_m": 0.3, "yaw_rad": 0.51}]
        rows = [{"taught_key_images": keys},
                # straight segment (IN 1): the truth 0.01 rad left of IN, lines read +0.002, -0.002
                # (0.9 and 0.6 m before IN)
                frame(0, 0.02, 0.012, 0.1), frame(0, 0.02, 0.008, 0.4),
                # turn (IN 2): the truth 0.2 rad right of IN, lines read 0.05 and 0.07 rad off
                frame(1, 0.31, -0.15), frame(1, 0.31, -0.13),
                frame(1, 0.31, None)]  # no heading from lines: left out
        with open(trace, "w") as f:
            for r in rows:
                f.write(json.dumps(r) + "\n")
        r = run(trace, "--worst", "1")
        out = r.stdout
        if r.returncode != 0:
            failures.append(f"exit {r.returncode}: {r.stderr}")
        if "4 frames of 2 segments in 1 traces" not in out:
            failures.append(f"the count of frames and segments: {out}")
        # straight: mean error 0, within RMS 2 mrad
        if "0.00 - 0.05         1       2            0.0            0.0              2.0" not in out:
            failures.append(f"the straight segment's bin: {out}")
        # turn: mean +60 mrad, within RMS 10 mrad
        if "0.30 -              1       2           60.0           60.0             10.0" not in out:
            failures.append(f"the turn's bin: {out}")
        if "IN 2: mean +60.0 mrad over 2 frames, taught turn 0.500 rad" not in out:
            failures.append(f"--worst 1: {out}")
        # --frames: the straight segment's frames 0.9 and 0.6 m from IN at a relative yaw of
        # 0.01 rad (2 mrad RMS), the turn's 1.5 m from IN 2 at 0.2 rad (50 and 70: 60.8 RMS)
        r = run(trace, "--frames")
        grid = r.stdout.split("distance m")[-1]
        if "0.5 -           2.0 /     2      60.8 /     2       nan /     0" not in grid:
            failures.append(f"--frames: {r.stdout}")
        if "0 - 0.25        nan /     0       nan /     0       nan /     0" not in grid:
            failures.append(f"--frames, near IN: {r.stdout}")
        old = os.path.join(d, "old.jsonl")
        with open(old, "w") as f:
            f.write(json.dumps({"taught_key_images": [{"x_m": 0.0, "y_m": 0.0}]}) + "\n")
        r = run(old)
        if r.returncode == 0 or "no taught yaws" not in r.stderr:
            failures.append("a trace without taught yaws was not refused")
        r = run(trace, "--bins", "0.3,0.1")
        if r.returncode == 0 or "increasing" not in r.stderr:
            failures.append("decreasing --bins were not refused")
    for f in failures:
        print("FAIL:", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
