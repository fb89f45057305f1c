#!/usr/bin/python3
"""Experiment 6 -- scale: generated 3D grids of 10k, 100k and 1M poses, N = 5 and 25.

For each size and N: partition time (`tessera partition --json`, same preset as the solve), then
IRBCD from the file's VERTEX poses (odometry; the centralized chordal initialisation would dominate
the time at this scale and is not what a distributed system runs) with a round cap (in-process engine: all agents in one process): rounds, solver wall time,
process wall time (load + partition + set-up + solve), and peak memory per agent
= the process's peak RSS / N (an upper bound of one agent's share; the in-process engine also
holds the whole graph once). `--quick` runs 2k and 10k only.

  scripts/bench/exp_scale.py [--quick] [--bin B] [--shared S] [--out-dir D] [--preset P]
"""
import argparse
import json
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_common as bc  # noqa: E402


def plan(quick):
    """(poses, round cap) per size; the caps keep the full run within its 30 minute budget."""
    if quick:
        return [(2000, 100), (10000, 100)]
    return [(10000, 500), (100000, 50), (1000000, 5)]


def run(ctx, preset="fast", mem_limit_gb=8):
    res = bc.Result("6. Scale")
    rows, table = [], []
    for poses, cap in plan(ctx.quick):
        path = ctx.generate(poses)
        for n in (5, 25):
            bc.progress(f"scale: {poses} poses, N = {n}: partition ({preset})")
            cmd = [ctx.bin, "partition", path, "--parts", str(n), "--preset", preset, "--json", "-"]
            ctx.log(cmd)
            t0 = time.monotonic()
            p = subprocess.run(cmd, capture_output=True, text=True, check=True)
            part = json.loads(p.stdout)
            part_wall = time.monotonic() - t0
            bc.progress(f"scale: {poses} poses, N = {n}: IRBCD, cap {cap} rounds")
            try:
                s, tr, rss_mb, wall = bc.run_tessera(ctx, ["solve", path, "--algorithm", "irbcd", "--agents", str(n),
                                                           "--partition", preset, "--grad-tol", "0.01", "--init",
                                                           "file", "--max-rounds", str(cap)],
                                                     mem_limit_mb=mem_limit_gb * 1024)
            except bc.OverLimit as e:
                bc.progress(f"  {e}")
                rows.append({"poses": poses, "agents": n, "preset": preset, "cut_edges": part["cut_edges"],
                             "partition_ms": part["time_ms"], "partition_process_s": part_wall, "round_cap": cap,
                             "stop": str(e)})
                table.append([poses, "-", n, part["cut_edges"], f"{part['time_ms']:.0f}", "-", str(e)] + ["-"] * 7)
                continue
            row = {"poses": poses, "edges": s["edges"], "agents": n, "preset": preset, "cut_edges": part["cut_edges"],
                   "partition_ms": part["time_ms"], "partition_process_s": part_wall, "round_cap": cap,
                   "rounds": s["rounds"], "stop": s["stop_reason"], "final_grad_norm": s["grad_norm"],
                   "initial_grad_norm": tr[0]["grad_norm"] if tr else None, "solve_s": s["solve_s"],
                   "ms_per_round": s["ms_per_round"], "cpu_ms_per_round": s.get("cpu_ms_per_round"),
                   "process_wall_s": wall, "peak_rss_mb": rss_mb, "peak_rss_mb_per_agent": rss_mb / n}
            rows.append(row)
            table.append([poses, s["edges"], n, part["cut_edges"], f"{part['time_ms']:.0f}", s["rounds"],
                          s["stop_reason"], f"{row['initial_grad_norm']:.3g}" if tr else "-",
                          f"{s['grad_norm']:.3g}", f"{s['ms_per_round']:.1f}", f"{s['solve_s']:.1f}",
                          f"{wall:.1f}", f"{rss_mb:.0f}", f"{rss_mb / n:.1f}"])
    md = bc.print_table("Scale (generated 3D grids, IRBCD, in-process engine)",
                        ["poses", "edges", "N", "cut", "partition ms", "rounds", "stop", "initial |grad|",
                         "final |grad|", "ms/round", "solve s", "process wall s", "peak RSS MB",
                         "peak MB per agent"], table)
    res.add(f"Generated 3D grids (`tessera generate --kind grid3d --poses P --robots 5`), `{preset}` partition, "
            f"IRBCD initialised from the file's VERTEX poses (odometry: the centralized chordal initialisation would "
            f"dominate at this scale and is not what a distributed system runs), with a round cap per size ({', '.join(f'{p}: {c}' for p, c in plan(ctx.quick))}) so the run fits "
            f"its time budget: the rounds column shows the cap, not convergence, where stop = max_rounds. "
            f"In-process engine (all agents in one process): peak MB per agent = the process's peak RSS / N, "
            f"an upper bound of one agent's share; a run is stopped (and said so in the stop column) when its peak RSS "
            f"passes {mem_limit_gb} GB, as the machine is shared. Process wall time includes loading, partitioning and setting up "
            f"the agents." + (" `--quick`: 2k and 10k poses only." if ctx.quick else "") + "\n\n" + md)
    res.add_csv(ctx, "exp6_scale.csv", rows)
    res.images.append(plot(ctx, rows))
    return res


def plot(ctx, rows):
    plt = bc.pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(18, 4.5))
    for n, marker in ((5, "o-"), (25, "s--")):
        rs = [r for r in rows if r["agents"] == n and "solve_s" in r]
        axes[0].plot([r["poses"] for r in rows if r["agents"] == n], [r["partition_ms"] for r in rows
                                                                       if r["agents"] == n], marker,
                     label=f"partition, N = {n}")
        xs = [r["poses"] for r in rs]
        axes[1].plot(xs, [r["ms_per_round"] for r in rs], marker, label=f"solver ms per round, N = {n}")
        axes[1].plot(xs, [1000 * r["process_wall_s"] / max(1, r["rounds"]) for r in rs], marker, alpha=0.5,
                     label=f"process wall ms / rounds, N = {n}")
        axes[2].plot(xs, [r["peak_rss_mb_per_agent"] for r in rs], marker, label=f"peak RSS / N, N = {n}")
    labels = [("partition time (ms, log)", "partitioning time"), ("time (ms, log)", "time per round"),
              ("memory (MB, log)", "peak memory per agent")]
    for ax, (yl, title) in zip(axes, labels):
        ax.set_xscale("log")
        bc.style_log_axes(ax, "poses (log)", title, yl, grid="both")
    return bc.save_figure(ctx, fig, "exp6_scale.png", dpi=100)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    bc.add_common_args(ap)
    ap.add_argument("--preset", default="fast")
    ap.add_argument("--mem-limit-gb", type=float, default=8, help="stop a solve whose peak RSS passes this")
    a = ap.parse_args()
    run(bc.Ctx(a), a.preset, a.mem_limit_gb)


if __name__ == "__main__":
    main()
