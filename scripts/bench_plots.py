#!/usr/bin/env python3
"""Plots and summary.md of a Tessera throughput report (called by scripts/bench).

    bench_plots.py RESULTS_DIR [--out DIR] [--dpi N]

Reads whatever of these RESULTS_DIR holds (Google Benchmark JSON unless said otherwise):
  bandwidth.json    bandwidth/triad/threads:<T>          (bench_bandwidth)
  kernels.json      kernel/<family>/<variant>            (bench_kernels)
  solver.json       solver/<mode>/<scene>/threads:<T>    (bench_solver)
  scaling.json      solver_size/gs/<kind>:<size>/threads:<T>  (bench_solver)
  coloring.json     coloring/<strategy>/<mesh>           (bench_coloring)
  convergence.json  residual per iteration               (convergence_report, its own JSON)
  accuracy.md       table of the accuracy set (scripts/bench_accuracy.py), copied into
                    summary.md with accuracy.png
and writes into RESULTS_DIR (or DIR) one PNG per plot it has data for (kernels.png,
solver_scaling.png, size_scaling.png, coloring.png, convergence.png) and summary.md with the
figures, including the fraction of the bandwidth ceiling the solver reaches.

Bandwidth ceiling of a scene at T threads = triad bandwidth at T threads (bytes/s) divided by
the bytes a projection must move (the bytes_per_projection counter of bench_solver, a traffic
model described in solver_benchmarks.cpp and docs/performance.md). With repetitions the
median is used.
"""
import argparse
import json
import math
import os
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after the backend is chosen)
from matplotlib.ticker import FuncFormatter  # noqa: E402

# Projections per second in millions on the axes (no "1e7" offset to multiply in one's head).
MILLIONS = FuncFormatter(lambda value, _: f"{value / 1e6:g}")

MODES = ["gs", "hybrid", "jacobi", "sequential"]


# ---------------------------------------------------------------- reading benchmark JSON
def load_json(directory, name):
    path = os.path.join(directory, name)
    if not os.path.exists(path):
        return None
    with open(path) as file:
        text = file.read()
    if not text.strip():
        return None
    return json.loads(text)


def strip_real_time(name):
    return name[: -len("/real_time")] if name.endswith("/real_time") else name


def benchmark_rows(report):
    """{run name: row} with one row per benchmark: the median aggregate when the run had
    repetitions, else the median (by time) of its iteration rows."""
    if report is None:
        return {}
    medians, iterations = {}, {}
    for row in report.get("benchmarks", []):
        if row.get("error_occurred"):
            continue
        name = strip_real_time(row.get("run_name", row["name"]))
        if row.get("run_type") == "aggregate":
            if row.get("aggregate_name") == "median":
                medians[name] = row
        else:
            iterations.setdefault(name, []).append(row)
    rows = dict(medians)
    for name, runs in iterations.items():
        if name not in rows:
            runs = sorted(runs, key=lambda r: r["real_time"])
            rows[name] = runs[len(runs) // 2]
    return rows


def seconds(row):
    scale = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}[row.get("time_unit", "ns")]
    return row["real_time"] * scale


def cpu_share(row):
    """CPU time over wall time of the benchmark's main thread: about 1 for a one-thread run
    on an idle machine; well below 1 when other processes took the core."""
    return f"{row['cpu_time'] / row['real_time']:.2f}" if row.get("real_time") else "–"


def thread_count(name):
    for part in name.split("/"):
        if part.startswith("threads:"):
            return int(part.split(":")[1])
    return None


def context(*reports):
    for report in reports:
        if report and "context" in report:
            return report["context"]
    return {}


# ---------------------------------------------------------------- formatting
def si(value, unit=""):
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "–"
    for factor, prefix in ((1e12, "T"), (1e9, "G"), (1e6, "M"), (1e3, "k")):
        if abs(value) >= factor:
            return f"{value / factor:.3g} {prefix}{unit}"
    return f"{value:.3g} {unit}".rstrip()


def table(header, rows):
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(cell) for cell in row) + " |" for row in rows]
    return "\n".join(lines)


# ---------------------------------------------------------------- bandwidth
def bandwidth_by_threads(report):
    """{threads: bytes/s} of the triad."""
    result = {}
    for name, row in benchmark_rows(report).items():
        if name.startswith("bandwidth/triad") and "bytes_per_second" in row:
            result[thread_count(name)] = row["bytes_per_second"]
    return result


