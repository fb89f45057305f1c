"""Shared helpers of the scripts/bench/exp_*.py experiments (and run_all.py).

Running tessera (with its JSON summary, per-round trace and the child's peak memory), f* from
../shared/reference/optima.csv, generated graphs (cached per invocation), the machine
description, markdown/plain tables, CSV writing and the matplotlib setup (Agg backend).
"""
import csv
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
DEFAULT_SHARED = os.path.abspath(os.path.join(ROOT, "..", "shared"))
OUT_DIR = os.path.join(ROOT, "docs", "benchmarks")
# Stand-in for the paper's grid3D, which ../shared holds only as structure (METIS).
GRID_NOTE = ("grid3D exists in ../shared only as a METIS structure file (no measurements), so the "
             "optimisation experiments use a generated 3D grid instead: "
             "`tessera generate --kind grid3d --poses P --robots 5`")


def add_common_args(ap):
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "bin", "tessera"), help="tessera binary")
    ap.add_argument("--shared", default=DEFAULT_SHARED, help="folder holding datasets/ and reference/")
    ap.add_argument("--out-dir", default=OUT_DIR, help="where CSV and PNG files go")
    ap.add_argument("--work", default="", help="scratch folder for generated graphs (default: a temp dir)")
    ap.add_argument("--quick", action="store_true", help="small graphs, fewer rounds (CI smoke test)")


def experiment_main(doc, run):
    """main() of an exp_*.py experiment with only the common options: run(Ctx)."""
    import argparse
    ap = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_common_args(ap)
    run(Ctx(ap.parse_args()))


class Ctx:
    """What every experiment needs: binary, folders, quick flag, a scratch dir and a command log."""

    def __init__(self, args):
        self.bin = os.path.abspath(args.bin)
        self.shared = os.path.abspath(args.shared)
        self.out_dir = os.path.abspath(args.out_dir)
        self.quick = args.quick
        os.makedirs(self.out_dir, exist_ok=True)
        self._tmp = None
        if args.work:
            self.work = os.path.abspath(args.work)
            os.makedirs(self.work, exist_ok=True)
        else:
            self._tmp = tempfile.TemporaryDirectory(prefix="tessera-bench-")
            self.work = self._tmp.name
        self.commands = []  # every tessera command line run, for the README
        self._fstar = {}

    def dataset(self, name):
        return os.path.join(self.shared, "datasets", name + ".g2o")

    def grid_poses(self):
        return 1000 if self.quick else 8000

    def log(self, cmd):
        """Records a command line for the README, with the scratch/shared folders abbreviated."""
        def short(c):
            c = c.replace(self.work, "$WORK").replace(self.shared, "../shared")
            return os.path.relpath(c, ROOT) if os.path.isabs(c) and c.startswith(ROOT) else c
        self.commands.append(" ".join(short(c) for c in cmd))

    def generate(self, poses, robots=5, kind="grid3d"):
        """Generates (once per invocation and work dir) a graph and returns its path."""
        path = os.path.join(self.work, f"{kind}_{poses}_r{robots}.g2o")
        if not os.path.exists(path):
            cmd = [self.bin, "generate", "--kind", kind, "--poses", str(poses), "--robots", str(robots),
                   "--out", path]
            self.log(cmd)
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        return path

    def grid(self):
        return self.generate(self.grid_poses())

    def fstar(self, name_or_path):
        """f* of a benchmark graph (optima.csv; the _qnorm row, as the reader normalises quaternions),
        or of a generated graph (computed once by the centralized certifiable solver)."""
        if name_or_path in self._fstar:
            return self._fstar[name_or_path]
        if not os.path.sep in name_or_path:
            table = read_reference(self.shared, "optima.csv", "dataset")
            v = float(table.get(name_or_path + "_qnorm", table[name_or_path])["f_star"])
            src = "reference/optima.csv"
        else:
            progress(f"computing f* of {os.path.basename(name_or_path)} with the centralized solver")
            js = os.path.join(self.work, os.path.basename(name_or_path) + ".fstar.json")
            cmd = [self.bin, "solve", name_or_path, "--algorithm", "centralized", "--json", js]
            self.log(cmd)
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
            with open(js) as f:
                s = json.load(f)
            v = s["cost"]
            src = "centralized solver, this run" + ("" if s.get("certified") else " (NOT certified)")
        self._fstar[name_or_path] = (v, src)
        return self._fstar[name_or_path]


