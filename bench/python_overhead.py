"""What the Python binding costs, measured side by side with the same C++ calls in one run.

    PYTHONPATH=build/release/python python3 bench/python_overhead.py [build/release]

Alternates, `--repetitions` times, bench_solver's solver/step_tiny and
solver/positions/cloth1024 (Google Benchmark) with the same calls through tessera (timeit,
best of 5 loops per repetition), and prints medians and ratios:
  - step(): a 2-particle, 1-constraint model, default settings, one thread;
  - reading the positions of the 1024² cloth (locality-renumbered, as `tessera run`):
    Solver.positions (an (N, 3) user-order copy), Solver.scheduled_positions (three read-only
    views, no copy), and the C++ Solver::positions() (a std::vector copy).
"""
import argparse
import json
import pathlib
import statistics
import subprocess
import timeit

import numpy as np

import tessera


def cpp(bench, pattern):
    out = subprocess.run([str(bench), f"--benchmark_filter={pattern}", "--benchmark_format=json",
                          "--benchmark_min_time=0.3"], capture_output=True, text=True, check=True)
    (entry,) = json.loads(out.stdout)["benchmarks"]
    scale = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}[entry["time_unit"]]
    return entry["real_time"] * scale


def per_call(statement, number):
    return min(timeit.repeat(statement, number=number, repeat=5)) / number


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("build", nargs="?", default="build/release")
    parser.add_argument("--repetitions", type=int, default=5)
    args = parser.parse_args()
    bench = pathlib.Path(args.build) / "bench" / "bench_solver"

    points = np.array([[0, 0, 0], [1, 0, 0]])
    tiny = tessera.Model(points, [0, 1])
    tiny.set_constraints("distance", [[0, 1]])
    tiny_solver = tessera.Solver(tiny, tessera.colour(tiny), threads=1)
    cloth = tessera.scene("cloth:1024").model
    cloth_solver = tessera.Solver(cloth, tessera.colour(cloth, "stencil", locality=True),
                                  threads=1)

    rows = {name: [] for name in ("step C++", "step Python", "positions C++ copy",
                                  "positions Python copy", "scheduled_positions views")}
    for _ in range(args.repetitions):
        rows["step C++"].append(cpp(bench, "^solver/step_tiny/"))
        rows["step Python"].append(per_call(tiny_solver.step, 20000))
        rows["positions C++ copy"].append(cpp(bench, "^solver/positions/cloth1024/"))
        rows["positions Python copy"].append(per_call(lambda: cloth_solver.positions, 20))
        rows["scheduled_positions views"].append(
            per_call(lambda: cloth_solver.scheduled_positions, 20000))
    medians = {name: statistics.median(values) for name, values in rows.items()}
    for name, value in medians.items():
        print(f"{name:28} {value * 1e6:12.3f} us  (median of {args.repetitions})")
    print(f"step: Python / C++ = {medians['step Python'] / medians['step C++']:.2f}, "
          f"overhead {(medians['step Python'] - medians['step C++']) * 1e9:.0f} ns per call")
    print(f"positions 1024^2: Python copy / C++ copy = "
          f"{medians['positions Python copy'] / medians['positions C++ copy']:.2f}; "
          f"views {medians['scheduled_positions views'] * 1e6:.2f} us")


if __name__ == "__main__":
    main()
