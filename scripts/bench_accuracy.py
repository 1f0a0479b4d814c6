#!/usr/bin/env python3
"""Accuracy per second: the error a setting leaves against the wall time it costs.

    bench_accuracy.py --tessera PATH --out DIR [--quick] [--scenes S,...] [--grid SxK,...]
                      [--modes M,...] [--tethers auto,none] [--threads T] [--timeout S]
    bench_accuracy.py --out DIR --redraw     (accuracy.md and .png again from accuracy.json)

Runs `tessera run SCENE --json` over a grid of scenes × substeps × iterations × modes ×
tethers, always for 1 s of simulated time (60 frames at the default dt of 1/60), and records
per run the wall seconds per simulated second (seconds_stepping / simulated seconds), the
final residuals (RMS and max, overall and of the distance family) and the threads. Writes
into DIR:
  accuracy.json  every run (its settings, its measures, or why it failed)
  accuracy.md    the table, the headline for the default scene, and the Pareto front per mode
  accuracy.png   per scene: wall time per simulated second (x, log) against the max residual
                 (y, log), the Pareto front of each mode as a curve, filled markers for
                 tethers auto, hollow ones for tethers none
A run that diverges (the tool exits 1: NumericalFailure) or times out is recorded as failed
and drawn nowhere. When `tessera run --help` lists --chebyshev, jacobi is also run with
--chebyshev on, as mode `jacobi+cheb`, at the points with more than 1 iteration per substep (at
1 it ends where plain jacobi does: measured, same residuals).

The grid is a plan per scene (below): the 1024² cloth is slow (about 16× the 256² one), so it
gets few points, and sequential (one thread) runs only where it is affordable. --frames is a
test hook (the ctest smoke test runs 5 frames); reports use the default, 60.
"""
import argparse
import json
import math
import os
import re
import signal
import subprocess
import sys
import time

DEFAULT_SCENE = "cloth:256x256"
MODES = ["gs", "jacobi", "hybrid", "sequential"]
COLOURS = {"gs": "tab:blue", "jacobi": "tab:orange", "jacobi+cheb": "tab:red",
           "hybrid": "tab:green", "sequential": "tab:purple"}
# The headline's bounds: max edge stretch ≤ 10 %, distance RMS ≤ 1 %.
MAX_STRETCH = 0.10
RMS_STRETCH = 0.01


def grid(text):
    return [tuple(int(v) for v in item.lower().split("x")) for item in text.split(",") if item]


# (scene, grid, modes, tethers): the full plan and the --quick one.
FULL_PLAN = [
    (DEFAULT_SCENE, grid("16x2,32x1,64x1,32x2"), ["gs", "jacobi", "hybrid"], ["auto", "none"]),
    (DEFAULT_SCENE, grid("8x4,16x4"), ["gs"], ["auto", "none"]),
    (DEFAULT_SCENE, grid("32x1"), ["sequential"], ["auto", "none"]),
    # The default (kClothSubsteps = 160) and the cheapest point within the stretch bounds.
    (DEFAULT_SCENE, grid("128x1,160x1"), ["gs", "hybrid"], ["auto", "none"]),
    (DEFAULT_SCENE, grid("160x1"), ["sequential"], ["auto"]),
    ("bar:10x10x40", grid("8x4,16x2,32x1,64x1,32x2"), ["gs", "jacobi", "hybrid"], ["auto", "none"]),
    ("bar:10x10x40", grid("16x2,32x1"), ["sequential"], ["auto", "none"]),
    ("cloth:1024x1024", grid("32x1"), ["gs"], ["auto"]),
]
QUICK_PLAN = [
    ("cloth:64x64", grid("16x2,32x1,64x1"), MODES, ["auto", "none"]),
    ("bar:4x4x16", grid("16x2,32x1"), MODES, ["auto", "none"]),
]


def tool_has_chebyshev(tessera):
    try:
        text = subprocess.run([tessera, "run", "--help"], capture_output=True, text=True,
                              timeout=30).stdout
    except (OSError, subprocess.SubprocessError):
        return False
    return "--chebyshev" in text


