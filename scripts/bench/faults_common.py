"""What the fault benchmarks share (faults.py: restart, faults_loss.py, faults_launch_loss.py,
faults_secured.py): the fault table's column contract, its CSV and the assembly of
docs/benchmarks/faults.md, the option preamble (--bin-dir, --out-dir, plus each script's own
options), the start (checked bin dir, scratch folder, generated graph) and the end of a
benchmark (contract row written and printed, per-trial CSV and notes written, table
re-assembled, scratch folder removed when every trial finished).

COLUMN CONTRACT (every docs/benchmarks/faults_<name>.csv, one row per fault kind):
    fault,trials,finished,cost_error,extra_time_s
  fault         short description of the fault injected
  trials        number of runs with that fault
  finished      runs that completed (exit 0 of every process, summary written)
  cost_error    worst relative cost error of the finished runs against the undisturbed run
                (|cost - cost_undisturbed| / cost_undisturbed), or against f* where stated
  extra_time_s  mean extra wall time of a faulty run over the undisturbed run, in seconds
"""
import argparse
import csv
import glob
import os
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import bench_common as bc  # noqa: E402

ROOT = bc.ROOT
OUT_DIR = bc.OUT_DIR
COLUMNS = ["fault", "trials", "finished", "cost_error", "extra_time_s"]


def parser(doc, **defaults):
    """The options every fault benchmark takes: --bin-dir, --out-dir, and (with defaults given
    here) --trials, --agents, --poses, --domain, --limit; the script adds its own."""
    ap = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin-dir", default=os.path.join(ROOT, "build", "bin"),
                    help="folder with tessera, tessera-agent, tessera-coordinator, tessera-dds-snoop")
    ap.add_argument("--out-dir", default=OUT_DIR, help="where faults_*.csv, faults/ and faults.md go")
    for name in ("trials", "agents", "poses", "domain"):
        if name in defaults:
            ap.add_argument("--" + name, type=int, default=defaults[name])
    if "limit" in defaults:
        ap.add_argument("--limit", type=float, default=defaults["limit"], help="time limit of one run, seconds")
    return ap


def check_args(args):
    """Clear errors for bad common options (exits with status 2 naming the option)."""
    for exe in ("tessera", "tessera-agent", "tessera-coordinator"):
        if not os.access(os.path.join(args.bin_dir, exe), os.X_OK):
            sys.exit("option --bin-dir: %s has no executable %s (build first)" % (args.bin_dir, exe))
    for name, low in (("trials", 1), ("agents", 2), ("poses", 10)):
        if getattr(args, name, low) < low:
            sys.exit("option --%s: must be at least %d" % (name, low))
    if getattr(args, "domain", 0) < 0 or getattr(args, "domain", 0) > 232:
        sys.exit("option --domain: must be 0..232")
    if getattr(args, "limit", 1) <= 0:
        sys.exit("option --limit: must be positive")


def start(args, prefix, graph=True):
    """Checks the options, makes the scratch folder and (graph=True) generates the benchmark's
    grid3d into work/graph.g2o (args.graph_path, seed 3). Returns the scratch folder."""
    check_args(args)
    work = tempfile.mkdtemp(prefix=prefix)
    if graph:
        args.graph_path = os.path.join(work, "graph.g2o")
        subprocess.run([os.path.join(args.bin_dir, "tessera"), "generate", "--kind", "grid3d", "--poses",
                        str(args.poses), "--robots", str(args.agents), "--seed", "3", "--out", args.graph_path],
                       check=True, stdout=subprocess.DEVNULL)
    return work


def write_contract_csv(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(COLUMNS)
        for r in rows:
            w.writerow([r[c] for c in COLUMNS])


def assemble(out_dir):
    """Rebuilds faults.md from every faults_*.csv of the contract, with links to every faults/*.md."""
    rows, sources = [], []
    for path in sorted(glob.glob(os.path.join(out_dir, "faults_*.csv"))):
        with open(path) as f:
            reader = csv.DictReader(f)
            if reader.fieldnames != COLUMNS:
                print("skipping %s: columns %s are not the contract %s" % (path, reader.fieldnames, COLUMNS))
                continue
            for r in reader:
                rows.append(r)
        sources.append(os.path.basename(path))
    lines = ["# Fault table", "",
             "Assembled by `scripts/bench/faults.py` from " + ", ".join("`%s`" % s for s in sources) +
             " (columns: %s; see scripts/bench/faults_common.py for their meaning)." % ", ".join(COLUMNS), "",
             "| fault | trials | finished | cost error | extra time (s) |", "|---|---|---|---|---|"]
    for r in rows:
        lines.append("| %s | %s | %s | %s | %s |" % tuple(r[c] for c in COLUMNS))
    # Each experiment's notes stay in faults/<name>.md; the table links them instead of copying them.
    notes = []
    for extra in sorted(glob.glob(os.path.join(out_dir, "faults", "*.md"))):
        with open(extra) as f:
            title = f.readline().lstrip("#").strip() or os.path.basename(extra)
        notes.append("[%s](faults/%s)" % (title, os.path.basename(extra)))
    if notes:
        lines += ["", "Each experiment's notes (the exact command, the machine's load, a table per trial; the "
                  "trials also in `faults/*_trials.csv`): " + ", ".join(notes) + "."]
    with open(os.path.join(out_dir, "faults.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("wrote %s (%d rows)" % (os.path.join(out_dir, "faults.md"), len(rows)))


def notes_head(title, name):
    """The first lines of faults/<name>.md: the title, the exact command, the machine's load."""
    load = ", ".join("%.1f" % x for x in os.getloadavg())
    return ["## %s (`faults_%s.csv`)" % (title, name), "",
            "Command: `scripts/bench/%s %s`" % (os.path.basename(sys.argv[0]), " ".join(sys.argv[1:])), "",
            "Load average (1, 5, 15 min) when the notes were written: %s on %d cores." % (load, os.cpu_count()), ""]


def finish(args, name, row, trials, work, notes=None):
    """The end of a benchmark named `name`: writes faults_<name>.csv (the contract row),
    faults/<name>_trials.csv (one row per trial), faults/<name>.md (`notes`, a list of lines,
    if given), prints the row, re-assembles faults.md, removes `work` when every trial
    finished (kept with TESSERA_BENCH_KEEP=1 or on a failure). Returns the exit status."""
    os.makedirs(os.path.join(args.out_dir, "faults"), exist_ok=True)
    write_contract_csv(os.path.join(args.out_dir, "faults_%s.csv" % name), [row])
    bc.write_csv(os.path.join(args.out_dir, "faults", "%s_trials.csv" % name), trials, announce=False)
    if notes is not None:
        with open(os.path.join(args.out_dir, "faults", "%s.md" % name), "w") as f:
            f.write("\n".join(notes) + "\n")
    print("\n" + " | ".join(COLUMNS))
    print(" | ".join(str(row[c]) for c in COLUMNS))
    assemble(args.out_dir)
    all_finished = sum(1 for x in trials if x["finished"]) == len(trials)
    if all_finished and not os.environ.get("TESSERA_BENCH_KEEP"):
        shutil.rmtree(work, ignore_errors=True)
    else:
        print("work dir kept: " + work)
    return 0 if all_finished else 1