def read_reference(shared, name, *key):
    """Rows of ../shared/reference/NAME (csv) as dicts of strings, by the value of the column
    `key` names, or by the tuple of values when it names several columns."""
    with open(os.path.join(shared, "reference", name)) as f:
        rows = csv.DictReader(f)
        if len(key) == 1:
            return {r[key[0]]: r for r in rows}
        return {tuple(r[k] for k in key): r for r in rows}


def children_usage():
    """(CPU seconds user + system, voluntary context switches) of every finished child process
    and its waited-for descendants (launch waits for the coordinator and the agents), so a
    difference around one run counts all of its processes."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime, r.ru_nvcsw


def usage_since(before):
    """(CPU seconds, context switches) of the children finished since `before` = children_usage()."""
    cpu, csw = children_usage()
    return cpu - before[0], csw - before[1]


def cpu_since(before):
    """CPU seconds (user + system) of the children finished since `before` = children_usage()."""
    return usage_since(before)[0]


def progress(msg):
    print(f"[{time.strftime('%H:%M:%S')}] {msg}", file=sys.stderr, flush=True)


class OverLimit(RuntimeError):
    """The run was stopped by run_tessera's memory or time limit."""


def run_tessera(ctx, args, trace=True, timeout=None, mem_limit_mb=None):
    """Runs `tessera ARGS --json F [--trace T]`; returns (summary, trace rows, peak RSS MB of the
    process (VmHWM, sampled every 50 ms), wall s). Raises RuntimeError with the output on failure."""
    fd, js = tempfile.mkstemp(suffix=".json", dir=ctx.work)
    os.close(fd)
    tr = js[:-5] + ".csv"
    cmd = [ctx.bin] + list(args) + ["--json", js] + (["--trace", tr] if trace else [])
    ctx.log([{js: "OUT.json", tr: "TRACE.csv"}.get(c, c) for c in cmd])
    t0 = time.monotonic()
    with open(js + ".log", "w") as logf:
        p = subprocess.Popen(cmd, stdout=logf, stderr=subprocess.STDOUT)
        deadline = None if timeout is None else t0 + timeout
        beat = t0
        hwm_kb = 0
        while True:
            # Peak RSS of the tessera process itself: VmHWM restarts at exec, whereas the child's ru_maxrss
            # also counts the forked Python interpreter before the exec.
            try:
                with open(f"/proc/{p.pid}/status") as f:
                    for line in f:
                        if line.startswith("VmHWM:"):
                            hwm_kb = max(hwm_kb, int(line.split()[1]))
            except (OSError, ValueError):
                pass
            pid, status, ru = os.wait4(p.pid, os.WNOHANG)
            if pid:
                break
            if time.monotonic() - beat > 15:  # long runs show progress: rounds so far (trace lines)
                beat = time.monotonic()
                done = 0
                if trace and os.path.exists(tr):
                    with open(tr, "rb") as f:
                        done = max(0, sum(1 for _ in f) - 2)
                progress(f"  ... {args[0]} running for {beat - t0:.0f} s" + (f", round {done}" if done else ""))
            over = None
            if deadline and time.monotonic() > deadline:
                over = f"stopped after the {timeout:.0f} s time limit"
            if mem_limit_mb and hwm_kb / 1024.0 > mem_limit_mb:
                # The machine is shared: stop before the process takes all of its memory.
                over = (f"stopped at {hwm_kb / 1048576.0:.1f} GB peak RSS (limit {mem_limit_mb / 1024.0:.0f} GB) "
                        f"after {time.monotonic() - t0:.0f} s")
            if over:
                p.kill()
                os.wait4(p.pid, 0)
                raise OverLimit(over)
            time.sleep(0.05)
    wall = time.monotonic() - t0
    p.returncode = os.waitstatus_to_exitcode(status)
    if p.returncode != 0:
        with open(js + ".log") as f:
            raise RuntimeError(f"failed ({p.returncode}): {' '.join(cmd)}\n{f.read()[-2000:]}")
    with open(js) as f:
        summary = json.load(f)
    rows = read_trace(tr) if trace else []
    return summary, rows, (hwm_kb or ru.ru_maxrss) / 1024.0, wall