def run_one(tessera, scene, substeps, iterations, mode, tethers, frames, threads, timeout):
    chebyshev = mode == "jacobi+cheb"
    command = [tessera, "run", scene, "--frames", str(frames), "--substeps", str(substeps),
               "--iterations", str(iterations), "--mode", "jacobi" if chebyshev else mode,
               "--tethers", tethers, "--json"]
    if chebyshev:
        command += ["--chebyshev", "on"]
    if threads:
        command += ["--threads", str(threads)]
    row = {"scene": scene, "substeps": substeps, "iterations": iterations, "mode": mode,
           "tethers": tethers, "frames": frames, "command": " ".join(command[1:])}
    started = time.monotonic()
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        row.update(failed=f"timed out after {timeout} s")
        return row
    row["wall_seconds_process"] = round(time.monotonic() - started, 3)
    if done.returncode != 0:
        message = (done.stderr.strip().splitlines() or ["(no message)"])[-1]
        row.update(failed=f"exit {done.returncode}: {message}")
        return row
    summary = json.loads(done.stdout)
    simulated = frames * summary["time_step"]
    row.update(
        threads=summary.get("threads"),
        simulated_seconds=simulated,
        seconds_stepping=summary["seconds_stepping"],
        wall_per_simulated_second=summary["seconds_stepping"] / simulated,
        residual_rms=summary.get("residual_rms_final"),
        residual_max=summary.get("residual_max_final"),
        distance_rms=summary.get("residual_distance_rms_final"),
        distance_max=summary.get("residual_distance_max_final"),
        constraints=summary.get("constraints"),
        colours=summary.get("colours"),
        sweep_order=summary.get("sweep_order"),   # the default (auto) picks by the scene
        state_hash=summary.get("state_hash"),
    )
    for key, value in summary.items():   # every family's residual, for the JSON
        if re.fullmatch(r"residual_[a-z_]+_(rms|max)_final", key):
            row[key] = value
    return row


def ok(row):
    return "failed" not in row and row.get("residual_max") is not None


def pareto(rows):
    """The rows not dominated in (wall time, max residual), sorted by wall time."""
    front = []
    for row in sorted(rows, key=lambda r: (r["wall_per_simulated_second"], r["residual_max"])):
        if not front or row["residual_max"] < front[-1]["residual_max"]:
            front.append(row)
    return front


def fmt(value, digits=3):
    if value is None:
        return "–"
    if isinstance(value, float):
        if value != 0 and (abs(value) < 1e-3 or abs(value) >= 1e4):
            return f"{value:.{digits - 1}e}"
        return f"{value:.{digits}g}"
    return str(value)


def setting(row):
    return f"{row['mode']} {row['substeps']}×{row['iterations']} tethers {row['tethers']}"


def headline(rows):
    """The cheapest run of the default scene within the bounds, or the closest ones."""
    scene_rows = [r for r in rows if r["scene"] == DEFAULT_SCENE and ok(r)
                  and r.get("distance_max") is not None]
    if not scene_rows:
        return []
    passing = [r for r in scene_rows
               if r["distance_max"] <= MAX_STRETCH and r["distance_rms"] <= RMS_STRETCH]
    bounds = f"max edge stretch ≤ {MAX_STRETCH:.0%} and distance RMS ≤ {RMS_STRETCH:.0%}"
    if passing:
        best = min(passing, key=lambda r: r["wall_per_simulated_second"])
        return [f"**Headline ({DEFAULT_SCENE}, {bounds}): {setting(best)}, "
                f"{best['wall_per_simulated_second']:.2f} wall s per simulated s "
                f"(distance max {fmt(best['distance_max'])}, RMS {fmt(best['distance_rms'])}; "
                f"{best['threads']} threads).**"]
    # The closest: the least max stretch, and the least stretch per unit of the bounds.
    def excess(r):
        return max(r["distance_max"] / MAX_STRETCH, r["distance_rms"] / RMS_STRETCH)
    closest = sorted(scene_rows, key=excess)[:3]
    lines = [f"**Headline ({DEFAULT_SCENE}, {bounds}): no setting of the grid reaches it.** "
             "The closest (by the larger of max / 10 % and RMS / 1 %):", ""]
    for r in closest:
        lines.append(f"- {setting(r)}: {r['wall_per_simulated_second']:.2f} wall s per simulated s, "
                     f"distance max {fmt(r['distance_max'])}, RMS {fmt(r['distance_rms'])}")
    return lines


