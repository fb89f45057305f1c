#!/usr/bin/python3
"""Experiment 5 -- number of robots (paper Fig. 5).

A generated 3D grid (stand-in for grid3D) with N = 4, 9, 16, 25 agents, highest partition, IRBCD,
chordal initialisation, in-process engine: rounds and solver wall time to grad norm 0.01, and the
convergence (grad norm against rounds) in one figure.

  scripts/bench/exp_robots.py [--quick] [--bin B] [--shared S] [--out-dir D]
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_common as bc  # noqa: E402

AGENTS = [4, 9, 16, 25]


def time_to(trace, tol):
    for r in trace:
        if r["grad_norm"] <= tol:
            return r.get("elapsed_s")
    return None


def run(ctx):
    res = bc.Result("5. Number of robots (paper Fig. 5)")
    max_rounds = 1000 if ctx.quick else 3000
    label = f"grid3d-{ctx.grid_poses()} (generated)"
    path = ctx.grid()
    fstar, fsrc = ctx.fstar(path)
    rows, table, traces = [], [], {}
    for n in AGENTS:
        bc.progress(f"number of robots: IRBCD on {label} with N = {n} (max {max_rounds} rounds)")
        s, tr, _, wall = bc.run_tessera(ctx, ["solve", path, "--algorithm", "irbcd", "--agents", str(n), "--partition",
                                              "highest", "--grad-tol", "0.01", "--max-rounds", str(max_rounds),
                                              "--reference-cost", repr(fstar)])
        traces[n] = tr
        row = {"graph": label, "agents": n, "cut_edges": s["cut_edges"], "rounds": s["rounds"],
               "stop": s["stop_reason"], "rounds_to_grad_0.01": bc.first_round(tr, 0.01),
               "solver_s_to_grad_0.01": time_to(tr, 0.01), "solve_s": s["solve_s"], "process_wall_s": wall,
               "ms_per_round": s["ms_per_round"], "cpu_ms_per_round": s.get("cpu_ms_per_round"),
               "final_grad_norm": s["grad_norm"], "rel_gap": s["rel_gap"], "f_star": fstar, "f_star_source": fsrc}
        rows.append(row)
        table.append([n, s["cut_edges"], bc.fmt(row["rounds_to_grad_0.01"]),
                      bc.fmt(row["solver_s_to_grad_0.01"], "{:.2f}"), f"{s['solve_s']:.2f}", f"{wall:.2f}",
                      f"{s['ms_per_round']:.2f}", f"{s['grad_norm']:.3g}", f"{s['rel_gap']:.2e}"])
    md = bc.print_table(f"IRBCD on {label}, highest partition", ["N", "cut", "rounds to |g|<=0.01",
                                                                "solver s to |g|<=0.01", "solve s",
                                                                "process wall s", "ms/round", "final |grad|",
                                                                "rel gap"], table)
    res.add(f"IRBCD, `highest` partition, chordal initialisation, in-process engine, stop at grad norm 0.01 or "
            f"{max_rounds} rounds. Solver seconds from the solver's clock (trace `elapsed_s`); process wall time "
            f"includes loading, partitioning and the chordal initialisation. f* from the centralized solver in "
            f"this run ({fsrc}). {bc.GRID_NOTE} (P = {ctx.grid_poses()}).\n\n" + md)
    res.add_csv(ctx, "exp5_robots.csv", rows)
    res.images.append(plot(ctx, label, traces, rows, fstar))
    return res


def plot(ctx, label, traces, rows, fstar):
    plt = bc.pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(18, 4.5))
    for n in AGENTS:
        tr = traces[n]
        axes[0].plot([r["round"] for r in tr], [r["grad_norm"] for r in tr], label=f"N = {n}")
        xs, ys = bc.gap_series(tr, fstar)
        axes[1].plot(xs, ys, label=f"N = {n}")
    for ax, yl in ((axes[0], "gradient norm (cost units, log)"), (axes[1], "f - f* (cost units, log)")):
        bc.style_log_axes(ax, "round", f"IRBCD on {label}", yl)
    ax = axes[2]
    ns = [r["agents"] for r in rows]
    ax.plot(ns, [r["rounds_to_grad_0.01"] or r["rounds"] for r in rows], "o-", color="C0",
            label="rounds to |grad| <= 0.01 (or the cap)")
    ax.set_xlabel("number of agents N")
    ax.set_ylabel("rounds", color="C0")
    ax2 = ax.twinx()
    ax2.plot(ns, [r["solver_s_to_grad_0.01"] or r["solve_s"] for r in rows], "s--", color="C1",
             label="solver wall time (s)")
    ax2.set_ylabel("solver wall time to |grad| <= 0.01 (s)", color="C1")
    ax.set_title("cost of convergence against N")
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = ax2.get_legend_handles_labels()
    ax.legend(h1 + h2, l1 + l2, fontsize=8, loc="upper left")
    return bc.save_figure(ctx, fig, "exp5_robots.png", dpi=100)


def main():
    bc.experiment_main(__doc__, run)


if __name__ == "__main__":
    main()