def read_trace(path):
    """Trace rows as floats; a non-numeric cell (`selected` of a parallel round, e.g. "1;3")
    stays a string."""
    def value(v):
        try:
            return float(v)
        except ValueError:
            return v
    rows = []
    with open(path) as f:
        for r in csv.DictReader(f):
            rows.append({k: value(v) for k, v in r.items() if v not in ("", None)})
    return rows


def first_round(trace, tol):
    for r in trace:
        if r["grad_norm"] <= tol:
            return int(r["round"])
    return None


def machine():
    """One line describing the machine and its load (the machine is shared)."""
    cpu = platform.processor() or ""
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    mem = ""
    try:
        with open("/proc/meminfo") as f:
            mem = "%.1f GB RAM" % (int(f.readline().split()[1]) / 1048576)
    except OSError:
        pass
    la = os.getloadavg()
    return (f"{platform.node()}: {cpu}, {os.cpu_count()} cores, {mem}, {platform.system()} {platform.release()}, "
            f"Python {platform.python_version()}; load average {la[0]:.2f} {la[1]:.2f} {la[2]:.2f}")


def fmt(x, spec="{:g}"):
    if x is None or x == "":
        return "-"
    if isinstance(x, str):
        return x
    return spec.format(x)


def print_table(title, headers, rows):
    """Prints a plain table; returns the same table as markdown."""
    cells = [[str(c) for c in r] for r in rows]
    widths = [max(len(h), *(len(r[i]) for r in cells)) if cells else len(h) for i, h in enumerate(headers)]
    print(f"\n{title}")
    print("  ".join(h.rjust(w) for h, w in zip(headers, widths)))
    for r in cells:
        print("  ".join(c.rjust(w) for c, w in zip(r, widths)))
    sys.stdout.flush()
    def esc(c):  # a "|" inside a cell (|grad|) would split the markdown column
        return c.replace("|", "\\|")
    md = ["| " + " | ".join(esc(h) for h in headers) + " |", "|" + "|".join("---" for _ in headers) + "|"]
    md += ["| " + " | ".join(esc(c) for c in r) + " |" for r in cells]
    return "\n".join(md)


def write_csv(path, rows, announce=True):
    """Writes dict rows (columns: every key, in first-seen order); `announce` prints the path."""
    if not rows:
        return
    keys = []
    for r in rows:
        for k in r:
            if k not in keys:
                keys.append(k)
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)
    if announce:
        print(f"wrote {os.path.relpath(path, ROOT)}")


def pyplot():
    try:
        import matplotlib
    except ImportError:
        # A python3 other than Debian's (e.g. pyenv) first on PATH: use Debian's python3-matplotlib.
        sys.path.append("/usr/lib/python3/dist-packages")
        import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def save_figure(ctx, fig, name, dpi=100):
    """Lays out `fig`, writes it as ctx.out_dir/name, closes it, and returns the path."""
    plt = pyplot()
    fig.tight_layout()
    path = os.path.join(ctx.out_dir, name)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    print(f"wrote {os.path.relpath(path, ROOT)}")
    return path


def style_log_axes(ax, xlabel, title, ylabel=None, grid="major"):
    """The look every convergence plot shares: log y axis, labels, light grid, small legend."""
    ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    if ylabel is not None:
        ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, which=grid, alpha=0.3)
    ax.legend(fontsize=8)