def markdown(rows, meta):
    out = ["# Accuracy per second", ""]
    out += [f"- {k}: {v}" for k, v in meta.items() if v not in (None, "")]
    out.append("")
    out += headline(rows)
    out.append("")
    header = ["scene", "mode", "substeps×iterations", "tethers", "threads", "wall s / sim s",
              "RMS", "max", "distance RMS", "distance max"]
    out += ["| " + " | ".join(header) + " |", "|" + " --- |" * len(header)]
    for r in rows:
        if ok(r):
            cells = [r["scene"], r["mode"], f"{r['substeps']}×{r['iterations']}", r["tethers"],
                     fmt(r["threads"]), f"{r['wall_per_simulated_second']:.3g}",
                     fmt(r["residual_rms"]), fmt(r["residual_max"]), fmt(r["distance_rms"]),
                     fmt(r["distance_max"])]
        else:
            cells = [r["scene"], r["mode"], f"{r['substeps']}×{r['iterations']}", r["tethers"],
                     "", "", f"failed: {r['failed']}", "", "", ""]
        out.append("| " + " | ".join(str(c).replace("|", "/") for c in cells) + " |")
    out += ["", "Pareto front (wall time against max residual) per scene and mode:", ""]
    for scene in dict.fromkeys(r["scene"] for r in rows):
        for mode in dict.fromkeys(r["mode"] for r in rows if r["scene"] == scene):
            front = pareto([r for r in rows if r["scene"] == scene and r["mode"] == mode and ok(r)])
            if front:
                points = "; ".join(f"{r['substeps']}×{r['iterations']} {r['tethers']} "
                                   f"{r['wall_per_simulated_second']:.3g} s → {fmt(r['residual_max'])}"
                                   for r in front)
                out.append(f"- {scene}, {mode}: {points}")
    out.append("")
    return "\n".join(out)


