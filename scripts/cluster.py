#!/usr/bin/env python3
"""Maps and campaigns too big for one machine, on a Dask cluster (docs/cluster.md).

This script only submits shards and merges them: each shard is one run of the project's own
tools on a Dask worker (`ftmap generate --shard I/N`, `harness trials --shard I/N`), whose
output file comes back to this process as bytes; `ftmap merge` and `harness merge` then join
them here into what one run on one machine writes. No file system needs to be shared.

  python3 scripts/cluster.py map --task peg_in_hole_4dof --shards 8 --out out/4dof.ftmap
  python3 scripts/cluster.py trials --shards 8 --out runs/peg -- --task peg_in_hole --trials 400

Without --scheduler, a local cluster of --workers processes is started (one thread each).
Every worker needs this project checked out and built at the path given by the environment
variable FTFUSION_ROOT on that worker (default: the path of this checkout).
"""

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def checkout():
    """The checkout this worker runs in: $FTFUSION_ROOT, else the path of this one."""
    return Path(os.environ.get("FTFUSION_ROOT", str(ROOT)))


def tool(name):
    """The release binary `name` of the checkout this worker runs in."""
    return str(checkout() / "target" / "release" / name)


def run_tool(args, cwd):
    """Runs a project tool; its error output is the exception's message when it fails."""
    done = subprocess.run(args, cwd=cwd, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(args)} failed ({done.returncode}):\n{done.stderr}")
    return done.stdout


def map_shard(task, i, n, extra):
    """On a worker: shard i of n of the task's map; the shard file's bytes."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / f"shard{i}.ftmap"
        run_tool([tool("ftmap"), "generate", "--task", task, "--shard", f"{i}/{n}",
                  "--out", str(out), *extra], cwd=checkout())
        return out.read_bytes()


def trials_shard(args, i, n):
    """On a worker: shard i of n of the campaign `args` (harness trials options); the text
    of its shard.json."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / f"shard{i}"
        run_tool([tool("harness"), "trials", *args, "--shard", f"{i}/{n}", "--out", str(out)],
                 cwd=checkout())
        return (out / "shard.json").read_text()


def client(opts):
    """A Dask client of the given scheduler, or of a local cluster started for this run."""
    from distributed import Client, LocalCluster

    if opts.scheduler:
        return Client(opts.scheduler)
    cluster = LocalCluster(n_workers=opts.workers, threads_per_worker=1, processes=True,
                           dashboard_address=None)
    return Client(cluster)


def gather(c, futures, what):
    """The futures' results in order; a failed shard ends the run with its tool's message."""
    try:
        return c.gather(futures)
    except RuntimeError as e:
        sys.exit(f"cluster: a {what} shard failed: {e}")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scheduler", help="address of a running Dask scheduler (tcp://host:8786)")
    p.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                   help="workers of the local cluster started without --scheduler")
    sub = p.add_subparsers(dest="job", required=True)
    m = sub.add_parser("map", help="an FT-Map in shards (ftmap generate --shard), merged")
    m.add_argument("--task", required=True, help="task name or task.toml path (on the workers)")
    m.add_argument("--shards", type=int, required=True)
    m.add_argument("--out", required=True, type=Path)
    m.add_argument("generate", nargs="*", help="more `ftmap generate` options, after --")
    t = sub.add_parser("trials", help="a campaign in shards (harness trials --shard), merged")
    t.add_argument("--shards", type=int, required=True)
    t.add_argument("--out", required=True, type=Path)
    t.add_argument("trials", nargs="+", help="the `harness trials` options, after --")
    opts = p.parse_args(argv)
    if opts.shards < 1:
        p.error("--shards must be at least 1")
    n = opts.shards
    with client(opts) as c, tempfile.TemporaryDirectory() as tmp:
        if opts.job == "map":
            futures = [c.submit(map_shard, opts.task, i, n, opts.generate, pure=False)
                       for i in range(n)]
            files = []
            for i, data in enumerate(gather(c, futures, "map")):
                files.append(Path(tmp) / f"shard{i}.ftmap")
                files[-1].write_bytes(data)
            opts.out.parent.mkdir(parents=True, exist_ok=True)
            print(run_tool([tool("ftmap"), "merge", *map(str, files), "--out", str(opts.out)],
                           cwd=ROOT), end="")
        else:
            if any(a.startswith("--shard") or a.startswith("--out") for a in opts.trials):
                p.error("give --out before --, and no --shard: the script sets them per shard")
            # One trial at a time per Dask thread unless the options say otherwise.
            args = opts.trials if "--jobs" in opts.trials else [*opts.trials, "--jobs", "1"]
            futures = [c.submit(trials_shard, args, i, n, pure=False) for i in range(n)]
            files = []
            for i, text in enumerate(gather(c, futures, "campaign")):
                files.append(Path(tmp) / f"shard{i}.json")
                files[-1].write_text(text)
            print(run_tool([tool("harness"), "merge", *map(str, files), "--out", str(opts.out)],
                           cwd=ROOT), end="")


if __name__ == "__main__":
    main()
