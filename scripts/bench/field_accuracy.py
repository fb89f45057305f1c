#!/usr/bin/env python3
"""Accuracy of the certified optimum against the generator's ground truth, per generator kind.

For each kind (grid3d, sphere, torus: 3D; city: 2D) at two noise levels this script runs
    tessera generate --kind K --poses P --robots 3 --keys gtsam --rot-noise R --trans-noise T
                     --truth truth.g2o --out g.g2o
    tessera solve g.g2o --out opt.g2o            (centralized, certified)
    tessera eval opt.g2o truth.g2o --json e.json (ATE after SE(d) alignment, RPE over 1 pose)
and writes docs/benchmarks/field_accuracy.csv and field_accuracy.md. The ATE is the error the
noise leaves in the maximum-likelihood estimate: it grows with the noise and shrinks with the
loop closures; counts, not timings, so the figures do not depend on the machine's load.

usage: scripts/bench/field_accuracy.py [--bin build/bin/tessera] [--poses 1000] [--out-dir D]
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
KINDS = ["grid3d", "sphere", "torus", "city"]
NOISE = [(0.01, 0.05), (0.05, 0.2)]  # (rotation rad, translation m) standard deviations


def run(cmd):
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if r.returncode != 0:
        sys.exit("failed: " + " ".join(cmd) + "\n" + r.stdout)
    return r.stdout


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "bin", "tessera"))
    ap.add_argument("--poses", type=int, default=1000)
    ap.add_argument("--out-dir", default=os.path.join(ROOT, "docs", "benchmarks"))
    args = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory(prefix="tessera-field-") as work:
        for kind in KINDS:
            for rot, trans in NOISE:
                base = os.path.join(work, f"{kind}_{rot}_{trans}")
                g, truth, opt, ej = base + ".g2o", base + "_truth.g2o", base + "_opt.g2o", base + ".json"
                run([args.bin, "generate", "--kind", kind, "--poses", str(args.poses), "--robots", "3",
                     "--keys", "gtsam", "--rot-noise", str(rot), "--trans-noise", str(trans),
                     "--seed", "1", "--truth", truth, "--out", g])
                solve = run([args.bin, "solve", g, "--out", opt, "--json", base + "_solve.json"])
                with open(base + "_solve.json") as f:
                    s = json.load(f)
                run([args.bin, "eval", opt, truth, "--json", ej])
                with open(ej) as f:
                    e = json.load(f)
                rows.append({
                    "kind": kind, "d": e["d"], "poses": s["poses"], "edges": s["edges"], "robots": 3,
                    "rot_noise_rad": rot, "trans_noise_m": trans,
                    "certified": s["certified"], "cost": s["cost"],
                    "ate_rmse_m": e["ate"]["rmse"], "ate_mean_m": e["ate"]["mean"],
                    "ate_median_m": e["ate"]["median"], "ate_max_m": e["ate"]["max"],
                    "rpe_rmse_m": e["rpe"]["rmse"], "rpe_max_m": e["rpe"]["max"],
                })
                print(f"{kind:7s} noise {rot}/{trans}: ATE rmse {e['ate']['rmse']:.4g} m, "
                      f"RPE rmse {e['rpe']['rmse']:.4g} m, certified {s['certified']}", flush=True)
                del solve
    os.makedirs(args.out_dir, exist_ok=True)
    csv_path = os.path.join(args.out_dir, "field_accuracy.csv")
    with open(csv_path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    md = ["# Accuracy of the certified optimum against the ground truth", "",
          "Reproduce: `scripts/bench/field_accuracy.py --poses %d` (generate -> solve -> eval, "
          "3 robots, GTSAM keys, seed 1)." % args.poses, "",
          "| kind | d | poses | edges | rot noise (rad) | trans noise (m) | certified | ATE rmse (m) | "
          "ATE median (m) | ATE max (m) | RPE rmse (m) |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        md.append(f"| {r['kind']} | {r['d']} | {r['poses']} | {r['edges']} | {r['rot_noise_rad']} | "
                  f"{r['trans_noise_m']} | {r['certified']} | {r['ate_rmse_m']:.4g} | "
                  f"{r['ate_median_m']:.4g} | {r['ate_max_m']:.4g} | {r['rpe_rmse_m']:.4g} |")
    with open(os.path.join(args.out_dir, "field_accuracy.md"), "w") as f:
        f.write("\n".join(md) + "\n")
    print("wrote", csv_path)


if __name__ == "__main__":
    main()
