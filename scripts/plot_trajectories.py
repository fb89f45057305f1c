#!/usr/bin/env python3
"""Renders the figure data written by `tessera plot` / `tessera launch --plot` into a PNG.

usage: plot_trajectories.py FIGURE.json OUT.png

The trajectories are drawn from above (x-y), and for 3D graphs also in a 3D view: one colour
per robot (or per block), loop closures as thin lines -- intra-robot grey, inter-robot
black, cut by the partition gold, rejected outliers red -- and the ground truth faint grey.
"""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402

EDGE_STYLE = {
    "intra": dict(color="0.6", lw=0.4, alpha=0.5, label="loop closure (intra-robot)"),
    "inter": dict(color="black", lw=0.6, alpha=0.7, label="inter-robot closure"),
    "cut": dict(color="goldenrod", lw=1.0, alpha=0.9, label="cut by the partition"),
    "rejected": dict(color="red", lw=0.9, alpha=0.9, label="rejected outlier"),
}


# tab10 without red (rejected outliers), grey (truth) and black-like tones (closures).
PALETTE = ["tab:blue", "tab:green", "tab:orange", "tab:purple", "tab:brown", "tab:pink",
           "tab:olive", "tab:cyan", "navy", "lime", "teal", "coral"]


def colours(n):
    return [PALETTE[k % len(PALETTE)] for k in range(max(n, 1))]


def draw(ax, fig, three_d):
    cols = colours(len(fig["names"]))
    dims = 3 if three_d else 2
    for path in fig["truth"]:
        pts = path["points"]
        if pts:
            xs = list(zip(*pts))
            ax.plot(*xs[:dims], color="0.75", lw=2.5, alpha=0.5, zorder=1,
                    label="ground truth" if path is fig["truth"][0] else None)
    for kind, style in EDGE_STYLE.items():
        segs = [(e["a"][0][:dims], e["b"][0][:dims]) for e in fig["edges"] if e["kind"] == kind]
        if not segs:
            continue
        if three_d:
            first = True
            for a, b in segs:
                ax.plot(*zip(a, b), color=style["color"], lw=style["lw"], alpha=style["alpha"],
                        label=style["label"] if first else None)
                first = False
        else:
            ax.add_collection(LineCollection(segs, colors=style["color"], linewidths=style["lw"],
                                             alpha=style["alpha"], label=style["label"], zorder=2))
    labelled = set()
    for path in fig["paths"]:
        pts, groups = path["points"], path["groups"]
        if not pts:
            continue
        xs = list(zip(*pts))
        if fig["color_by"] == "robot":
            g = groups[0]
            ax.plot(*xs[:dims], color=cols[g], lw=1.0, zorder=3,
                    label=fig["names"][g] if g not in labelled else None)
            labelled.add(g)
        else:
            ax.plot(*xs[:dims], color="0.4", lw=0.5, zorder=3)
            for g in sorted(set(groups)):
                sel = [p for p, q in zip(pts, groups) if q == g]
                ax.scatter(*list(zip(*sel))[:dims], s=3, color=cols[g], zorder=4,
                           label=fig["names"][g] if g not in labelled else None)
                labelled.add(g)


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    with open(sys.argv[1]) as f:
        fig = json.load(f)
    three_d = fig["d"] == 3
    figure = plt.figure(figsize=(14, 6.5) if three_d else (8, 7.5))
    ax = figure.add_subplot(1, 2, 1) if three_d else figure.add_subplot(1, 1, 1)
    draw(ax, fig, False)
    ax.set_aspect("equal", adjustable="datalim")
    ax.autoscale_view()
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title("from above")
    ax.legend(loc="best", fontsize=7, markerscale=3)
    if three_d:
        ax3 = figure.add_subplot(1, 2, 2, projection="3d")
        draw(ax3, fig, True)
        ax3.set_xlabel("x")
        ax3.set_ylabel("y")
        ax3.set_zlabel("z")
        ax3.set_title("3D")
    figure.suptitle(fig["title"])
    figure.tight_layout()
    figure.savefig(sys.argv[2], dpi=110)


if __name__ == "__main__":
    main()
