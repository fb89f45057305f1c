#!/usr/bin/env python3
"""IRBCD rounds to a gradient norm of 0.01 against the partition: cut objective vs rounds objective.

For torus3D and the generated 8000-pose grid (`tessera generate --kind grid3d --poses 8000
--robots 5 --seed 1`), N = 5 agents, presets eco and highest, seeds 1-5, runs

  tessera solve G --algorithm irbcd --agents 5 --partition P --seed S
                  --partition-objective cut|rounds --json F

and prints per run the cut, the block adjacency (quotient) graph's adjacent pairs and colours
(chromatic number, the number of colour classes IRBCD cycles through) and the rounds. The model
rounds ~ r x colours (r: rounds per sweep through the colour classes, one per graph) is fitted
(least squares through the origin) on the `cut` runs only and then predicts every run; the table
shows prediction and error, the summary the mean absolute error per objective (the `rounds` runs
are out of sample). Rounds are counts: they do not depend on the machine's load.
Writes docs/benchmarks/partition_rounds.csv and docs/benchmarks/partition_rounds.md.

  scripts/bench/partition_rounds.py [--bin build/bin/tessera] [--shared ../shared]
      [--seeds 5] [--objectives cut,rounds] [--presets eco,highest] [--work DIR] [--csv FILE]

--csv FILE re-reads the runs of an earlier partition_rounds.csv instead of running them.
"""
import argparse
import os
import statistics
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import bench_common as bc  # noqa: E402


def fit_proportional(xs, ys):
    """Least-squares r of y = r x."""
    return sum(x * y for x, y in zip(xs, ys)) / sum(x * x for x in xs)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    bc.add_common_args(ap)
    ap.add_argument("--seeds", type=int, default=5, help="partition seeds 1..S (default 5)")
    ap.add_argument("--objectives", default="cut,rounds", help="comma-separated (default cut,rounds)")
    ap.add_argument("--presets", default="eco,highest", help="partition presets (default eco,highest)")
    ap.add_argument("--agents", type=int, default=5, help="N (default 5)")
    ap.add_argument("--csv", default="", help="analyse the runs of this CSV instead of running them")
    ap.add_argument("--note", default="", help="a line for the markdown file (e.g. the load of a --csv run)")
    args = ap.parse_args()
    ctx = bc.Ctx(args)
    labels = ["torus3D", "grid3d-8000 (generated)"]
    objectives = args.objectives.split(",")
    presets = args.presets.split(",")
    rows = []
    if args.csv:
        import csv
        with open(args.csv) as f:
            for r in csv.DictReader(f):
                rows.append({k: (int(v) if k in ("seed", "cut_edges", "adjacent_block_pairs", "colours", "rounds")
                                 else v) for k, v in r.items() if k not in ("predicted_rounds", "prediction_error")})
    graphs = [] if args.csv else [(labels[0], ctx.dataset("torus3D")), (labels[1], ctx.generate(8000))]
    for label, path in graphs:
        for preset in presets:
            for obj in objectives:
                for seed in range(1, args.seeds + 1):
                    bc.progress(f"{label}: IRBCD, {preset} partition, objective {obj}, seed {seed}")
                    s, _, _, _ = bc.run_tessera(ctx, ["solve", path, "--algorithm", "irbcd", "--agents",
                                                      str(args.agents), "--partition", preset, "--seed",
                                                      str(seed), "--partition-objective", obj], trace=False)
                    rows.append({"graph": label, "preset": preset, "objective": obj, "seed": seed,
                                 "cut_edges": s["cut_edges"],
                                 "adjacent_block_pairs": s["adjacent_block_pairs"], "colours": s["colours"],
                                 "rounds": s["rounds"], "stop": s["stop_reason"],
                                 "partition_ms": round(s["partition_ms"], 1),
                                 "partition_cpu_ms": round(s["partition_cpu_ms"], 1)})
    fit_rows = [r for r in rows if r["objective"] == "cut"] or rows
    models = {}
    for label in labels:
        sub = [r for r in fit_rows if r["graph"] == label]
        models[label] = fit_proportional([r["colours"] for r in sub], [r["rounds"] for r in sub])
    table = []
    for r in rows:
        r["predicted_rounds"] = round(models[r["graph"]] * r["colours"], 1)
        r["prediction_error"] = round(r["predicted_rounds"] - r["rounds"], 1)
        table.append([r["graph"], r["preset"], r["objective"], r["seed"], r["cut_edges"],
                      r["adjacent_block_pairs"], r["colours"], r["rounds"], r["predicted_rounds"],
                      r["prediction_error"], r["partition_ms"], r.get("partition_cpu_ms") or "-"])
    load = open("/proc/loadavg").read().split()[:3]
    md = [bc.print_table(f"IRBCD rounds to |grad| <= 0.01, N = {args.agents}",
                         ["graph", "preset", "objective", "seed", "cut", "adjacent pairs", "colours", "rounds",
                          "model", "model - rounds", "partition ms", "partition CPU ms"], table)]
    summary = []
    for label in labels:
        for preset in sorted({r["preset"] for r in rows}):
            for obj in objectives:
                sub = [r for r in rows if r["graph"] == label and r["objective"] == obj and r["preset"] == preset]
                if not sub:
                    continue
                summary.append([label, preset, obj, " ".join(str(r["rounds"]) for r in sub),
                                f"{max(r['rounds'] for r in sub)}", f"{statistics.fmean(r['cut_edges'] for r in sub):.1f}",
                                " ".join(str(r["colours"]) for r in sub), f"{models[label]:.1f} x colours",
                                f"{statistics.fmean(abs(r['prediction_error']) for r in sub):.1f}"])
    md.append(bc.print_table("Summary over seeds 1-%d" % args.seeds,
                             ["graph", "preset", "objective", "rounds by seed", "max", "mean cut", "colours by seed",
                              "model (fitted on cut runs)", "mean |model - rounds|"], summary))
    print(f"\nload while this ran: {' '.join(load)} (/proc/loadavg); rounds are counts, partition ms is "
          f"wall time (inflated by the load), partition CPU ms process CPU time (- = not recorded).")
    bc.write_csv(os.path.join(ctx.out_dir, "partition_rounds.csv"), rows)
    with open(os.path.join(ctx.out_dir, "partition_rounds.md"), "w") as f:
        run = ("tessera solve G --algorithm irbcd --agents N --partition P --seed S "
               "--partition-objective O --json F")
        cmds = ctx.commands if ctx.commands else [f"{run}   (every row; read back with --csv)"]
        f.write("# IRBCD rounds against the partition\n\nWritten by `scripts/bench/partition_rounds.py`"
                f" (load {' '.join(load)} when it finished; rounds are counts, partition ms is wall time and"
                " grows with the load). " + args.note + "\n\n" + "\n\n".join(md) +
                "\n\nCommands:\n\n" + "\n".join(f"    {c}" for c in cmds) + "\n")
    print(f"wrote {os.path.relpath(os.path.join(ctx.out_dir, 'partition_rounds.md'), bc.ROOT)}")


if __name__ == "__main__":
    main()
