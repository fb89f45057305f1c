#!/usr/bin/python3
"""Experiment 2 -- effect of the partition on convergence (paper Fig. 3).

RBCD (greedy selection, chordal initialisation, N = 5, in-process engine) on parking-garage and on
a generated 3D grid (stand-in for grid3D, see the output) with the sequential partition and each
preset: grad norm and f - f* against rounds, one row of plots per graph, one figure.

  scripts/bench/exp_partition_convergence.py [--quick] [--bin B] [--shared S] [--out-dir D]
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_common as bc  # noqa: E402

PRESETS = ["sequential", "fast", "eco", "strong", "highest"]


def run(ctx):
    res = bc.Result("2. Partition effect on convergence (paper Fig. 3)")
    max_rounds = 300 if ctx.quick else 2000
    presets = ["sequential", "fast", "highest"] if ctx.quick else PRESETS
    graphs = [("parking-garage", ctx.dataset("parking-garage"), "parking-garage"),
              (f"grid3d-{ctx.grid_poses()} (generated)", ctx.grid(), None)]
    rows, traces, table = [], {}, []
    for label, path, name in graphs:
        fstar, fsrc = ctx.fstar(name if name else path)
        for p in presets:
            bc.progress(f"partition effect: RBCD on {label}, {p} partition (max {max_rounds} rounds)")
            s, tr, _, _ = bc.run_tessera(ctx, ["solve", path, "--algorithm", "rbcd", "--agents", "5", "--partition",
                                               p, "--grad-tol", "0.01", "--max-rounds", str(max_rounds),
                                               "--reference-cost", repr(fstar)])
            traces[(label, p)] = tr
            row = {"graph": label, "partition": p, "cut_edges": s["cut_edges"], "rounds": s["rounds"],
                   "stop": s["stop_reason"], "rounds_to_grad_0.1": bc.first_round(tr, 0.1),
                   "rounds_to_grad_0.01": bc.first_round(tr, 0.01), "final_grad_norm": s["grad_norm"],
                   "final_rel_gap": s["rel_gap"], "f_star": fstar, "f_star_source": fsrc,
                   "ms_per_round": s["ms_per_round"]}
            rows.append(row)
            table.append([label, p, s["cut_edges"], bc.fmt(row["rounds_to_grad_0.1"]),
                          bc.fmt(row["rounds_to_grad_0.01"]), s["rounds"], f"{s['grad_norm']:.3g}",
                          f"{s['rel_gap']:.2e}", f"{s['ms_per_round']:.2f}"])
    md = bc.print_table(f"RBCD, N = 5, chordal init, greedy selection, cap {max_rounds} rounds",
                        ["graph", "partition", "cut", "rounds to |g|<=0.1", "rounds to |g|<=0.01", "rounds",
                         "final |grad|", "rel gap", "ms/round"], table)
    res.add(f"RBCD, N = 5 agents (in-process engine), chordal initialisation, greedy block selection, stop at "
            f"grad norm 0.01 or {max_rounds} rounds. f* of parking-garage from `reference/optima.csv` "
            f"(quaternion-normalised row); f* of the generated grid from the centralized certifiable solver in "
            f"this run. {bc.GRID_NOTE} (P = {ctx.grid_poses()}).\n\n" + md)
    res.add_csv(ctx, "exp2_partition_convergence.csv", rows)
    res.images.append(plot(ctx, graphs, presets, traces, rows))
    return res


def plot(ctx, graphs, presets, traces, rows):
    plt = bc.pyplot()
    fig, axes = plt.subplots(len(graphs), 2, figsize=(12, 4.2 * len(graphs)), squeeze=False)
    for gi, (label, _, _) in enumerate(graphs):
        fstar = next(r["f_star"] for r in rows if r["graph"] == label)
        for p in presets:
            tr = traces[(label, p)]
            cut = next(r["cut_edges"] for r in rows if r["graph"] == label and r["partition"] == p)
            axes[gi][0].plot([r["round"] for r in tr], [r["grad_norm"] for r in tr], label=f"{p} (cut {cut})")
            xs, ys = bc.gap_series(tr, fstar)
            axes[gi][1].plot(xs, ys, label=f"{p} (cut {cut})")
        axes[gi][0].set_ylabel("Riemannian gradient norm (cost units, log)")
        axes[gi][1].set_ylabel("f - f* (cost units, log)")
        for ax in axes[gi]:
            bc.style_log_axes(ax, "round (one block update each)", f"RBCD on {label}, N = 5")
    return bc.save_figure(ctx, fig, "exp2_partition_convergence.png", dpi=100)


def main():
    bc.experiment_main(__doc__, run)


if __name__ == "__main__":
    main()
