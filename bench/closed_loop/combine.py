#!/usr/bin/env python3
"""Combine `pepper_app evaluate --json` files (shards of one measurement) into one Markdown table.

Usage: bench/closed_loop/combine.py SHARD.json [SHARD.json ...] [--out combined.json]
                                    [--html index.html]

One row per (world, features, controller, size, disturbances): success, the mean of the per-run
lateral RMS and the largest per-run maximum over the runs that succeeded (cm), the longest
distance any run drove before it first came within 5 cm of the path, the range of the per-run
median step times, and every failed run with how and where it ended. Definitions:
docs/evaluation.md. Evaluations of the same configuration in several shards (e.g. `--run 1 2 3`
and `--run 4 5 6`) are merged run by run.

Generated worlds (`gen_<kind>_<seed>`, from `pepper_app world generate`) get a second table, one
row per disturbance over all of them, as issue 26 states its targets: success over all runs,
lateral RMS on the successes, and every failure with its world seed and how it ended.

Drift corrected at re-acquisition (issue 29): the distribution (median, max; cm and degrees) of
the correction the odometry needed when vision came back after a stretch driven blind, over all
runs.

`--html FILE` writes one page with the whole matrix at a glance: the failed runs first, then a
table per world (a row per disturbance) coloured against issue 26's targets (green: every run
succeeded with lateral RMS <= 5 cm and max <= 15 cm; amber: all succeeded, accuracy over a
target; red: a run failed), each row linked to that configuration's report and showing its top
view when `evaluate --plots` wrote one beside the JSON (matrix.sh: DIR/NAME.json and DIR/NAME/).
Each failed run in the first table, and each row's runs (failed ones first, framed in red), show
that run's own small top view (`evaluate --plots` writes PREFIX + run<N>_top_view.png, PREFIX =
world_features_[disturbances_]); a report written before those existed gets a note instead.
"""
import argparse
import html
import json
import math
import os
import statistics
import sys

# Issue 26's targets per configuration.
TARGET_RMS_M = 0.05
TARGET_MAX_M = 0.15


def disturbance_name(e):
    """The disturbances, the light one with its factor (x0.6 and x1.4 are different rows; a
    spread over the runs, evaluate's default, shows its range)."""
    factors = sorted({r.get("light_factor") for r in e["runs"] if r.get("light_factor")})
    names = []
    for d in e["disturbances"]:
        if d == "light" and factors:
            d += f" x{factors[0]:g}" if len(factors) == 1 else f" x{factors[0]:g}-{factors[-1]:g}"
        names.append(d)
    return "+".join(names) or "none"


def plots_prefix(e):
    """The file-name prefix `evaluate --plots` gives an evaluation's plots (cmd_evaluate.cpp)."""
    dist = "+".join(e["disturbances"])
    return f"{e['world']}_{e['features']}_" + (f"{dist}_" if dist else "")


def key_of(e):
    return (e["world"], e["features"], e["controller"], e["size"], disturbance_name(e))


def fmt(x, scale=1.0, digits=1):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    return f"{x * scale:.{digits}f}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="+")
    ap.add_argument("--out", help="also write the merged evaluations as one JSON file")
    ap.add_argument("--html", help="also write an HTML index of the matrix (see above)")
    a = ap.parse_args()
    merged = {}
    reports = {}  # key -> (the configuration's report folder (evaluate --plots), plots prefix)
    for f in a.files:
        with open(f) as fh:
            doc = json.load(fh)
        plots = f[:-len(".json")] if f.endswith(".json") else None
        for e in doc["evaluations"]:
            k = key_of(e)
            if plots and os.path.isfile(os.path.join(plots, "report.html")):
                reports.setdefault(k, (plots, plots_prefix(e)))
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
    drift = drift_summary(merged)
    if drift:
        print()
        print(drift)
    if a.html:
        write_html(a.html, merged, reports, drift)
    if a.out:
        with open(a.out, "w") as fh:
            json.dump({"format": "pepper.evaluation", "version": 1,
                       "evaluations": list(merged.values())}, fh, indent=1)
    return 0


def drift_summary(merged):
    """One line: the corrections at re-acquisition over every run, or None if there were none."""
    cm, deg = [], []
    for e in merged.values():
        for r in e["runs"]:
            for q in r.get("reacquisitions") or []:
                if q.get("corrected_m") is not None:
                    cm.append(100.0 * q["corrected_m"])
                if q.get("corrected_rad") is not None:
                    deg.append(math.degrees(abs(q["corrected_rad"])))
    if not cm:
        return None
    return (f"Drift corrected at re-acquisition ({len(cm)} re-acquisitions with a correction): "
            f"median {statistics.median(cm):.1f} cm / {statistics.median(deg):.1f} deg, "
            f"max {max(cm):.1f} cm / {max(deg):.1f} deg.")


def row_stats(e):
    runs = sorted(e["runs"], key=lambda r: r["index"])
    ok = [r for r in runs if r["success"]]
    rms = [r["lateral_rms_m"] for r in ok if r["lateral_rms_m"] is not None]
    mx = [r["lateral_max_m"] for r in ok if r["lateral_max_m"] is not None]
    mean_rms = sum(rms) / len(rms) if rms else None
    worst = max(mx) if mx else None
    if len(ok) < len(runs):
        verdict = "fail"
    elif (mean_rms is not None and mean_rms > TARGET_RMS_M) or (worst is not None and worst > TARGET_MAX_M):
        verdict = "over"
    else:
        verdict = "ok"
    return runs, ok, mean_rms, worst, verdict