def plot(rows, path, dpi):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    from matplotlib.ticker import FuncFormatter
    plain = FuncFormatter(lambda value, _: f"{value:g}")   # 20, not 2×10^1
    # Minor ticks: only 2× and 5× the decade are labelled.
    some = FuncFormatter(lambda value, _: f"{value:g}" if value > 0 and round(
        value / 10 ** math.floor(math.log10(value))) in (2, 5) else "")

    scenes = list(dict.fromkeys(r["scene"] for r in rows if ok(r)))
    if not scenes:
        return False
    figure, axes = plt.subplots(1, len(scenes), figsize=(5.2 * len(scenes), 4.4), squeeze=False)
    modes_seen = []
    for axis, scene in zip(axes[0], scenes):
        for mode in dict.fromkeys(r["mode"] for r in rows if r["scene"] == scene and ok(r)):
            mine = [r for r in rows if r["scene"] == scene and r["mode"] == mode and ok(r)
                    and r["residual_max"] > 0 and r["wall_per_simulated_second"] > 0]
            if not mine:
                continue
            if mode not in modes_seen:
                modes_seen.append(mode)
            colour = COLOURS.get(mode, "black")
            for r in mine:
                tethered = r["tethers"] == "auto"
                axis.scatter(r["wall_per_simulated_second"], r["residual_max"], s=30,
                             marker="o" if tethered else "s", edgecolors=colour,
                             facecolors=colour if tethered else "none", alpha=0.85, zorder=3)
            front = pareto(mine)
            axis.plot([r["wall_per_simulated_second"] for r in front],
                      [r["residual_max"] for r in front], color=colour, linewidth=1.4, zorder=2)
        if scene == DEFAULT_SCENE:
            axis.axhline(MAX_STRETCH, color="grey", linestyle=":", linewidth=1)
        axis.set_xscale("log")
        axis.set_yscale("log")
        axis.xaxis.set_major_formatter(plain)
        axis.xaxis.set_minor_formatter(some)
        axis.set_title(scene)
        axis.set_xlabel("wall seconds per simulated second")
        axis.grid(True, which="both", linewidth=0.3, alpha=0.5)
    axes[0][0].set_ylabel("max residual at 1 s (residual_max_final)")
    handles = [Line2D([], [], color=COLOURS.get(m, "black"), label=f"{m} (front)") for m in modes_seen]
    handles += [Line2D([], [], marker="o", color="grey", linestyle="none", label="tethers auto"),
                Line2D([], [], marker="s", color="grey", markerfacecolor="none", linestyle="none",
                       label="tethers none")]
    axes[0][-1].legend(handles=handles, fontsize=8, loc="best")
    figure.suptitle("Accuracy per second: Pareto front per mode (lower left is better)", fontsize=10 if len(scenes) > 1 else 8)
    figure.tight_layout()
    figure.savefig(path, dpi=dpi)
    plt.close(figure)
    return True


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--tessera", default="build/release/apps/tessera")
    parser.add_argument("--out", required=True)
    parser.add_argument("--quick", action="store_true", help="small scenes, few points")
    parser.add_argument("--scenes", help="comma-separated scenes in place of the plan")
    parser.add_argument("--grid", help="SxK,... (substeps × iterations) in place of the plan")
    parser.add_argument("--modes", help="comma-separated modes in place of the plan")
    parser.add_argument("--tethers", help="auto,none or one of them")
    parser.add_argument("--threads", type=int, default=0, help="default: the tool's (every thread)")
    parser.add_argument("--frames", type=int, default=60, help=argparse.SUPPRESS)  # test hook
    parser.add_argument("--timeout", type=float, default=900, help="seconds per run")
    parser.add_argument("--dpi", type=int, default=100)
    parser.add_argument("--redraw", action="store_true",
                        help="rewrite accuracy.md and accuracy.png from DIR/accuracy.json, running nothing")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    # Killed (SIGTERM): unwind through subprocess.run, which then kills the running tool too.
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    if args.redraw:
        with open(os.path.join(args.out, "accuracy.json")) as file:
            saved = json.load(file)
        return write_reports(saved["runs"], saved.get("meta", {}), args)

    plan = QUICK_PLAN if args.quick else FULL_PLAN
    if args.scenes or args.grid or args.modes or args.tethers:
        scenes = args.scenes.split(",") if args.scenes else list(dict.fromkeys(p[0] for p in plan))
        plan = [(s, grid(args.grid) if args.grid else grid("16x2,32x1"),
                 args.modes.split(",") if args.modes else MODES,
                 args.tethers.split(",") if args.tethers else ["auto", "none"]) for s in scenes]
    chebyshev = tool_has_chebyshev(args.tessera)
    runs = []
    for scene, points, modes, tethers in plan:
        modes = list(modes)
        if chebyshev and "jacobi" in modes:
            modes.insert(modes.index("jacobi") + 1, "jacobi+cheb")
        for substeps, iterations in points:
            for mode in modes:
                if mode == "jacobi+cheb" and iterations == 1:
                    continue   # one iteration per substep: Chebyshev has nothing to accelerate
                for tether in tethers:
                    runs.append((scene, substeps, iterations, mode, tether))

    load_before = open("/proc/loadavg").read().split()[:3] if os.path.exists("/proc/loadavg") else None
    started = time.monotonic()
    rows = []
    for index, (scene, substeps, iterations, mode, tether) in enumerate(runs, 1):
        row = run_one(args.tessera, scene, substeps, iterations, mode, tether, args.frames,
                      args.threads, args.timeout)
        rows.append(row)
        result = (f"{row['wall_per_simulated_second']:.2f} s/s, max {fmt(row['residual_max'])}, "
                  f"rms {fmt(row['residual_rms'])}") if ok(row) else row["failed"]
        print(f"bench_accuracy: [{index}/{len(runs)}] {scene} {mode} {substeps}x{iterations} "
              f"tethers {tether}: {result}", file=sys.stderr, flush=True)
        with open(os.path.join(args.out, "accuracy.json"), "w") as file:   # kept if interrupted
            json.dump({"runs": rows}, file, indent=1)
    load_after = open("/proc/loadavg").read().split()[:3] if os.path.exists("/proc/loadavg") else None
    custom = args.scenes or args.grid or args.modes or args.tethers
    meta = {"mode": "custom" if custom else "quick" if args.quick else "full", "frames": args.frames,
            "cpus": os.cpu_count(), "chebyshev_in_tool": chebyshev,
            "load before": " ".join(load_before) if load_before else None,
            "load after": " ".join(load_after) if load_after else None,
            "wall time (s)": round(time.monotonic() - started)}
    with open(os.path.join(args.out, "accuracy.json"), "w") as file:
        json.dump({"meta": meta, "runs": rows}, file, indent=1)
    return write_reports(rows, meta, args)


def write_reports(rows, meta, args):
    text = markdown(rows, meta)
    with open(os.path.join(args.out, "accuracy.md"), "w") as file:
        file.write(text)
    drew = plot(rows, os.path.join(args.out, "accuracy.png"), args.dpi)
    print(f"bench_accuracy: wrote accuracy.json, accuracy.md{', accuracy.png' if drew else ''} "
          f"({sum(ok(r) for r in rows)} of {len(rows)} runs) in {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
