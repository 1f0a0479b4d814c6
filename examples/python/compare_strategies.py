"""Compare Tessera's colouring strategies from Python on three scenes.

Each scene is coloured with every strategy (tessera.strategies()), then simulated for a fixed
number of frames with the same substeps and iterations (coloured Gauss-Seidel), so the
strategies differ only in how they order the constraints. Prints one line per scene and
strategy and plots, against wall time, the colour count and balance (against the colouring's
time) and the residual left (against the solve's time).

    PYTHONPATH=build/release/python python3 examples/python/compare_strategies.py \
        --out docs/images/compare_strategies.png
    ... --quick --no-plot       small scenes, no matplotlib needed (run by the tests)
"""
import argparse
import pathlib
import time

import tessera

HERE = pathlib.Path(__file__).resolve().parent
SCENES = {  # name: (full spec, quick spec)
    "cloth 128²": ("cloth:128", "cloth:12"),
    "FEM bar 8×8×32": ("bar:8x8x32", "bar:2x2x4"),
    "curtain (32², soft bending)": (str(HERE.parent / "scenes" / "curtain.json"),) * 2,
}


def run(spec, strategy, frames, threads):
    """Colours and simulates one scene; returns the measurements."""
    scene = tessera.scene(spec)
    colouring = tessera.colour(scene.model, strategy, locality=True, threads=threads or None)
    settings = scene.solver_settings() | {"threads": threads, "report_residuals": False}
    solver = tessera.Solver(scene.model, colouring, **settings)
    start = time.perf_counter()
    solver.step(frames)
    solve_seconds = time.perf_counter() - start
    stats = colouring.statistics
    return {"colours": stats["colours"], "lower_bound": stats["lower_bound"],
            "balance": stats["balance"], "colour_seconds": stats["seconds"],
            "solve_seconds": solve_seconds, "residual": solver.residual()["rms"]}


def plot(results, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    strategies = list(tessera.strategies())
    # One marker per strategy, cycling if a user registered more than there are markers.
    shapes = "osD^vP*Xhp<>"
    markers = {name: shapes[k % len(shapes)] for k, name in enumerate(strategies)}
    fig, axes = plt.subplots(len(results), 3, figsize=(13, 3.4 * len(results)), squeeze=False)
    for row, (scene, rows) in enumerate(results.items()):
        for name, r in rows.items():
            style = {"marker": markers[name], "linestyle": "none", "markersize": 8, "label": name}
            axes[row][0].plot(r["colour_seconds"], r["colours"], **style)
            axes[row][1].plot(r["colour_seconds"], r["balance"], **style)
            axes[row][2].plot(r["solve_seconds"], r["residual"], **style)
        bound = next(iter(rows.values()))["lower_bound"]
        axes[row][0].axhline(bound, color="grey", linewidth=0.8, linestyle="--")
        axes[row][0].set_ylabel(f"{scene}\ncolours (dashed: lower bound)")
        axes[row][1].set_ylabel("balance (largest / mean colour)")
        axes[row][2].set_ylabel("residual RMS after the run")
        for column in range(3):
            if column < 2:  # colouring times span decades; solve times a narrow range
                axes[row][column].set_xscale("log")
            axes[row][column].grid(True, alpha=0.3)
        axes[row][0].set_xlabel("colouring wall time [s]")
        axes[row][1].set_xlabel("colouring wall time [s]")
        axes[row][2].set_xlabel("solve wall time [s]")
    axes[0][2].legend(fontsize=8, ncol=2)
    fig.suptitle("Tessera colouring strategies: colours, balance and residual against wall time "
                 "(each run: the same frames, substeps and iterations, gs mode)")
    fig.tight_layout()
    fig.savefig(out, dpi=90)
    print(f"wrote {out}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="compare_strategies.png", help="the PNG to write")
    parser.add_argument("--frames", type=int, default=20, help="frames simulated per run")
    parser.add_argument("--threads", type=int, default=0, help="0: every hardware thread")
    parser.add_argument("--quick", action="store_true", help="small scenes, 2 frames")
    parser.add_argument("--no-plot", action="store_true", help="print the table only")
    args = parser.parse_args()
    frames = 2 if args.quick else args.frames

    results = {}
    print(f"{'scene':30} {'strategy':16} {'colours':>7} {'bound':>5} {'balance':>7} "
          f"{'colour s':>9} {'solve s':>8} {'residual':>10}")
    for name, specs in SCENES.items():
        spec = specs[1] if args.quick else specs[0]
        scene = name if not args.quick else pathlib.Path(spec).name  # label what was run
        results[scene] = {}
        for strategy in tessera.strategies():
            r = run(spec, strategy, frames, args.threads)
            results[scene][strategy] = r
            print(f"{scene:30} {strategy:16} {r['colours']:7} {r['lower_bound']:5} "
                  f"{r['balance']:7.3f} {r['colour_seconds']:9.4f} {r['solve_seconds']:8.4f} "
                  f"{r['residual']:10.3e}")
    if not args.no_plot:
        plot(results, args.out)


if __name__ == "__main__":
    main()
