"""`hmblur sweep`: `hmblur compare` over a grid of scenes, times, shutters, sizes, reference
samples, seeds and variants, run on Dask, written as one tidy table with plots."""
from __future__ import annotations

from world import limits
from viewer.cli import args as cliargs

DEFAULT_WORKERS = 1


def register(sub):
    p = sub.add_parser("sweep", help="compare over a grid of scenes, times, shutters, sizes "
                       "and variants, on Dask; one table", description="Run `hmblur compare` "
                       "for every cell of SWEEP.toml (scene x time x shutter x size x samples "
                       "x seed; each cell's reference shared by its variants) on a Dask "
                       "cluster, and write DIR/table.csv, DIR/table.parquet, DIR/plots/*.png "
                       "and DIR/summary.md. Finished cells are kept in DIR/cells and skipped "
                       "when the sweep is run again (docs/sweeps.md).")
    p.add_argument("sweep", metavar="SWEEP.toml", help="the sweep file (docs/sweeps.md)")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="output folder (made if missing; holds the finished cells; a file of "
                        "yours there is never replaced: docs/sweeps.md)")
    p.add_argument("--workers", default=None, metavar="N",
                   help="local worker processes, one thread each, at most one per core "
                        f"(default {DEFAULT_WORKERS}: one worker keeps every core busy; on 2 "
                        "cores docs/sweeps/small.toml took 7.5 s with one, 10.9 s with two; "
                        "0: every cell in this process, without Dask)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="a running Dask scheduler (tcp://host:8786) whose workers have the "
                        "project installed, instead of a local cluster")
    p.add_argument("--images", action="store_true",
                   help="also write each cell's images (variants, reference, regions, a "
                        "labelled strip) under DIR/images")
    p.add_argument("--timing", action="store_true",
                   help="add frame_ms: the median of 5 warm frames of each variant (each "
                        "timed cell alone on its machine: one local worker; on a scheduler, "
                        "the workers that declare the resource timer)")
    p.set_defaults(run=run)


def run(args) -> int:
    from viewer.io.sidecar import version
    from viewer.sweep.run import run_sweep
    from viewer.sweep.spec import load_sweep
    spec = load_sweep(args.sweep)
    out = cliargs.check_output_dir(args.out, "--out")
    if args.workers is not None and args.scheduler is not None:
        raise cliargs.UserError("--workers and --scheduler: give one (the scheduler's "
                                "cluster has its own workers)")
    workers = DEFAULT_WORKERS if args.workers is None else \
        cliargs.parse_int("--workers", args.workers, 0, limits.MAX_LOCAL_WORKERS)
    if args.timing and workers > 1:
        raise cliargs.UserError(f"--timing with --workers {workers}: a timed cell has its "
                                "machine's cores to itself, so cells run one at a time: give "
                                "--workers 1 (or 0)")
    facts = run_sweep(spec, out, version(), workers, args.scheduler, args.images, args.timing)
    print(f"{out}: table.csv, table.parquet, summary.md, plots/ ({facts['total']} cells, "
          f"{facts['failed']} failed)")
    return 0
