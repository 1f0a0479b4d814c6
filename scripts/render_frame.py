#!/usr/bin/python3
"""Renders one .vtu frame written by `tessera run --out DIR` as a PNG with matplotlib.

    /usr/bin/python3 scripts/render_frame.py DIR/frame_00060.vtu picture.png [--family N]

Left: the surface (grey, lit by its normals); in a run with collisions, the particles held by a
contact in the frame's last substep as red dots (point data "contacts"). Right: the
constraints of one family (default 0, distance) drawn as lines in their colour, so the
colouring is seen on the deformed mesh.
Uses Debian's python3-matplotlib (scripts/setup --bench installs it); reads the ASCII .vtu
with the standard library's XML parser.
"""
import argparse
import xml.etree.ElementTree as ElementTree

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib import colormaps  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection  # noqa: E402


def read_vtu(path):
    piece = ElementTree.parse(path).getroot().find("UnstructuredGrid/Piece")
    arrays = {}
    for array in piece.iter("DataArray"):
        text = (array.text or "").split()
        kind = array.get("type")
        arrays[array.get("Name")] = [float(v) for v in text] if kind.startswith("Float") else [int(v) for v in text]
    points = arrays["Points"]
    points = [tuple(points[i:i + 3]) for i in range(0, len(points), 3)]
    cells, start = [], 0
    for end in arrays["offsets"]:
        cells.append(arrays["connectivity"][start:end])
        start = end
    return points, cells, arrays["types"], arrays.get("colour"), arrays.get("family"), arrays.get("contacts")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("vtu")
    parser.add_argument("png")
    parser.add_argument("--family", type=int, default=0, help="constraint family to draw (0 = distance)")
    parser.add_argument("--title", default="")
    arguments = parser.parse_args()

    points, cells, types, colours, families, contacts = read_vtu(arguments.vtu)
    # View: x right, the model's y up (matplotlib's z), z into the page.
    view = [(x, z, y) for x, y, z in points]
    triangles = [[view[v] for v in cell] for cell, t, f in zip(cells, types, families) if t == 5 and f < 0]
    lines = [([view[v] for v in cell], c) for cell, t, c, f in zip(cells, types, colours, families)
             if f == arguments.family and len(cell) >= 2]
    palette = colormaps["tab20"]
    count = max((c for _, c in lines), default=0) + 1

    figure = plt.figure(figsize=(10, 5), dpi=110)
    low = [min(p[k] for p in view) for k in range(3)]
    high = [max(p[k] for p in view) for k in range(3)]
    span = max(h - l for l, h in zip(low, high)) or 1.0
    for index in (1, 2):
        axes = figure.add_subplot(1, 2, index, projection="3d")
        if index == 1:
            shades = []
            for a, b, c in triangles:
                u = [b[k] - a[k] for k in range(3)]
                w = [c[k] - a[k] for k in range(3)]
                n = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]]
                length = sum(x * x for x in n) ** 0.5 or 1.0
                light = abs(n[0] * 0.4 + n[1] * -0.5 + n[2] * 0.77) / length
                shades.append((0.35 + 0.6 * light,) * 3)
            axes.add_collection3d(Poly3DCollection(triangles, facecolors=shades, edgecolors="none", linewidths=0, antialiased=False))
            title = "simulated surface"
            if contacts:
                touching = [p for p, n in zip(view, contacts) if n > 0]
                if touching:
                    xs, ys, zs = zip(*touching)
                    axes.scatter(xs, ys, zs, s=1.5, c="red", depthshade=False)
                title += f", {len(touching)} particles in contact (red)"
            axes.set_title(title)
        else:
            segments = [[cell[0], cell[-1]] for cell, _ in lines]
            axes.add_collection3d(Line3DCollection(
                segments, colors=[palette(c % 20) for _, c in lines], linewidths=1.2))
            axes.set_title(f"family {arguments.family} constraints by colour ({count} colours)")
        for k, setter in enumerate((axes.set_xlim, axes.set_ylim, axes.set_zlim)):
            centre = (low[k] + high[k]) / 2
            setter(centre - span / 2, centre + span / 2)
        axes.view_init(elev=12, azim=-65)
        axes.set_axis_off()
    if arguments.title:
        figure.suptitle(arguments.title)
    figure.tight_layout()
    figure.savefig(arguments.png)


if __name__ == "__main__":
    main()
