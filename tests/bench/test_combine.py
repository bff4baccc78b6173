#!/usr/bin/env python3
"""bench/closed_loop/combine.py on two small evaluation shards: the Markdown table, the drift line
and the HTML index (failures first, rows coloured against issue 26's targets, the report and top
view linked when `evaluate --plots` wrote them beside the JSON)."""
import json
import os
import subprocess
import sys
import tempfile

COMBINE = os.path.join(os.path.dirname(__file__), "..", "..", "bench", "closed_loop", "combine.py")


def run(index, success, rms_m, max_m, corrected_m=None, outcome=None, light_factor=0.0):
    return {"index": index, "success": success, "light_factor": light_factor, "outcome": outcome or ("complete" if success else "lost"),
            "detail": "" if success else "no features", "travelled_m": 4.2,
            "lateral_rms_m": rms_m, "lateral_max_m": max_m, "first_under_5cm_m": 1.0,
            "step_ms_median": 12.0,
            "reacquisitions": [{"blind_m": 0.5, "blind_rad": 0.3, "corrected_m": corrected_m,
                                "corrected_rad": 0.02 if corrected_m is not None else None}]}


def evaluation(world, disturbance, runs):
    # As evaluate writes it: no disturbance is an empty list (shown as "none").
    return {"format": "pepper.evaluation", "version": 1, "evaluations": [
        {"world": world, "features": "lines+points", "controller": "vnhv", "size": "640x480",
         "disturbances": [] if disturbance == "none" else [disturbance], "runs": runs}]}


def main():
    failures = []

    def check(cond, what):
        if not cond:
            failures.append(what)

    with tempfile.TemporaryDirectory() as d:
        good = os.path.join(d, "room_none.json")
        bad = os.path.join(d, "room_light0.6.json")
        over = os.path.join(d, "hall_person.json")
        with open(good, "w") as fh:
            json.dump(evaluation("room", "none", [run(0, True, 0.01, 0.03, 0.04), run(1, True, 0.02, 0.05, 0.10)]), fh)
        with open(bad, "w") as fh:
            json.dump(evaluation("room", "light", [run(0, True, 0.01, 0.03, light_factor=0.6),
                                                   run(1, False, None, None, light_factor=0.6)]), fh)
        # The same world and disturbance at another light factor is another configuration.
        bright = os.path.join(d, "room_light1.4.json")
        with open(bright, "w") as fh:
            json.dump(evaluation("room", "light", [run(0, True, 0.01, 0.03, light_factor=1.4),
                                                   run(1, True, 0.01, 0.03, light_factor=1.4)]), fh)
        with open(over, "w") as fh:
            json.dump(evaluation("hall", "person", [run(0, True, 0.08, 0.20)]), fh)
        # Reports beside the JSON (matrix.sh: DIR/NAME/), files named as evaluate --plots names
        # them (PREFIX = world_features_[disturbances_]): the good configuration and the failed
        # one with a top view per run; hall's report predates those (combined top view only).
        reports = {"room_none": ("room_lines+points_", 2), "room_light0.6": ("room_lines+points_light_", 2),
                   "hall_person": ("hall_lines+points_person_", 0)}
        for folder, (prefix, n_runs) in reports.items():
            os.makedirs(os.path.join(d, folder))
            names = ["report.html", prefix + "top_view.png"]
            names += [f"{prefix}run{i}_top_view.png" for i in range(1, n_runs + 1)]
            for name in names:
                open(os.path.join(d, folder, name), "w").close()
        index = os.path.join(d, "index.html")
        r = subprocess.run([sys.executable, COMBINE, good, bad, bright, over, "--html", index],
                           capture_output=True, text=True)
        check(r.returncode == 0, f"exit code {r.returncode}: {r.stderr}")
        check("| room | none | 2/2 |" in r.stdout, "table row of room/none")
        check("| room | light x0.6 | 1/2 |" in r.stdout, "table row of room/light x0.6")
        check("| room | light x1.4 | 2/2 |" in r.stdout, "table row of room/light x1.4")
        # Corrections 4 and 10 cm: median 7.0, max 10.0.
        check("median 7.0 cm" in r.stdout and "max 10.0 cm" in r.stdout, "drift line: " + r.stdout[-300:])
        page = open(index).read() if os.path.exists(index) else ""
        check(page.index("Failed runs (1)") < page.index("<h2>hall") if "Failed runs (1)" in page and "<h2>hall" in page else False,
              "the failures come first")
        check("<tr class='fail'>" in page, "a red row for the failed configuration")
        check("<tr class='over'>" in page, "an amber row for the configuration over the accuracy target")
        check("<tr class='ok'><td><a href=\"room_none/report.html\">none</a>" in page, "a green row linking its report")
        check('src="room_none/room_lines+points_top_view.png"' in page, "the top view shown")
        # The failed run (room light x0.6, run 2) with its own top view in the failures table.
        fail_row = page[page.index("<tr class='fail'><td>"):] if "<tr class='fail'><td>" in page else ""
        fail_row = fail_row[:fail_row.index("</tr>")] if fail_row else ""
        check('room_light0.6/room_lines+points_light_run2_top_view.png' in fail_row,
              "the failed run's own top view in the failures table: " + fail_row)
        # In its configuration's row, run 2 (failed) comes before run 1.
        row = page[page.rindex("<tr class='fail'>"):]
        row = row[:row.index("</tr>")]
        check(0 <= row.find("light_run2_top_view") < row.find("light_run1_top_view")
              and "figure class='run failed'" in row, "failed runs first in the row: " + row)
        check('room_none/room_lines+points_run1_top_view.png' in page
              and 'room_none/room_lines+points_run2_top_view.png' in page, "every run of room/none shown")
        check("no per-run top views in this report" in page, "a note where a report has none")
    for f in failures:
        print("FAIL", f)
    print("ok" if not failures else f"{len(failures)} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
