#!/usr/bin/env python3
"""Online runs (docs/online.md): a multi-robot graph is replayed as its robots' front ends would
publish it while one agent per robot solves in one process (`tessera solve GRAPH --online`).

Per run: median and 95th percentile latency over the batches (publication of a batch to the
end of the step that absorbed it, when the gradient is back under the tolerance; with
--real-time the steps' wall time is stream time), the relative gap to the optimum of the graph received so far at
sampled checkpoints (centralized solver, offline) and how soon after a checkpoint's data the
estimate came within --gap-bound of that optimum (the issue's latency target; median and 95th
percentile over the checkpoints), rounds and bytes per second of stream,
the CPU time of the online run against re-solving from scratch after every loop closure (the
issue's baseline: same agents and blocks, on the graph published up to and with each closure, a
sample of them re-solved and scaled), and the final cost against the batch optimum f*
(centralized solver on the whole graph) with the certificate.

Writes docs/benchmarks/online.csv, online.png and online.md. The default sizes are small: the machine is
shared; --full runs the issue's sizes (city10000 / 5 robots, a 50,000-pose grid / 10 robots,
sphere2500).
"""
import argparse
import json
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_common as bc  # noqa: E402


def cases(args, work, tessera):
    shared = os.path.join(args.shared, "datasets")
    if args.full:
        city, sphere = os.path.join(shared, "city10000.g2o"), os.path.join(shared, "sphere2500.g2o")
        grid = os.path.join(work, "grid50000.g2o")
        if not args.cases or "grid3d-50000" in args.cases.split(","):
            subprocess.run([tessera, "generate", "--kind", "grid3d", "--poses", "50000", "--robots", "10",
                            "--out", grid], check=True, stdout=subprocess.DEVNULL)
        # Re-solving from scratch after every closure step of the larger graphs would take hours:
        # those baselines re-solve at every K-th such step and scale (--baseline-every).
        # With steps shorter than a real-time step's (tick, or a fixed period) there are many more
        # closure steps: sample more sparsely.
        every = (1, 10, 40) if args.steps == "real-time" else (5, 40, 200)
        # The grid's re-solves are of graphs up to 50,000 poses: at most --grid-baseline-samples.
        grid_samples = min(args.baseline_samples, args.grid_baseline_samples)
        out = [("sphere2500", sphere, 5, "sphere2500", every[0], args.baseline_samples),
               ("city10000", city, 5, "city10000", every[1], args.baseline_samples),
               ("grid3d-50000", grid, 10, grid, every[2], grid_samples)]
        out = [c for c in out if not args.cases or c[0] in args.cases.split(",")]
        # The 20,000-pose grid over 10 robots (pairs of robots meet from 4,650 poses, chains from
        # 8,960): where the steps' coarse correction is measured (docs/online.md). Only by name.
        if "grid3d-20000" in args.cases.split(","):
            grid20 = os.path.join(work, "grid20000.g2o")
            subprocess.run([tessera, "generate", "--kind", "grid3d", "--poses", "20000", "--robots", "10",
                            "--seed", "1", "--out", grid20], check=True, stdout=subprocess.DEVNULL)
            out.append(("grid3d-20000", grid20, 10, grid20, every[2], grid_samples))
        return out
    out = []
    for kind, poses, robots in (("city", args.poses, 5), ("grid3d", args.poses, 5), ("sphere", args.poses, 5)):
        path = os.path.join(work, f"{kind}{poses}.g2o")
        subprocess.run([tessera, "generate", "--kind", kind, "--poses", str(poses), "--robots", str(robots),
                        "--seed", "1", "--out", path], check=True, stdout=subprocess.DEVNULL)
        out.append((f"{kind}-{poses} (generated)", path, robots, path, 1, args.baseline_samples))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    bc.add_common_args(ap)
    ap.add_argument("--poses", type=int, default=300, help="poses of each generated graph (default 300)")
    ap.add_argument("--rate", type=float, default=10.0, help="poses per second per robot (default 10)")
    ap.add_argument("--speedup", type=float, default=10.0, help="replay speedup (default 10)")
    ap.add_argument("--grad-tol", type=float, default=1e-3, help="agents' gradient tolerance (default 1e-3)")
    ap.add_argument("--checkpoints", type=int, default=5, help="checkpoints per run (default 5)")
    ap.add_argument("--gap-bound", type=float, default=1e-3,
                    help="the checkpoints' relative gap bound for the gap latency (default 1e-3)")
    ap.add_argument("--full", action="store_true", help="the issue's sizes (long on a shared machine)")
    ap.add_argument("--steps", default="real-time",
                    help="real-time (a step absorbs what was published while the last one ran: depends on the "
                         "load), tick (one step per publication time: load-free, re-solving after every tick that "
                         "brought a loop closure), or a number S (a step every S seconds of stream time)")
    ap.add_argument("--no-baseline", action="store_true", help="skip the re-solving baseline")
    ap.add_argument("--baseline-per", default="publication", choices=("publication", "closure", "step"),
                    help="the baseline re-solves from scratch after every loop closure: once per batch a "
                         "front end published with closures in it (default; closures that arrive together "
                         "share a re-solve), once per closure measurement, or once per step that brought one")
    ap.add_argument("--baseline-samples", type=int, default=40,
                    help="re-solve about this many of them, spread evenly, and scale the CPU time by "
                         "(counted / re-solved); 0 = all (or --full's fixed strides) (default 40)")
    ap.add_argument("--grid-baseline-samples", type=int, default=6,
                    help="with --full: at most this many re-solves of the 50,000-pose grid (default 6)")
    ap.add_argument("--baseline-solver", default="newton", choices=("newton", "rounds"),
                    help="the re-solves' solver: the online steps' Newton steps from scratch (default: "
                         "cheaper than the rounds on the generated graphs) or the batch solver's rounds")
    ap.add_argument("--baseline-init", default="chordal", choices=("chordal", "guesses"),
                    help="the re-solves' start: chordal initialization (default; the front ends' guesses "
                         "while the graph is not connected) or the front ends' guesses")
    ap.add_argument("--no-certify", action="store_true", help="skip the final certificate")
    ap.add_argument("--cases", default="", help="with --full: comma list of sphere2500,city10000,grid3d-50000 "
                    "(and grid3d-20000, only when named)")
    ap.add_argument("--dds", action="store_true",
                    help="also run each case over DDS (tessera launch --online: one agent process per robot)")
    ap.add_argument("--domain", type=int, default=63, help="DDS domain of the --dds runs (default 63)")
    ap.add_argument("--name", default="online",
                    help="stem of the files written into --out-dir (default online: online.md, .csv, .png)")
    ap.add_argument("--extra", default="", help="more arguments for every `tessera solve --online` run")
    ap.add_argument("--instructions", action="store_true",
                    help="also count instructions (valgrind --tool=callgrind, load-free): the online run "
                         "(run_online: steps and final certified solve) and its re-solves from scratch "
                         "(resolve_from_scratch), two more runs per case; slow (~50x)")
    args = ap.parse_args()
    ctx = bc.Ctx(args)
    rows, runs, dds_rows = [], [], []
    for name, path, robots, fkey, every, samples in cases(args, ctx.work, ctx.bin):
        load = os.getloadavg()[0]
        js = os.path.join(ctx.work, os.path.basename(path) + ".online.json")
        cmd = [ctx.bin, "solve", path, "--online", "--robots", str(robots), "--rate", str(args.rate),
               "--speedup", str(args.speedup)] + step_args(args) + [
               "--grad-tol", str(args.grad_tol), "--checkpoints", str(args.checkpoints),
               "--gap-bound", str(args.gap_bound), "--json", js]
        if not args.no_baseline:
            cmd += ["--baseline"]
        if not args.no_baseline:
            cmd += ["--baseline-per", args.baseline_per]
            if samples > 0:
                cmd += ["--baseline-samples", str(samples)]
            elif every > 1:
                cmd += ["--baseline-every", str(every)]
            if args.baseline_init != "chordal":
                cmd += ["--baseline-init", args.baseline_init]
            if args.baseline_solver != "newton":
                cmd += ["--baseline-solver", args.baseline_solver]
        if args.no_certify:
            cmd += ["--no-certify"]
        cmd += args.extra.split()
        if args.full:
            # Robot-aligned blocks cut city10000 thousands of times: the certificate's LOBPCG needs
            # more than its default 300 iterations there (docs/online.md, Figures).
            cmd += ["--certify-iters", "3000"]
        ctx.log(cmd)
        bc.progress(" ".join(cmd))
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        with open(js) as f:
            s = json.load(f)
        fstar, _ = ctx.fstar(fkey)
        stream_s = max(u["time_s"] for u in s["updates"]) or 1.0
        row = {
            "graph": name, "robots": robots, "poses": s["poses"], "measurements": s["measurements"],
            "steps": s["steps"], "rate": args.rate, "speedup": args.speedup, "grad_tol": args.grad_tol,
            "latency_median_s": s["latency_median_s"], "latency_p95_s": s["latency_p95_s"],
            "latency_cpu_median_s": s.get("latency_cpu_median_s"), "latency_cpu_p95_s": s.get("latency_cpu_p95_s"),
            "max_checkpoint_rel_gap": s["max_checkpoint_rel_gap"],
            # The latency: a checkpoint's newest data to an estimate within the gap bound
            # (null in the JSON: some checkpoint's step ended above it).
            "gap_bound": s.get("gap_bound"), "checkpoints": len(s.get("checkpoints", [])),
            "gap_latency_median_s": s.get("gap_latency_median_s"), "gap_latency_p95_s": s.get("gap_latency_p95_s"),
            "gap_latency_cpu_median_s": s.get("gap_latency_cpu_median_s"),
            "gap_latency_cpu_p95_s": s.get("gap_latency_cpu_p95_s"),
            "gap_latency_missed": s.get("gap_latency_missed"),
            "gap_cg_median": s.get("gap_cg_median"),
            "absorbed_gap_median": median([c["points"][0]["rel_gap"] for c in s.get("checkpoints", [])
                                           if c.get("points")]),
            "rounds_per_s": s["rounds"] / stream_s, "bytes_per_s_per_agent": s["bytes"] / stream_s / robots,
            "online_cpu_s": s["cpu_s"], "online_setup_s": s["setup_s"], "online_rounds_cpu_s": s["rounds_cpu_s"], "baseline_cpu_s": s.get("baseline_cpu_s"),
            "baseline_solves": s.get("baseline_solves"), "baseline_resolved": s.get("baseline_resolved"),
            "baseline_per": s.get("baseline_per"), "closures": s.get("baseline_closures"),
            "closure_publications": s.get("baseline_publications"),
            "closure_steps": s.get("baseline_closure_steps"),
            "baseline_rounds_per_solve": (s["baseline_measured_rounds"] / s["baseline_resolved"]
                                          if s.get("baseline_resolved") else None),
            "baseline_cg_per_solve": (s["baseline_measured_cg_iterations"] / s["baseline_resolved"]
                                      if s.get("baseline_resolved") else None),
            "cpu_ratio": s["cpu_s"] / s["baseline_cpu_s"] if s.get("baseline_cpu_s") else None,
            "max_step_cpu_s": max((u["cpu_s"] for u in s["updates"]), default=0.0),
            "critical_path_cpu_s": sum(u.get("critical_path_cpu_s", 0.0) for u in s["updates"]),
            "step_solver": s.get("step_solver", "rounds"),
            "newton_cg_iterations": sum(u.get("newton_cg_iterations", 0) for u in s["updates"]),
            # The blocks' tangent factorizations over the steps and their predicted flops (load-free).
            "factorizations": sum(u.get("factorizations", 0) for u in s["updates"]),
            "factor_gflops": sum(u.get("factor_flops", 0.0) for u in s["updates"]) / 1e9,
            "message_steps": s["rounds"] + sum(u.get("newton_message_steps", 0) for u in s["updates"]),
            "newton_steps": sum(u.get("newton_steps", 0) for u in s["updates"]),
            "repartitions": s.get("repartitions", 0), "poses_moved": s.get("poses_moved", 0),
            # Measurements between two blocks after the last step (0 when the cut refinement is off).
            "final_cut": s["updates"][-1].get("cut", 0) if s["updates"] else 0,
            "largest_block": max((u["largest_block"] for u in s["updates"]), default=0),
            "final_cost": s["cost"], "fstar": fstar,
            "final_rel_gap": (s["cost"] - fstar) / fstar if s.get("cost") else None,
            "certified": s["certified"], "load_1min": round(load, 2),
        }
        if args.instructions:
            row.update(count_instructions(ctx, cmd, js))
        rows.append(row)
        runs.append((name, s))
        if args.dds:
            dds_rows.append(run_dds(args, ctx, name, path, robots, fstar))
        write_outputs(args, ctx, rows, runs, dds_rows)  # after each case: a long run keeps what it did


