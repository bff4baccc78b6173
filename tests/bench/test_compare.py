#!/usr/bin/env python3
"""bench/closed_loop/compare.py on two small matrix directories: the per-group summary counts the
successes and the runs over the targets, a run whose outcome changed or whose RMS moved is
listed, an unchanged one is not, and a missing directory is an error."""
import json
import os
import subprocess
import sys
import tempfile

COMPARE = os.path.join(os.path.dirname(__file__), "..", "..", "bench", "closed_loop", "compare.py")


def evaluation(runs):
    return {"format": "pepper.evaluation", "version": 1, "evaluations": [
        {"world": "w", "runs": [{"index": i, "success": ok, "outcome": "complete" if ok else "collision",
                                 "lateral_rms_m": rms, "lateral_max_m": mx}
                                for i, (ok, rms, mx) in enumerate(runs)]}]}


def main():
    failures = []
    with tempfile.TemporaryDirectory() as d:
        before, after = os.path.join(d, "before"), os.path.join(d, "after")
        for path, runs in ((before, [(True, 0.02, 0.05), (False, None, None)]),
                           (after, [(True, 0.021, 0.05), (True, 0.03, 0.20)])):
            os.makedirs(path)
            with open(os.path.join(path, "gen_room_1_none.json"), "w") as f:
                json.dump(evaluation(runs), f)
        r = subprocess.run([sys.executable, COMPARE, before, after], capture_output=True, text=True)
        out = r.stdout
        if r.returncode != 0:
            failures.append(f"exit {r.returncode}: {r.stderr}")
        if "before 1/2, lateral RMS mean 2.00 cm" not in out:
            failures.append("before's summary")
        if "after 2/2, lateral RMS mean 2.55 cm, 0 over 5 cm, 1 with max > 15 cm" not in out:
            failures.append("after's summary")
        if "gen_room_1_none run 2: collision" not in out:
            failures.append("the run whose outcome changed is not listed")
        if "gen_room_1_none run 1" in out:
            failures.append("an unchanged run is listed")
        r = subprocess.run([sys.executable, COMPARE, before, os.path.join(d, "missing")],
                           capture_output=True, text=True)
        if r.returncode == 0 or "is not a directory" not in r.stderr:
            failures.append("a missing directory is not an error")
    if failures:
        print("FAILED:\n" + out + "\n".join(failures))
        return 1
    print("ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())
