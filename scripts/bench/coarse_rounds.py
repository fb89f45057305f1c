#!/usr/bin/python3
"""Rounds against the number of agents, with and without the coarse correction.

IRBCD on the generated 8000-pose grid (`tessera generate --kind grid3d --poses 8000 --robots 5
--seed 1`), N = 4, 9, 16, 25, 49 agents, chordal initialisation, in-process engine (the same
messages as over DDS): rounds to ||grad f|| <= 0.01, the ratio to the rounds at N = 4, and the
bytes a round exchanges (all messages, each recipient counted: pose blocks, statuses, the coarse
terms to the solver agent and its motions back; and the same divided by N, what one agent receives on
average), one-level
(`--coarse off`) beside two-level over each coarse space of `--spaces` (`--coarse on --coarse-space
blocks|smoothed`). Prints one table and writes docs/benchmarks/coarse_rounds.csv.

  scripts/bench/coarse_rounds.py [--agents 4,9,16,25,49] [--partition auto] [--every 1]
                                 [--spaces blocks,smoothed] [--aggregates 4] [--smoothing 1]
                                 [--max-rounds 2000] [--poses 8000] [--bin B] [--out-dir D]
"""
import argparse
import os
import statistics
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_common as bc  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    bc.add_common_args(ap)
    ap.add_argument("--agents", default="4,9,16,25,49")
    ap.add_argument("--partition", default="auto", help="partition preset (default auto, what solve uses)")
    ap.add_argument("--every", type=int, default=1, help="--coarse-every of the two-level runs")
    ap.add_argument("--spaces", default="blocks,smoothed", help="coarse spaces of the two-level runs")
    ap.add_argument("--aggregates", type=int, default=4, help="--coarse-aggregates of the smoothed runs")
    ap.add_argument("--smoothing", type=int, default=1, help="--coarse-smoothing of the smoothed runs")
    ap.add_argument("--max-rounds", type=int, default=2000)
    ap.add_argument("--poses", type=int, default=8000)
    ap.add_argument("--seed", type=int, default=1, help="shared seed (partitioner, selection)")
    args = ap.parse_args()
    ctx = bc.Ctx(args)
    path = os.path.join(ctx.work, f"grid3d_{args.poses}_r5_s1.g2o")
    if not os.path.exists(path):
        cmd = [ctx.bin, "generate", "--kind", "grid3d", "--poses", str(args.poses), "--robots", "5", "--seed", "1",
               "--out", path]
        ctx.log(cmd)
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    agents = [int(a) for a in args.agents.split(",")]
    rows, table = [], []
    base = {}
    for n in agents:
        for mode in ["off"] + args.spaces.split(","):
            bc.progress(f"IRBCD, grid {args.poses}, N = {n}, coarse {mode}")
            cmd = ["solve", path, "--algorithm", "irbcd", "--agents", str(n), "--partition", args.partition,
                   "--seed", str(args.seed), "--grad-tol", "0.01", "--max-rounds", str(args.max_rounds)]
            if mode == "off":
                cmd += ["--coarse", "off"]
            else:
                cmd += ["--coarse", "on", "--coarse-space", mode, "--coarse-every", str(args.every)]
            if mode == "smoothed":
                cmd += ["--coarse-aggregates", str(args.aggregates), "--coarse-smoothing", str(args.smoothing)]
            s, tr, _, wall = bc.run_tessera(ctx, cmd)
            r01 = bc.first_round(tr, 0.01)
            if n == agents[0]:
                base[mode] = r01
            per_round = [int(r["bytes"]) for r in tr if "bytes" in r and int(r["round"]) < s["rounds"]]
            row = {"agents": n, "coarse": mode, "cut_edges": s["cut_edges"], "colours": s.get("colours"),
                   "rounds_to_grad_0.01": r01,
                   "ratio_to_first_N": (r01 / base[mode]) if r01 and base.get(mode) else None,
                   "bytes_per_round_mean": statistics.mean(per_round) if per_round else None,
                   "bytes_per_round_max": max(per_round) if per_round else None,
                   "bytes_per_agent_round": statistics.mean(per_round) / n if per_round else None,
                   "cpu_ms_per_round": s.get("cpu_ms_per_round"), "stop": s["stop_reason"],
                   "final_grad_norm": s["grad_norm"], "cost": s["cost"]}
            rows.append(row)
            table.append([n, mode, s["cut_edges"], bc.fmt(s.get("colours")), bc.fmt(r01), bc.fmt(row["ratio_to_first_N"], "{:.2f}"),
                          bc.fmt(row["bytes_per_round_mean"], "{:.0f}"), bc.fmt(row["bytes_per_agent_round"], "{:.0f}"),
                          bc.fmt(row["cpu_ms_per_round"], "{:.1f}"), s["stop_reason"]])
    with open("/proc/loadavg") as f:
        load = f.read().split()[0]
    bc.print_table(f"IRBCD rounds against N, generated grid {args.poses}, {args.partition} partition "
                   f"(load {load})",
                   ["N", "coarse", "cut", "colours", "rounds to |g|<=0.01", f"x rounds at N={agents[0]}", "bytes/round",
                    "bytes/agent/round", "cpu ms/round", "stop"], table)
    bc.write_csv(os.path.join(ctx.out_dir, "coarse_rounds.csv"), rows)
    print("\ncommands:\n" + "\n".join(ctx.commands))


if __name__ == "__main__":
    main()
