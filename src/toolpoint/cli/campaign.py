"""``toolpoint campaign synth|run|learn`` — the experimental campaign (paper section 5)."""

from __future__ import annotations

from pathlib import Path

from ..errors import InputError


def register(sub) -> None:
    p = sub.add_parser("campaign", help="many tools on one spindle–holder: synthesise, identify all, learn ANFIS")
    cs = p.add_subparsers(dest="campaign_command", required=True, metavar="STEP")

    s = cs.add_parser("synth", help="write a realistic synthetic campaign (truth law documented, kept in truth/)")
    s.add_argument("out_dir")
    s.add_argument("--n", type=int, default=178, help="number of tool assemblies (default 178)")
    s.add_argument("--seed", type=int, default=0)
    s.add_argument("--noise", type=float, default=0.01, help="tool-point FRF noise, fraction of the peak (default 0.01)")
    s.add_argument("--blank-noise", type=float, default=5e-5,
                   help="noise of the blank FRFs for inverse RCSA, fraction of the peak (default 5e-5)")
    s.add_argument("--format", choices=("csv", "uff"), default="csv", help="FRF file format (default csv)")
    s.set_defaults(func=_synth)

    r = cs.add_parser("run", help="identify the joint of every measurement (resumable)")
    r.add_argument("campaign_dir")
    r.add_argument("--out", required=True, help="results folder (identified.csv)")
    r.add_argument("--method", help="hybrid, ga, sa, pso or de (default: campaign.toml, else hybrid)")
    r.add_argument("--workers", type=int, help="local processes (default: all cores)")
    r.add_argument("--dask", metavar="ADDRESS", help="run on an existing Dask scheduler, e.g. tcp://10.0.0.5:8786")
    r.add_argument("--seed", type=int, default=0)
    r.set_defaults(func=_run)

    lp = cs.add_parser("learn", help="ANFIS per target on (diameter_mm, overhang_mm), with baselines")
    lp.add_argument("results_dir")
    from ..campaign.learn import add_arguments

    add_arguments(lp)
    lp.set_defaults(func=_learn)


def _synth(args) -> int:
    from ..campaign.synth import synthesise

    if args.n < 1:
        raise InputError("must be ≥ 1", file="command line", field="--n")
    if args.noise < 0 or args.blank_noise < 0:
        raise InputError("noise levels must be ≥ 0", file="command line", field="--noise")
    out = Path(args.out_dir)
    if out.exists() and any(out.iterdir()):
        raise InputError("folder exists and is not empty", file=out, field="OUT_DIR")
    s = synthesise(out, n=args.n, seed=args.seed, noise=args.noise, blank_noise=args.blank_noise, fmt=args.format)
    print(f"wrote a campaign of {s['n']} tools to {out} (truth in {out / 'truth'}, not read by the pipeline)")
    return 0


def _run(args) -> int:
    from ..campaign.run import run_campaign

    if args.workers is not None and args.workers < 1:
        raise InputError("must be ≥ 1", file="command line", field="--workers")
    r = run_campaign(args.campaign_dir, args.out, method=args.method, workers=args.workers, dask=args.dask,
                     seed=args.seed)
    print(f"{r['ok']} identified, {r['failed']} failed, {r['skipped']} already done; {r['seconds']:.1f} s → {r['path']}")
    return 0 if r["failed"] == 0 else 1


def _learn(args) -> int:
    from ..campaign.learn import run_cli

    return run_cli(args)
