#!/usr/bin/python3
"""Experiment 1 -- partition quality (paper Table I).

The 12 graphs of the paper, N = 5, eps 0.03: cut measurements of the sequential partition and of
each preset, balance (max block / ceil(n/N)), Cvolume and partitioning time, beside the paper's
cuts (../shared/datasets/PAPER_PARTITIONS.md; labelled "paper"). Full mode also runs N = 4, 9, 16,
25 on the larger graphs. Uses the runner of scripts/bench/partition_quality.py.

  scripts/bench/exp_partition_quality.py [--quick] [--bin B] [--shared S] [--out-dir D]
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_common as bc  # noqa: E402
import partition_quality as pq  # noqa: E402

PRESETS = ["sequential", "fast", "eco", "strong", "highest"]
PAPER_COLS = {"strong": 1, "eco": 2, "fast": 3, "highest": 4}


def run(ctx):
    res = bc.Result("1. Partition quality (paper Table I)")
    datasets = os.path.join(ctx.shared, "datasets")
    rows, table = [], []
    # --quick skips the slow presets (strong/highest take seconds per graph on a loaded machine).
    presets = ["sequential", "fast", "eco"] if ctx.quick else PRESETS
    for name, rel, label, paper in pq.GRAPHS:
        bc.progress(f"partition quality: {name}")
        path = os.path.join(datasets, rel)
        line = [name]
        for p in presets:
            ctx.log([ctx.bin, "partition", path, "--parts", "5", "--preset", p, "--seed", "1", "--eps", "0.03",
                     "--json", "-"])
            m = pq.measure(ctx.bin, path, 5, p, 1, 0.03)
            if p == "sequential":
                line.insert(1, m["n"])
            paper_cut = paper[PAPER_COLS[p]] if p in PAPER_COLS else None
            rows.append({"graph": name, "n": m["n"], "edges": m["edges"], "parts": 5, "preset": p,
                         "cut": m["best"], "paper_cut": paper_cut, "max_block_ratio": m["ratio"],
                         "cvolume": round(m["cvolume"], 6), "time_ms": round(m["ms"], 2),
                         "cpu_ms": round(m["cpu"], 2)})
            line.append(f"{m['best']}" + (f" ({paper_cut})" if paper_cut is not None else ""))
            if p == presets[-1]:
                line += [f"{m['ratio']:.3f}", f"{m['cvolume']:.4f}", f"{m['ms']:.1f}"]
            if p == "sequential":
                line.append(f"{m['cvolume']:.4f}")
        table.append(line)
    last = presets[-1]
    headers = (["graph", "n", "sequential cut", "Cvol seq"] + [f"{p} (paper)" for p in presets[1:]]
               + [f"balance {last}", f"Cvol {last}", f"ms {last}"])
    md = bc.print_table("Partition quality, N = 5, eps 0.03 (cut = measurements between blocks; in brackets: "
                        "the paper's Table I, printed labels)", headers, table)
    res.add(("`--quick`: presets sequential, fast, eco only. " if ctx.quick else "") + "N = 5, eps = 0.03, seed 1. Cut = measurements between blocks; numbers in brackets are the "
            "**paper's** Table I cuts (`PAPER_PARTITIONS.md`, printed labels), not measured here. "
            "Balance = largest block / ceil(n/N); Cvolume as defined by the paper; ms = partitioning wall time.\n\n"
            + md)
    res.add_csv(ctx, "exp1_partition_quality.csv", rows)

    krows = []
    if not ctx.quick:
        table = []
        for name, rel, label, paper in pq.GRAPHS:
            if name not in pq.LARGE:
                continue
            path = os.path.join(datasets, rel)
            for parts in (4, 9, 16, 25):
                bc.progress(f"partition quality: {name} N = {parts}")
                line = [name, parts]
                for p in PRESETS:
                    ctx.log([ctx.bin, "partition", path, "--parts", str(parts), "--preset", p, "--json", "-"])
                    m = pq.measure(ctx.bin, path, parts, p, 1, 0.03)
                    krows.append({"graph": name, "n": m["n"], "parts": parts, "preset": p, "cut": m["best"],
                                  "max_block_ratio": m["ratio"], "cvolume": round(m["cvolume"], 6),
                                  "time_ms": round(m["ms"], 2)})
                    line.append(f"{m['best']}")
                line.append(f"{krows[-1]['time_ms']:.0f}")
                table.append(line)
        md = bc.print_table("Cut for N = 4, 9, 16, 25", ["graph", "N"] + PRESETS + ["ms highest"], table)
        res.add("Cut for N = 4, 9, 16, 25 on the larger graphs:\n\n" + md)
        res.add_csv(ctx, "exp1_partition_quality_k.csv", krows)
    else:
        res.add("(`--quick`: N = 4, 9, 16, 25 skipped.)")

    res.images.append(plot(ctx, rows, krows))
    return res


def plot(ctx, rows, krows):
    plt = bc.pyplot()
    ncols = 2 if krows else 1
    fig, axes = plt.subplots(1, ncols, figsize=(7 * ncols + 2, 5), squeeze=False)
    ax = axes[0][0]
    graphs = [g[0] for g in pq.GRAPHS]
    width = 0.8 / (len(PRESETS) + 1)  # fixed, so quick and full plots look alike
    presets = [p for p in PRESETS if any(r["preset"] == p for r in rows)]
    for k, p in enumerate(presets):
        ys = [next(r["cut"] for r in rows if r["graph"] == g and r["preset"] == p) for g in graphs]
        ax.bar([i + k * width for i in range(len(graphs))], ys, width, label=f"{p} (measured)")
    paper = [g[3][4] for g in pq.GRAPHS]
    ax.bar([i + len(presets) * width for i in range(len(graphs))], paper, width, color="black",
           label="paper highest (Table I)")
    ax.set_xticks([i + 0.4 for i in range(len(graphs))])
    ax.set_xticklabels(graphs, rotation=45, ha="right")
    ax.set_yscale("log")
    ax.set_ylabel("cut measurements (count, log)")
    ax.set_title("N = 5: cut per graph and preset")
    ax.legend(fontsize=7)
    if krows:
        ax = axes[0][1]
        for g in pq.LARGE:
            xs = [r["parts"] for r in krows if r["graph"] == g and r["preset"] == "highest"]
            ys = [r["cut"] for r in krows if r["graph"] == g and r["preset"] == "highest"]
            ax.plot(xs, ys, "o-", label=f"{g} highest")
            ys = [r["cut"] for r in krows if r["graph"] == g and r["preset"] == "sequential"]
            ax.plot(xs, ys, "x--", color=ax.lines[-1].get_color(), alpha=0.6, label=f"{g} sequential")
        ax.set_yscale("log")
        ax.set_xlabel("number of blocks N")
        ax.set_ylabel("cut measurements (count, log)")
        ax.set_title("cut against N")
        ax.legend(fontsize=6, ncol=2)
    return bc.save_figure(ctx, fig, "exp1_partition_quality.png", dpi=110)


def main():
    bc.experiment_main(__doc__, run)


if __name__ == "__main__":
    main()