def median(values):
    v = sorted(values)
    if not v:
        return None
    return v[len(v) // 2] if len(v) % 2 else 0.5 * (v[len(v) // 2 - 1] + v[len(v) // 2])


def callgrind(ctx, cmd, function):
    """Instructions executed inside `function` (callgrind --toggle-collect) by `cmd`: load-free."""
    out = os.path.join(ctx.work, "callgrind.out")
    full = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", f"--toggle-collect={function}"] + cmd
    ctx.log(full)
    bc.progress(" ".join(full))
    r = subprocess.run(full, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, check=True)
    m = re.search(r"Collected\s*:\s*([0-9]+)", r.stderr)
    os.remove(out)
    return int(m.group(1)) if m else None


def count_instructions(ctx, cmd, js):
    """The online run (steps and final certified solve, without the checkpoints' and the baseline's
    work) and the re-solves from scratch, counted in two runs of the same command."""
    base = [c for c in cmd if c not in ("--baseline",)]
    base = [c if c != js else js + ".cg" for c in base]
    k = base.index("--checkpoints")
    base[k + 1] = "0"
    online = callgrind(ctx, base, "tessera::run_online(*")
    scratch = callgrind(ctx, base + ["--baseline", "--no-certify"], "tessera::cli::resolve_from_scratch(*")
    with open(js + ".cg") as f:  # --baseline-every K: scaled as the CPU time is
        s = json.load(f)
    if scratch and s.get("baseline_resolved"):
        scratch = scratch * s["baseline_solves"] / s["baseline_resolved"]
    return {"online_ginstr": online / 1e9 if online else None,
            "baseline_ginstr": scratch / 1e9 if scratch else None,
            "instr_ratio": online / scratch if online and scratch else None}


def step_args(args):
    if args.steps == "real-time":
        return ["--real-time"]
    if args.steps == "tick":
        return []
    return ["--step-every", str(float(args.steps))]


def gap_fmt(r, key, spec="{:.4f}"):
    """A gap latency; "never" where the JSON has null (a checkpoint whose step ended above the bound)."""
    if r[key] is None and r["checkpoints"]:
        return "never"
    return bc.fmt(r[key], spec)


def write_outputs(args, ctx, rows, runs, dds_rows):
    headers = ["graph", "poses", "steps", "step solver", "message steps", "Newton steps", "Newton CG",
               "repartitions", "poses moved", "final cut", "largest block", "lat med s", "lat p95 s", "lat CPU med s", "lat CPU p95 s", "checkpoints", "gap lat med s",
               "gap lat p95 s", "gap lat CPU med s", "gap lat CPU p95 s", "gap CG med", "gap missed", "absorbed gap med", "max gap", "online CPU s", "set-up s",
               "rounds CPU s", "max step CPU s", "critical path s", "closures", "closure publications", "closure steps", "re-solves", "re-solve rounds", "re-solve CG", "re-solve CPU s", "ratio", "final rel gap", "certified", "load"]
    if args.instructions:
        headers += ["online G instr", "re-solve G instr", "instr ratio"]
    table = bc.print_table(
        f"online runs (rate {args.rate}/s per robot, speedup {args.speedup}, steps {args.steps}, "
        f"grad tol {args.grad_tol})",
        headers,
        [[r["graph"], r["poses"], r["steps"], r["step_solver"], r["message_steps"], r["newton_steps"],
          r["newton_cg_iterations"], r["repartitions"], r["poses_moved"], r["final_cut"], r["largest_block"],
          bc.fmt(r["latency_median_s"], "{:.4f}"),
          bc.fmt(r["latency_p95_s"], "{:.4f}"), bc.fmt(r["latency_cpu_median_s"], "{:.4f}"),
          bc.fmt(r["latency_cpu_p95_s"], "{:.4f}"), r["checkpoints"], gap_fmt(r, "gap_latency_median_s"),
          gap_fmt(r, "gap_latency_p95_s"), gap_fmt(r, "gap_latency_cpu_median_s"),
          gap_fmt(r, "gap_latency_cpu_p95_s"), gap_fmt(r, "gap_cg_median", "{:.0f}"), r["gap_latency_missed"], bc.fmt(r["absorbed_gap_median"], "{:.1e}"),
          bc.fmt(r["max_checkpoint_rel_gap"], "{:.2e}"),
          bc.fmt(r["online_cpu_s"], "{:.2f}"), bc.fmt(r["online_setup_s"], "{:.2f}"),
          bc.fmt(r["online_rounds_cpu_s"], "{:.2f}"), bc.fmt(r["max_step_cpu_s"], "{:.2f}"),
          bc.fmt(r["critical_path_cpu_s"], "{:.2f}"),
          r["closures"], r["closure_publications"], r["closure_steps"],
          f"{r['baseline_resolved']}/{r['baseline_solves']}",
          bc.fmt(r["baseline_rounds_per_solve"], "{:.0f}"), bc.fmt(r["baseline_cg_per_solve"], "{:.0f}"),
          bc.fmt(r["baseline_cpu_s"], "{:.2f}"),
          bc.fmt(r["cpu_ratio"], "{:.3f}"), bc.fmt(r["final_rel_gap"], "{:.1e}"), r["certified"], r["load_1min"]]
         + ([bc.fmt(r.get("online_ginstr"), "{:.2f}"), bc.fmt(r.get("baseline_ginstr"), "{:.2f}"),
             bc.fmt(r.get("instr_ratio"), "{:.3f}")] if args.instructions else [])
         for r in rows])
    bc.write_csv(os.path.join(ctx.out_dir, args.name + ".csv"), rows)
    dds_table = ""
    if dds_rows:
        dds_table = bc.print_table(
            f"online runs over DDS (tessera launch --online, rate {args.rate}/s per robot, speedup {args.speedup}, "
            f"grad tol {args.grad_tol})",
            ["graph", "agents", "solves", "rounds", "lat med s", "lat p95 s", "agents CPU s", "KB/s per agent",
             "repartitions", "poses moved", "final rel gap", "certified", "wall s", "load"],
            [[r["graph"], r["agents"], r["solves"], r["rounds"], bc.fmt(r["latency_median_s"], "{:.3f}"),
              bc.fmt(r["latency_p95_s"], "{:.3f}"), bc.fmt(r["agents_cpu_s"], "{:.2f}"),
              bc.fmt(r["kbytes_per_s_per_agent"], "{:.0f}"), r["repartitions"], r["poses_moved"],
              bc.fmt(r["final_rel_gap"], "{:.1e}"), r["certified"], bc.fmt(r["wall_s"], "{:.1f}"), r["load_1min"]]
             for r in dds_rows])
        bc.write_csv(os.path.join(ctx.out_dir, "online_dds.csv"), dds_rows)
    plt = bc.pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for name, s in runs:
        t = [u["time_s"] for u in s["updates"]]
        line, = axes[0].plot(t, [max(u["latency_s"], 1e-4) for u in s["updates"]], ".", ms=3, label=name)
        cps = [c for c in s.get("checkpoints", []) if c.get("time_to_gap_s") is not None]
        if cps:
            axes[0].plot([c["time_s"] for c in cps], [max(c["time_to_gap_s"], 1e-4) for c in cps], "x", ms=7,
                         color=line.get_color(), label=f"{name}: checkpoint within the gap bound")
        axes[1].plot(t, [u["rounds"] for u in s["updates"]], ".", ms=3, label=name)
    bc.style_log_axes(axes[0], "stream time (s)", "latency per step", "seconds")
    axes[1].set_xlabel("stream time (s)")
    axes[1].set_ylabel("rounds")
    axes[1].set_title("rounds per step")
    for ax in axes:
        ax.legend(fontsize=7)
    bc.save_figure(ctx, fig, args.name + ".png")
    print("\n" + table)
    print("\n" + bc.machine())
    md = os.path.join(ctx.out_dir, args.name + ".md")
    with open(md, "w") as f:
        f.write("# Online runs\n\nWritten by `scripts/bench/online.py` (docs/online.md); do not edit by hand.\n\n")
        f.write("- Command: `scripts/bench/online.py " + " ".join(sys.argv[1:]) + "`\n")
        f.write("- Machine when written: " + bc.machine() + "\n")
        f.write("- Runs (`load` = 1-minute load average at the start of each; the machine is shared, so "
                "latencies and CPU times are inflated by other jobs; rounds are not):\n\n")
        for c in ctx.commands:
            f.write(f"      {c}\n")
        f.write("\n" + table + "\n\n")
        if dds_table:
            f.write(dds_table + "\n\n")
            f.write("Over DDS: one `tessera-agent --online` process per robot and `tessera replay`; latency = a "
                    "batch's arrival at an agent to the end of the solve that absorbed it (agent 0); rounds = all "
                    "solves' rounds plus the final certified solve's; agents CPU = sum of the agents' process CPU "
                    "of their epochs; KB/s per agent = protocol and report bytes sent over the run's wall time; "
                    "repartitions = solves that moved poses between blocks.\n\n")
        f.write("Columns: step solver = how a step brings the gradient back under the tolerance (newton: "
                "distributed Newton steps from the warm start, the default; rounds: block-coordinate rounds); "
                "message steps = rounds plus the Newton steps' neighbour exchanges and all-agent sums over all "
                "steps (load-free); Newton CG = their CG iterations; "
                "latency = publication of a batch to the end of the step that absorbed it "
                "(gradient back under the tolerance or stalled), median and 95th percentile over all batches; "
                "gap lat = the issue's latency target, per checkpoint k the time from the publication of the "
                "newest batch of the graph received by k (stream clock) to the first estimate of the step that "
                "absorbed it whose relative gap (f(estimate) - f*_k) / f*_k is at most " + f"{args.gap_bound:g}" + " "
                "(--gap-bound): the estimates are the absorbed one (new poses composed and placed, before any "
                "solve), each accepted Newton step's and the step's end, each rounded and costed on graph k after "
                "the step; median and 95th percentile over the checkpoints, with wall time (gap lat) or the step's "
                "process CPU (gap lat CPU) since the step began, as the latency's; gap CG med = median over the "
                "checkpoints of the step's Newton CG iterations up to that estimate (load-free); gap missed = checkpoints whose "
                "step ended above the bound (their gap latency counts as infinite; never = a median or 95th "
                "percentile among them); absorbed gap med = median relative gap of the absorbed estimate (before any "
                "solve); with --speedup S the replay's clock runs S times faster than the robots', so the wait "
                "for a step is S times shorter than at real time while the step's compute time is not; max "
                "gap = largest relative gap (f(estimate) - f*_k) / f*_k over the checkpoints, f*_k the centralized "
                "optimum of the graph received by checkpoint k; online CPU = process CPU of all steps and the final "
                "certificate; max step CPU s = the longest step's process CPU (all agents); critical path s = the rounds' compute time summed over the steps with every agent on its own machine (per message step the slowest agent); set-up s = wall time of the agents' set-up (block problems, preconditioner factors) over the steps; rounds CPU s = process CPU of the rounds alone; closures = loop closure measurements in the replay; closure publications = batches (one robot, one "
                "publication time) with at least one; closure steps = steps that brought at least one; re-solves = "
                "re-solved / counted (per " + args.baseline_per + ": one per closure publication, the issue's "
                "re-solve after every loop closure with closures that arrive together sharing one; per closure one "
                "per closure measurement; per step one per closure step); re-solve rounds / CG = mean rounds / "
                "Newton CG iterations of a re-solve; re-solve CPU = the same agents and blocks solving from scratch (with " + args.baseline_solver +
                ": newton = the online steps' Newton steps, rounds = the batch solver's rounds; no warm start; from " + args.baseline_init + ": chordal = the batch solver's chordal initialization "
                "where the graph is connected, the front ends' guesses elsewhere) on the graph published up to "
                "and with each, to the same tolerance, without certificate; when only a sample is re-solved "
                "(every K-th, K = publications or closures / --baseline-samples), their CPU times (counted / re-solved); ratio = "
                "online CPU / re-solve CPU; final rel gap = (cost - f*) / f* with f* of the whole graph; with --instructions, "
                "online / re-solve G instr = instructions (valgrind --tool=callgrind, load-free) of the online run "
                "(tessera::run_online: the steps and the final certified solve) and of its re-solves from scratch "
                "(tessera::cli::resolve_from_scratch), each in its own run of the same command, and instr ratio = their "
                "ratio; repartitions = steps that moved poses between blocks, poses moved = their sum, final cut = "
                "measurements between two blocks after the last step (0: cut refinement off, --cut-fraction 1), "
                "largest block = the largest block's poses over the steps (block_rebalance.hpp).\n\n"
                f"![online]({args.name}.png)\n")
    print(f"wrote {os.path.relpath(md, bc.ROOT)}")


def run_dds(args, ctx, name, path, robots, fstar):
    load = os.getloadavg()[0]
    js = os.path.join(ctx.work, os.path.basename(path) + ".online_dds.json")
    cmd = [ctx.bin, "launch", path, "--agents", str(robots), "--online", "--rate", str(args.rate),
           "--speedup", str(args.speedup), "--grad-tol", str(args.grad_tol), "--domain", str(args.domain),
           "--json", js]
    ctx.log(cmd)
    bc.progress(" ".join(cmd))
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    with open(js) as f:
        s = json.load(f)
    wall = s["launch_wall_s"] or 1.0
    return {
        "graph": name, "agents": robots, "poses": s["total_poses"], "solves": s["solves"],
        "rounds": s["rounds"] + s["final_rounds"], "latency_median_s": s["latency_median_s"],
        "latency_p95_s": s["latency_p95_s"], "agents_cpu_s": sum(a["cpu_s"] for a in s["agents"]),
        "kbytes_per_s_per_agent": sum(a["bytes_sent"] + a["report_bytes"] for a in s["agents"]) / wall / robots / 1e3,
        "repartitions": sum(1 for u in s["updates"] if u["moved"] > 0),
        "poses_moved": sum(u["moved"] for u in s["updates"]),
        "final_cost": s.get("cost"), "fstar": fstar,
        "final_rel_gap": (s["cost"] - fstar) / fstar if s.get("cost") is not None else None,
        "certified": s["certified"], "wall_s": wall, "load_1min": round(load, 2),
    }


if __name__ == "__main__":
    main()