def bandwidth_at(bandwidth, threads):
    """The triad bandwidth measured at `threads`, or at the nearest measured count."""
    if not bandwidth:
        return None
    if threads in bandwidth:
        return bandwidth[threads]
    nearest = min(bandwidth, key=lambda t: (abs(t - threads), -t))
    return bandwidth[nearest]


# ---------------------------------------------------------------- kernels
def plot_kernels(rows, path, dpi):
    families = {}
    for name, row in rows.items():
        parts = name.split("/")
        if len(parts) == 3 and parts[0] == "kernel" and "items_per_second" in row:
            families.setdefault(parts[1], {})[parts[2]] = row["items_per_second"]
    families = {f: v for f, v in families.items() if "scalar" in v and "batch" in v}
    if not families:
        return None
    names = sorted(families)
    fig, ax = plt.subplots(figsize=(10, 4.8))
    width = 0.38
    xs = range(len(names))
    scalar = [families[f]["scalar"] for f in names]
    batch = [families[f]["batch"] for f in names]
    ax.bar([x - width / 2 for x in xs], scalar, width, label="scalar API (AoS loop)", color="#9e9e9e")
    bars = ax.bar([x + width / 2 for x in xs], batch, width, label="batched SIMD kernel (SoA)", color="#1f77b4")
    for bar, s, b in zip(bars, scalar, batch):
        ax.annotate(f"×{b / s:.1f}", (bar.get_x() + bar.get_width() / 2, bar.get_height()),
                    ha="center", va="bottom", fontsize=8, xytext=(0, 2), textcoords="offset points")
    ax.set_yscale("log")
    ax.set_xticks(list(xs))
    ax.set_xticklabels([n.replace("_", "\n") for n in names], fontsize=8)
    ax.set_ylabel("constraint projections / s (one thread)")
    ax.set_title("Kernels: scalar API vs batched kernel, 65,536 constraints, random gathers")
    ax.legend(fontsize=8)
    ax.grid(axis="y", which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    lines = [table(["family", "scalar (proj/s)", "batch (proj/s)", "speed-up"],
                   [[f, si(families[f]["scalar"]), si(families[f]["batch"]),
                     f"{families[f]['batch'] / families[f]['scalar']:.1f}×"] for f in names])]
    return "\n".join(lines)


# ---------------------------------------------------------------- solver thread scaling
def plot_solver_scaling(rows, bandwidth, path, dpi):
    scenes = {}
    for name, row in rows.items():
        parts = name.split("/")
        if len(parts) == 4 and parts[0] == "solver" and parts[1] in MODES and "items_per_second" in row:
            scenes.setdefault(parts[2], {}).setdefault(parts[1], {})[thread_count(name)] = row
    if not scenes:
        return None
    names = sorted(scenes)
    columns = min(len(names), 4)
    rows_of_plots = math.ceil(len(names) / columns)
    fig, axes = plt.subplots(rows_of_plots, columns, figsize=(3.6 * columns, 3.4 * rows_of_plots),
                             squeeze=False)
    summary = []
    for index, scene in enumerate(names):
        ax = axes[index // columns][index % columns]
        for mode in MODES:
            runs = scenes[scene].get(mode)
            if not runs:
                continue
            threads = sorted(runs)
            ax.plot(threads, [runs[t]["items_per_second"] for t in threads], marker="o", label=mode)
            for t in threads:
                row = runs[t]
                bytes_per = row.get("bytes_per_projection")
                ceiling = (bandwidth_at(bandwidth, t) / bytes_per
                           if bytes_per and bandwidth_at(bandwidth, t) else None)
                summary.append([scene, mode, t, si(row["items_per_second"]),
                                f"{seconds(row) * 1e3:.2f}", cpu_share(row),
                                si(ceiling) if ceiling else "–",
                                f"{100 * row['items_per_second'] / ceiling:.0f} %" if ceiling else "–"])
        all_threads = sorted({t for runs in scenes[scene].values() for t in runs})
        ax.set_xticks(all_threads)
        ax.set_xlabel("threads")
        ax.set_ylabel("M projections / s")
        ax.yaxis.set_major_formatter(MILLIONS)
        ax.set_title(scene, fontsize=10)
        ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    for index in range(len(names), rows_of_plots * columns):
        axes[index // columns][index % columns].axis("off")
    fig.suptitle("Solver: one projection sweep, projections/s against worker threads")
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return table(["scene", "mode", "threads", "projections/s", "ms per sweep", "CPU / wall",
                  "bandwidth ceiling", "of ceiling"], summary)


# ---------------------------------------------------------------- size scaling
def size_points(rows):
    """{kind: {threads: [(size, row), ...] sorted by particles}}"""
    kinds = {}
    for name, row in rows.items():
        parts = name.split("/")
        if len(parts) == 4 and parts[0] == "solver_size" and "items_per_second" in row:
            kind, size = parts[2].split(":")
            kinds.setdefault(kind, {}).setdefault(thread_count(name), []).append((int(size), row))
    for by_threads in kinds.values():
        for points in by_threads.values():
            points.sort(key=lambda p: p[1].get("particles", p[0]))
    return kinds


def kind_label(kind, size):
    return f"cloth {size}²" if kind == "cloth" else f"bar {size}×{size}×{4 * size}"


def plot_size_scaling(rows, bandwidth, path, dpi):
    kinds = size_points(rows)
    if not kinds:
        return None, None
    names = sorted(kinds)
    fig, axes = plt.subplots(len(names), 3, figsize=(14, 3.8 * len(names)), squeeze=False)
    summary, largest = [], []
    for index, kind in enumerate(names):
        ax_rate, ax_bytes, ax_fraction = axes[index]
        for threads in sorted(kinds[kind]):
            points = kinds[kind][threads]
            particles = [row.get("particles", size) for size, row in points]
            rates = [row["items_per_second"] for _, row in points]
            (line,) = ax_rate.plot(particles, rates, marker="o", label=f"gs, {threads} thread(s)")
            band = bandwidth_at(bandwidth, threads)
            ceilings = [band / row["bytes_per_projection"] if band and row.get("bytes_per_projection")
                        else None for _, row in points]
            if band:
                ax_rate.plot(particles, ceilings, linestyle="--", color=line.get_color(),
                             label=f"bandwidth ceiling, {threads} thread(s)")
                ax_fraction.plot(particles, [100 * r / c for r, c in zip(rates, ceilings)],
                                 marker="o", color=line.get_color(), label=f"{threads} thread(s)")
            for (size, row), rate, ceiling in zip(points, rates, ceilings):
                fraction = rate / ceiling if ceiling else None
                summary.append([kind_label(kind, size), threads, f"{row.get('particles', 0):,.0f}",
                                f"{row.get('constraints', 0):,.0f}", si(rate), cpu_share(row),
                                f"{row.get('bytes_per_projection', float('nan')):.0f}",
                                si(ceiling) if ceiling else "–",
                                f"{100 * fraction:.1f} %" if fraction else "–"])
            size, row = points[-1]
            if ceilings[-1]:
                largest.append((kind_label(kind, size), threads, rates[-1], ceilings[-1]))
        # What must move per projection (the model, the same for every thread count) against
        # what the memory bus could move in the time one projection took: where the two
        # meet, the sweep runs at the bandwidth ceiling.
        points = kinds[kind][max(kinds[kind])]
        ax_bytes.plot([row.get("particles", s) for s, row in points],
                      [row.get("bytes_per_projection", float("nan")) for _, row in points],
                      marker="s", color="#555555", label="must move (traffic model)")
        for threads in sorted(kinds[kind]):
            band = bandwidth_at(bandwidth, threads)
            if not band:
                continue
            points = kinds[kind][threads]
            ax_bytes.plot([row.get("particles", s) for s, row in points],
                          [band / row["items_per_second"] for _, row in points], marker="o",
                          linestyle=":", label=f"triad bandwidth ÷ measured rate, {threads} thread(s)")
        ax_bytes.legend(fontsize=7)
        title = "cloth N×N (distance + dihedral)" if kind == "cloth" else "FEM tet bar n×n×4n"
        for ax in (ax_rate, ax_bytes, ax_fraction):
            ax.set_xscale("log")
            ax.set_xlabel("particles")
            ax.grid(alpha=0.3, which="both")
        ax_rate.set_ylim(bottom=0)
        ax_rate.set_ylabel("M projections / s")
        ax_rate.yaxis.set_major_formatter(MILLIONS)
        ax_rate.set_title(f"{title}: throughput", fontsize=10)
        ax_rate.legend(fontsize=7)
        ax_bytes.set_ylabel("bytes per projection")
        ax_bytes.set_ylim(bottom=0)
        ax_bytes.set_title(f"{title}: bytes per projection", fontsize=10)
        ax_fraction.set_ylabel("% of bandwidth ceiling")
        ax_fraction.set_ylim(bottom=0)
        ax_fraction.set_title(f"{title}: fraction of the ceiling", fontsize=10)
        if ax_fraction.lines:
            ax_fraction.legend(fontsize=7)
    fig.suptitle("Size scaling: gs projection sweep against problem size, with the triad-bandwidth ceiling")
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    text = table(["scene", "threads", "particles", "constraints", "projections/s", "CPU / wall",
                  "bytes/projection", "bandwidth ceiling", "of ceiling"], summary)
    return text, largest


# ---------------------------------------------------------------- colouring
def plot_coloring(rows, path, dpi):
    data = {}
    for name, row in rows.items():
        parts = name.split("/")
        if len(parts) == 3 and parts[0] == "coloring" and "+" not in parts[1] and "colours" in row:
            data.setdefault(parts[2], {})[parts[1]] = row
    if not data:
        return None
    meshes = sorted(data)
    strategies = sorted({s for per_mesh in data.values() for s in per_mesh})
    fig, (ax_ratio, ax_time) = plt.subplots(1, 2, figsize=(13, 4.4))
    width = 0.8 / len(meshes)
    for m, mesh in enumerate(meshes):
        xs = [i + (m - (len(meshes) - 1) / 2) * width for i in range(len(strategies))]
        ratios = [data[mesh][s]["colours"] / data[mesh][s]["lower_bound"]
                  if s in data[mesh] and data[mesh][s].get("lower_bound") else 0 for s in strategies]
        times = [seconds(data[mesh][s]) if s in data[mesh] else 0 for s in strategies]
        ax_ratio.bar(xs, ratios, width, label=mesh)
        ax_time.bar(xs, times, width, label=mesh)
    for ax in (ax_ratio, ax_time):
        ax.set_xticks(range(len(strategies)))
        ax.set_xticklabels(strategies, rotation=30, ha="right", fontsize=8)
        ax.grid(axis="y", alpha=0.3, which="both")
        ax.legend(fontsize=7)
    ax_ratio.axhline(1, color="black", linewidth=0.8)
    ax_ratio.set_ylabel("colours / lower bound")
    ax_ratio.set_title("Colours used, relative to the lower bound (1 = optimal)", fontsize=10)
    ax_time.set_yscale("log")
    ax_time.set_ylabel("seconds per colouring (all threads)")
    ax_time.set_title("Colouring time", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return table(["mesh", "strategy", "colours", "lower bound", "colours / bound", "seconds"],
                 [[mesh, s, f"{data[mesh][s]['colours']:.0f}", f"{data[mesh][s]['lower_bound']:.0f}",
                   f"{data[mesh][s]['colours'] / data[mesh][s]['lower_bound']:.2f}",
                   f"{seconds(data[mesh][s]):.3f}"]
                  for mesh in meshes for s in strategies if s in data[mesh]])


# ---------------------------------------------------------------- convergence
def plot_convergence(report, path, dpi):
    scenes = report.get("scenes", {})
    if not scenes:
        return None
    names = [n for n in ("cloth", "bar") if n in scenes] + [n for n in scenes if n not in ("cloth", "bar")]
    fig, axes = plt.subplots(len(names), 2, figsize=(12, 3.8 * len(names)), squeeze=False)
    summary = []
    for index, scene in enumerate(names):
        entry = scenes[scene]
        measure = entry.get("measure", "rms")
        measure_label = ("rms residual of all constraints" if measure == "rms" else
                         f"rms residual of the {measure[len('rms_'):]} constraints")
        label = (f"cloth {report.get('cloth_size')}²" if scene == "cloth" else
                 f"FEM bar {report.get('bar_size')}×{report.get('bar_size')}×{4 * report.get('bar_size', 0)}"
                 if scene == "bar" else scene)
        for column, (group, title) in enumerate((("modes", "solver modes (greedy colouring)"),
                                                 ("strategies", "gs under each colouring strategy"))):
            ax = axes[index][column]
            for run, curves in entry.get(group, {}).items():
                rms = [math.nan if v is None else v for v in curves.get(measure, curves["rms"])]
                ax.plot(range(len(rms)), rms, label=run, linewidth=1.2)
                summary.append([label, measure_label, "mode" if group == "modes" else "gs, strategy", run,
                                f"{rms[0]:.3g}", f"{rms[min(10, len(rms) - 1)]:.3g}", f"{rms[-1]:.3g}"])
            ax.set_yscale("log")
            ax.set_xlabel("iteration")
            ax.set_ylabel("rms residual (all constraints)" if measure == "rms" else
                          f"rms residual ({measure[len('rms_'):]} constraints)")
            ax.set_title(f"{label}: {title}", fontsize=10)
            ax.grid(alpha=0.3, which="both")
            ax.legend(fontsize=7, ncol=2)
    fig.suptitle(f"Convergence: residual after each iteration of one step "
                 f"(after {report.get('warmup_steps', '?')} warm-up steps)")
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    iterations = report.get("iterations", "K")
    return table(["scene", "measure", "run", "name", "residual at 0", "at 10", f"at {iterations}"],
                 summary)


# ---------------------------------------------------------------- main
def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("results", help="the results directory of scripts/bench")
    parser.add_argument("--out", help="write the plots and summary.md here instead")
    parser.add_argument("--dpi", type=int, default=100)
    args = parser.parse_args()
    directory = args.results
    target = args.out or directory
    os.makedirs(target, exist_ok=True)

    reports = {name: load_json(directory, f"{name}.json")
               for name in ("bandwidth", "kernels", "solver", "scaling", "coloring")}
    convergence = load_json(directory, "convergence.json")
    bandwidth = bandwidth_by_threads(reports["bandwidth"])
    info = context(*reports.values())

    out = ["# Tessera throughput report", ""]
    meta = load_json(directory, "run.json") or {}
    facts = [("host", info.get("host_name")), ("date", info.get("date")),
             ("CPU", meta.get("cpu")), ("CPUs", info.get("num_cpus")),
             ("MHz", info.get("mhz_per_cpu")),
             ("SIMD target", info.get("tessera_simd_target")),
             ("SIMD lanes", info.get("tessera_simd_lanes")),
             ("precision", info.get("tessera_precision")),
             ("Tessera", info.get("tessera_version")),
             ("mode", meta.get("mode")), ("sets", meta.get("sets")),
             ("load before", meta.get("load_before")), ("load after", meta.get("load_after")),
             ("wall time (s)", meta.get("wall_seconds"))]
    caches = info.get("caches")
    if caches:
        facts.append(("caches", ", ".join(f"L{c['level']} {c['type'][0]} {c['size'] // 1024} KiB"
                                          f"{' ×' + str(c['num_sharing']) if c.get('num_sharing') else ''}"
                                          for c in caches)))
    out += [f"- {k}: {v}" for k, v in facts if v not in (None, "")]
    out.append("")

    written = []
    if bandwidth:
        out += ["## Memory bandwidth (triad a = b + s·c, 3 × 8 bytes per element)", "",
                table(["threads", "bytes/s"], [[t, si(b, "B/s")] for t, b in sorted(bandwidth.items())]), ""]

    def section(title, png, text):
        if text:
            written.append(png)
            out.extend([f"## {title}", "", f"![{title}]({png})", "", text, ""])

    section("Kernels", "kernels.png",
            plot_kernels(benchmark_rows(reports["kernels"]), os.path.join(target, "kernels.png"), args.dpi))
    section("Solver thread scaling", "solver_scaling.png",
            plot_solver_scaling(benchmark_rows(reports["solver"]), bandwidth,
                                os.path.join(target, "solver_scaling.png"), args.dpi))
    size_text, largest = plot_size_scaling(benchmark_rows(reports["scaling"]), bandwidth,
                                           os.path.join(target, "size_scaling.png"), args.dpi)
    if largest:
        lines = ["Fraction of the bandwidth ceiling reached by gs on the largest scenes:", ""]
        for label, threads, rate, ceiling in largest:
            lines.append(f"- **{label}, {threads} thread(s): {100 * rate / ceiling:.1f} %** "
                         f"({si(rate)} projections/s of a {si(ceiling)} projections/s ceiling)")
        size_text = "\n".join(lines) + "\n\n" + size_text
    section("Size scaling and the bandwidth ceiling", "size_scaling.png", size_text)
    section("Colouring", "coloring.png",
            plot_coloring(benchmark_rows(reports["coloring"]), os.path.join(target, "coloring.png"), args.dpi))
    if convergence:
        section("Convergence", "convergence.png",
                plot_convergence(convergence, os.path.join(target, "convergence.png"), args.dpi))

    # The accuracy set writes its own table and plot (scripts/bench_accuracy.py): linked here.
    accuracy_md = os.path.join(directory, "accuracy.md")
    if os.path.exists(accuracy_md):
        with open(accuracy_md) as file:
            body = file.read().split("\n", 1)[1].strip()   # without its "# Accuracy per second"
        png = "accuracy.png" if os.path.exists(os.path.join(directory, "accuracy.png")) else None
        out.extend(["## Accuracy per second", ""] + ([f"![Accuracy per second]({png})", ""] if png else [])
                   + [body, ""])

    with open(os.path.join(target, "summary.md"), "w") as file:
        file.write("\n".join(out))
    print(f"bench_plots: wrote summary.md and {', '.join(written) if written else 'no plots'} "
          f"in {target}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
