"""`parslip bench`: the benchmark suite (``parslip.studies.bench.suite``) from the command line."""
from __future__ import annotations

import json


def register(sub) -> None:
    b = sub.add_parser("bench", help="measure throughput, start-up, output, exchange and memory on this machine; "
                                     "prints a table, writes JSON")
    b.add_argument("--sizes", type=int, nargs="+", default=[100, 500, 1000],
                   help="contact lengths l to measure, in a (the paper's geometry scaled; default 100 500 1000)")
    b.add_argument("--ranks", type=int, nargs="+", default=None,
                   help="MPI rank counts (default 1 2; with --scaling 1 2 3)")
    b.add_argument("--precision", nargs="+", default=["float64", "float32"], choices=["float64", "float32"])
    b.add_argument("--seconds", type=float, default=4.0, help="wall seconds of stepping per case (default 4)")
    b.add_argument("--quick", action="store_true", help="l = 100 and 500 only, 2 s per case")
    b.add_argument("--no-push", action="store_true", help="skip the whole-process time of run/push.toml")
    b.add_argument("--json", default="bench.json", help="where to write the results (default bench.json)")
    b.add_argument("--scaling", action="store_true",
                   help="instead: time per step at --sizes on --ranks, fit t_step = a N + b H + c (rank counts "
                        "above the machine's cores kept out of the fit), predict l = 2000 on 64 ranks "
                        "(parslip.studies.bench.scaling)")
    b.add_argument("--sweep", action="store_true",
                   help="instead: time an 8-point sweep of the push scene on 1 rank and on 2 (one point per rank), "
                        "warm cache, --repeat times; prints the medians and their ratio "
                        "(parslip.studies.bench.sweep_throughput; target <= 0.55)")
    b.add_argument("--repeat", type=int, default=3, help="with --sweep: repeats of each rank count (default 3)")
    b.set_defaults(func=cmd_bench)


def cmd_bench(args) -> int:
    import sys

    from ..studies.bench import suite
    if args.scaling:
        return _scaling(args)
    if args.sweep:
        from ..studies.bench import sweep_throughput
        res = sweep_throughput.measure(repeat=args.repeat, log=lambda m: print(m, file=sys.stderr, flush=True))
        with open(args.json, "w") as f:
            json.dump(res, f, indent=1)
        print(sweep_throughput.report(res))
        print(f"\n(written to {args.json})")
        return 0
    args.ranks = args.ranks or [1, 2]
    sizes = [s for s in args.sizes if not args.quick or s <= 500]
    seconds = 2.0 if args.quick else args.seconds
    res = suite.run(sizes=sizes, ranks=args.ranks, precisions=args.precision, seconds=seconds,
                    push=None if args.no_push else "run/push.toml",
                    log=lambda m: print(m, file=sys.stderr, flush=True))
    with open(args.json, "w") as f:
        json.dump(res, f, indent=1)
    print(suite.table(res))
    print(f"\n(written to {args.json})")
    return 0


def _scaling(args) -> int:
    """`parslip bench --scaling`: the measured points written to --json, the fit and prediction printed."""
    import os
    import sys

    from ..studies.bench import scaling
    ranks = args.ranks or [1, 2, 3]
    pts = scaling.measure(args.sizes, ranks, seconds=2.0 if args.quick else args.seconds, path=args.json,
                          log=lambda m: print(m, file=sys.stderr, flush=True))
    cores = os.cpu_count() or 1
    scaling.report(pts, ("N", "H", "1"), [r for r in ranks if r > cores], ["2000:64"], "shear", scaling.Cluster())
    from ..io.cache import store_coefficients
    from ..studies.bench import model_check
    coef = model_check.measured(pts, log=lambda m: print(m, file=sys.stderr, flush=True))
    print("\nThe travel model (parslip info) against the measured steps, with this host's coefficients:\n")
    print(model_check.table(model_check.check(pts, coef, cores=cores)))
    if coef.source != "defaults":
        print(f"(coefficients kept for parslip info: {store_coefficients(coef.__dict__)})")
    print(f"\n(written to {args.json})")
    return 0