def gap_series(trace, fstar):
    """(rounds, f - f*) with non-positive gaps (round-off at the optimum) clipped for log axes."""
    xs, ys = [], []
    for r in trace:
        xs.append(r["round"])
        ys.append(max(r["cost"] - fstar, 1e-12 * abs(fstar)))
    return xs, ys


class Result:
    """What an experiment hands back to run_all.py: a title, markdown sections, files, notes."""

    def __init__(self, title):
        self.title = title
        self.sections = []  # markdown text blocks
        self.images = []
        self.csvs = []

    def add(self, text):
        self.sections.append(text)

    def add_csv(self, ctx, name, rows):
        """Writes `rows` (see write_csv) as ctx.out_dir/name and lists the file in the section."""
        path = os.path.join(ctx.out_dir, name)
        write_csv(path, rows)
        self.csvs.append(path)
        return path

    def markdown(self, out_dir):
        parts = [f"## {self.title}", ""]
        parts += [s + "\n" for s in self.sections]
        for img in self.images:
            parts.append(f"![{self.title}]({os.path.relpath(img, out_dir)})\n")
        if self.csvs:
            parts.append("CSV: " + ", ".join(f"[{os.path.basename(c)}]({os.path.relpath(c, out_dir)})"
                                              for c in self.csvs) + "\n")
        return "\n".join(parts)


# ---- fault benchmarks (faults.py, faults_loss.py): processes of one run and the fault table row

def wait_for_output(read, text, deadline, alive):
    """Polls read() (every 5 ms) until it contains `text`; False at `deadline` (time.time()) or
    when alive() turns false (the process that writes it ended)."""
    while text not in read():
        if time.time() > deadline or not alive():
            return False
        time.sleep(0.005)
    return True


def fault_row(fault, trials):
    """The fault table's contract row from the trials (dicts with finished, rel_cost_error,
    extra_s): worst cost error and mean extra time over the finished trials."""
    finished = [x for x in trials if x["finished"]]
    return dict(fault=fault, trials=len(trials), finished=len(finished),
                cost_error="%.1e" % max([x["rel_cost_error"] for x in finished], default=float("nan")),
                extra_time_s="%.2f" % (sum(x["extra_s"] for x in finished) / max(1, len(finished))))


# ---- permanent-loss benchmarks (faults_loss.py, faults_launch_loss.py) ----------------------

def add_loss_args(ap, domain):
    """The options both permanent-loss benchmarks take (same names, same defaults)."""
    ap.add_argument("--trials", type=int, default=10)
    ap.add_argument("--agents", type=int, default=5)
    ap.add_argument("--poses", type=int, default=500)
    ap.add_argument("--grad-tol", type=float, default=0.0005)
    ap.add_argument("--replica-every", type=int, default=5)
    ap.add_argument("--rejoin-timeout", type=float, default=1.0)
    ap.add_argument("--domain", type=int, default=domain)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--limit", type=float, default=300, help="time limit of one run, seconds")


def loss_graph_and_fstar(tessera, args, work):
    """Generates the benchmark's 3D grid into work/graph.g2o (args.graph_path) and returns f*
    from the centralized solver, which every trial's final cost is compared with."""
    args.graph_path = os.path.join(work, "graph.g2o")
    subprocess.run([tessera, "generate", "--kind", "grid3d", "--poses", str(args.poses), "--robots",
                    str(args.agents), "--seed", "3", "--out", args.graph_path], check=True,
                   stdout=subprocess.DEVNULL)
    cjson = os.path.join(work, "centralized.json")
    subprocess.run([tessera, "solve", args.graph_path, "--algorithm", "centralized", "--json", cjson],
                   check=True, stdout=subprocess.DEVNULL)
    with open(cjson) as f:
        fstar = json.load(f)["cost"]
    print("f* = %.12g (centralized)" % fstar, flush=True)
    return fstar


def g2o_vertex_ids(path):
    """The pose ids of a g2o file's VERTEX lines (empty when the file does not exist)."""
    ids = set()
    if os.path.exists(path):
        with open(path) as f:
            for line in f:
                if line.startswith("VERTEX"):
                    ids.add(int(line.split()[1]))
    return ids