def write_html(path, merged, reports, drift):
    base = os.path.dirname(os.path.abspath(path))

    def link(k, text):
        if k not in reports:
            return html.escape(text)
        href = os.path.relpath(os.path.join(reports[k][0], "report.html"), base)
        return f'<a href="{html.escape(href)}">{html.escape(text)}</a>'

    def image(k, name):
        """The report's PNG `name` (prefixed as evaluate writes it; unprefixed in old reports),
        relative to the index, or None."""
        if k not in reports:
            return None
        folder, prefix = reports[k]
        for f in (prefix + name, name):
            if os.path.isfile(os.path.join(folder, f)):
                return os.path.relpath(os.path.join(folder, f), base)
        return None

    def thumb(k):
        src = image(k, "top_view.png")
        return f'<img src="{html.escape(src)}" alt="top view" loading="lazy">' if src else ""

    def run_thumb(k, r):
        src = image(k, f"run{r['index'] + 1}_top_view.png")
        if not src:
            return None
        what = f"run {r['index'] + 1}: " + ("ok" if r["success"] else r["outcome"])
        cls = "run" if r["success"] else "run failed"
        return (f"<figure class='{cls}'><img src=\"{html.escape(src)}\" alt=\"{html.escape(what)}\" "
                f"loading='lazy'><figcaption>{html.escape(what)}</figcaption></figure>")

    def runs_cell(k, runs):
        if k not in reports:
            return ""
        figs = [run_thumb(k, r) for r in sorted(runs, key=lambda r: (r["success"], r["index"]))]
        if not any(figs):
            return ("<small>no per-run top views in this report (written before `evaluate --plots` "
                    "drew one per run): re-run the configuration</small>")
        return "".join(f for f in figs if f)

    out = ["<!doctype html><meta charset='utf-8'><title>Closed-loop matrix</title><style>",
           "body{font:14px sans-serif;margin:20px}table{border-collapse:collapse;margin:8px 0 24px}",
           "td,th{border:1px solid #ccc;padding:4px 8px;vertical-align:top}",
           ".ok{background:#dcfce7}.over{background:#fef3c7}.fail{background:#fee2e2}",
           "img{width:220px}figure.run{display:inline-block;margin:2px;text-align:center}",
           "figure.run img{width:150px;border:2px solid #ccc}figure.failed img{border-color:#dc2626}",
           "figcaption{font-size:11px}</style>",
           "<h1>Closed-loop matrix</h1>",
           f"<p>Targets (issue 26): every run succeeds, lateral RMS &le; {TARGET_RMS_M * 100:.0f} cm, "
           f"max &le; {TARGET_MAX_M * 100:.0f} cm once converged. Green: met; amber: all runs "
           "succeeded, accuracy over a target; red: a run failed.</p>"]
    if drift:
        out.append(f"<p>{html.escape(drift)}</p>")
    fails = [(k, r) for k in sorted(merged) for r in sorted(merged[k]["runs"], key=lambda r: r["index"])
             if not r["success"]]
    out.append(f"<h2 id='failures'>Failed runs ({len(fails)})</h2>")
    if fails:
        out.append("<table><tr><th>world</th><th>disturbance</th><th>run</th><th>how it ended</th>"
                   "<th>top view of the run</th></tr>")
        for k, r in fails:
            out.append(f"<tr class='fail'><td>{link(k, k[0])}</td><td>{html.escape(k[4])}</td>"
                       f"<td>{r['index'] + 1}</td><td>{html.escape(r['outcome'])} at "
                       f"{r['travelled_m']:.1f} m {html.escape(r.get('detail') or '')}</td>"
                       f"<td>{run_thumb(k, r) or ''}</td></tr>")
        out.append("</table>")
    else:
        out.append("<p>none</p>")
    worlds = {}
    for k in merged:
        worlds.setdefault(k[:4], []).append(k)
    for w in sorted(worlds):
        out.append(f"<h2>{html.escape(w[0])} <small>({html.escape(' / '.join(w[1:]))})</small></h2>")
        out.append("<table><tr><th>disturbance</th><th>success</th><th>lateral RMS / max (cm)</th>"
                   "<th>step ms (per-run medians)</th><th>top view</th>"
                   "<th>each run (failures first)</th></tr>")
        for k in sorted(worlds[w], key=lambda k: k[4]):
            runs, ok, mean_rms, worst, verdict = row_stats(merged[k])
            steps = [r["step_ms_median"] for r in runs if r["step_ms_median"] is not None]
            out.append(f"<tr class='{verdict}'><td>{link(k, k[4])}</td><td>{len(ok)}/{len(runs)}</td>"
                       f"<td>{fmt(mean_rms, 100)} / {fmt(worst, 100)}</td>"
                       f"<td>{fmt(min(steps)) if steps else '-'}-{fmt(max(steps)) if steps else '-'}</td>"
                       f"<td>{thumb(k)}</td><td>{runs_cell(k, runs)}</td></tr>")
        out.append("</table>")
    tmp = path + ".tmp"
    with open(tmp, "w") as fh:
        fh.write("\n".join(out) + "\n")
    os.replace(tmp, path)


if __name__ == "__main__":
    sys.exit(main())
