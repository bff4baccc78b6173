#!/usr/bin/env python3
"""bench/closed_loop/fix_error_by_distance.py on a small synthetic trace: a fix's lateral error is
its reading minus the truth against the chord IP -> IN, binned by the fix's own distance from IN
(or the true one); frames without a fix or without vnhv_fix_r_units are left out, and a file
that is not a trace is an error."""
import json
import os
import subprocess
import sys
import tempfile

TOOL = os.path.join(os.path.dirname(__file__), "..", "..", "bench", "closed_loop",
                    "fix_error_by_distance.py")


def frame(x, y, lat_fix, r_fix):
    # Key images at (0, 0) and (1, 0): the chord runs along +x, left is +y.
    t = {"ip": 0, "in": 1, "vnhv_fix_lateral_m": lat_fix, "vnhv_fix_r_units": r_fix}
    return {"t_s": 0.0, "gt": {"x_m": x, "y_m": y, "yaw_rad": 0.0, "s_m": x, "lateral_m": y},
            "telemetry": t, "command": {"v_m_s": 0.1, "omega_rad_s": 0.0}}


def main():
    failures = []
    with tempfile.TemporaryDirectory() as d:
        trace = os.path.join(d, "t.jsonl")
        rows = [{"taught_key_images": [{"x_m": 0.0, "y_m": 0.0}, {"x_m": 1.0, "y_m": 0.0}]},
                frame(0.9, 0.10, 0.13, 0.1),   # 3 cm off, fix 0.1 from IN
                frame(0.9, 0.10, 0.07, 0.1),   # 3 cm off the other way
                frame(-0.5, 0.10, 0.20, 1.5),  # 10 cm off, fix 1.5 from IN (true 1.5)
                frame(0.5, 0.0, None, None)]   # no fix: left out
        with open(trace, "w") as f:
            for r in rows:
                f.write(json.dumps(r) + "\n")
        r = subprocess.run([sys.executable, TOOL, trace], capture_output=True, text=True)
        out = r.stdout
        if r.returncode != 0:
            failures.append(f"exit {r.returncode}: {r.stderr}")
        if "3 fixes of 1 segments in 1 traces" not in out:
            failures.append("the count of fixes and segments")
        if " 0.00 -  0.25         1      2             3.0     3.0     3.0" not in out:
            failures.append("the near bin: two fixes 3 cm off")
        if " 1.50 -  1.75         1      1            10.0    10.0    10.0" not in out:
            failures.append("the far bin: one fix 10 cm off")
        r = subprocess.run([sys.executable, TOOL, trace, "--true-distance", "--bin", "1"],
                           capture_output=True, text=True)
        if " 0.00 -  1.00         1      2" not in r.stdout or " 1.00 -  2.00         1      1" \
                not in r.stdout:
            failures.append(f"--true-distance --bin 1: {r.stdout}")
        bad = os.path.join(d, "bad.jsonl")
        with open(bad, "w") as f:
            f.write('{"x": 1}\n')
        r = subprocess.run([sys.executable, TOOL, bad], capture_output=True, text=True)
        if r.returncode == 0 or "not an evaluate --trace file" not in r.stderr:
            failures.append("a file that is not a trace was not refused")
    for f in failures:
        print("FAIL:", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
