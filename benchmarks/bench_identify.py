"""Joint identification on the numerical case: speed, accuracy and a side-by-side
comparison with scipy and pymoo optimisers (examples/numerical_case.toml).

"Measured" = the model with the exact holder–tool joint (the paper's Table 1:
kt 2.1e7 N/m, ct 15 N s/m, kr 1.4e6 N m/rad, cr 3 N m s/rad) at 1–3000 Hz,
step 1 Hz, noise-free unless stated. Prints

1. objective throughput (``JointProblem.evaluate``, one core, 3001 frequencies)
   for population batches of 1, 50, 400 and 2000 points (target ≥ 20 000 /s);
2. a side-by-side table: our GA, SA, PSO and hybrid against scipy
   ``differential_evolution`` and ``dual_annealing`` and pymoo ``GA`` and
   ``PSO`` on the same objective (``JointProblem.evaluate``, log10 space, the
   paper's bounds), first with our paper-default settings and their own
   budgets, then at common budgets counted in points evaluated
   (``JointProblem.nfev``); medians over seeds 0, 1, 2;
3. the paper's Table 1 errors and evaluation costs for reference;
4. the hybrid check: all four parameters within 0.01 % in < 1 s and
   < 20 000 evaluations, seeds 0–9;
5. coverage of the hybrid's 95 % intervals under 1 % complex Gaussian noise.

Run: OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_identify.py [--quick]
(full ≈ 3 min on one core, --quick ≈ 1 min; the thread variables default to 1
here when unset.)
"""

from __future__ import annotations

import os

_THREAD_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
_SET_HERE = [v for v in _THREAD_VARS if v not in os.environ]
for _v in _SET_HERE:  # before numpy is imported: one core unless the caller says otherwise
    os.environ[_v] = "1"

import argparse  # noqa: E402
import platform  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import scipy  # noqa: E402
from scipy.optimize import differential_evolution, dual_annealing  # noqa: E402

from toolpoint.dynamics.assembly import load_assembly  # noqa: E402
from toolpoint.frf import FRF  # noqa: E402
from toolpoint.identification.identify import identify, make_algorithm, model_for, relative_errors  # noqa: E402
from toolpoint.identification.objective import JointProblem  # noqa: E402
from toolpoint.identification.params import PARAMS  # noqa: E402
from toolpoint.errors import IdentifiabilityWarning  # noqa: E402

try:
    import pymoo
    from pymoo.algorithms.soo.nonconvex.ga import GA as PymooGA
    from pymoo.algorithms.soo.nonconvex.pso import PSO as PymooPSO
    from pymoo.config import Config as PymooConfig
    from pymoo.core.problem import Problem as PymooProblem
    from pymoo.optimize import minimize as pymoo_minimize

    PymooConfig.warnings["not_compiled"] = False
except ImportError:  # pragma: no cover - pymoo is the optional "bench" extra
    pymoo = None

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "numerical_case.toml"
FREQ = np.arange(1.0, 3001.0)  # 1–3000 Hz, step 1 Hz
SEEDS = (0, 1, 2)
OURS = ("ga", "sa", "pso", "hybrid")
THIRD_PARTY = ("scipy-de", "scipy-da", "pymoo-ga", "pymoo-pso")
# Paper (Čiča et al.) Table 1, relative error in %; settings from section 4.
PAPER_ERR = {"ga": (0.0016, 10.7, 1.3, 306.7), "sa": (9.5, 2.7, 10.0, 2866.0), "pso": (0.3, 9.33, 49.8, 200.0)}
PAPER_COST = {
    "ga": "population 420 × 2430 generations ≈ 1.02 million evaluations (optimum after 51 generations)",
    "pso": "swarm 120 × 280 iterations ≈ 33 600 evaluations (optimum after 276 iterations)",
    "sa": "T0 300, reannealing interval 50; optimum after 1020 iterations (evaluations not reported)",
}


# --------------------------------------------------------------------------- setup

def load_case():
    asm = load_assembly(EXAMPLE, require_holder_tool=True)
    model = model_for(asm, FREQ)
    exact = asm.holder_tool.as_array()
    measured = FRF(FREQ, model.tool_point(exact), "receptance", "synthetic measurement (exact joint)")
    return model, exact, measured


def machine_header(quick: bool) -> None:
    print("toolpoint identification benchmark" + ("  [--quick]" if quick else ""))
    print(f"  machine : {platform.platform()}, {platform.machine()}, {os.cpu_count()} logical CPUs")
    print(f"  python  : {platform.python_version()}  numpy {np.__version__}  scipy {scipy.__version__}  "
          f"pymoo {pymoo.__version__ if pymoo else 'not installed'}")
    threads = "  ".join(f"{v}={os.environ.get(v)}" + (" (set by script)" if v in _SET_HERE else "")
                        for v in _THREAD_VARS)
    print(f"  threads : {threads}")
    try:
        from threadpoolctl import threadpool_info

        pools = ", ".join(f"{p['internal_api']} {p.get('version') or ''} ×{p['num_threads']}".replace("  ", " ")
                          for p in threadpool_info())
        print(f"  BLAS    : {pools}")
    except ImportError:
        pass
    print(f"  case    : {EXAMPLE.name}, {FREQ.size} frequencies {FREQ[0]:g}–{FREQ[-1]:g} Hz, noise-free, "
          "bounds = the paper's (kt 1e6–1e9, ct 1–300, kr 1e5–1e7, cr 1–300), searched in log10")


# --------------------------------------------------------------------------- 1. throughput

def throughput(quick: bool) -> None:
    f = np.arange(1.0, 3002.0)  # 3001 frequencies (the model excludes 0 Hz)
    asm = load_assembly(EXAMPLE, require_holder_tool=True)
    model = model_for(asm, f)
    print("\n1. Objective throughput — JointProblem.evaluate, one core, "
          f"{f.size} frequencies {f[0]:g}–{f[-1]:g} Hz (target ≥ 20 000 evaluations/s for population batches)")
    prob = JointProblem(model.coupler, model.tool_point(asm.holder_tool.as_array()))
    rng = np.random.default_rng(0)
    min_time = 0.2 if quick else 0.5
    print(f"   {'batch':>6} {'calls':>7} {'best evals/s':>13} {'median evals/s':>15} {'µs/point':>9}  target")
    for batch in (1, 50, 400, 2000):
        X = prob.xl + rng.random((batch, 4)) * (prob.xu - prob.xl)
        prob.evaluate(X)  # warm-up
        rates, calls = [], 0
        for _ in range(5):
            n, t0 = 0, time.perf_counter()
            while True:
                prob.evaluate(X)
                n += 1
                dt = time.perf_counter() - t0
                if dt >= min_time / 5:
                    break
            rates.append(n * batch / dt)
            calls += n
        best, med = max(rates), float(np.median(rates))
        verdict = "(single point, information only)" if batch == 1 else ("ok" if med >= 20000 else "BELOW TARGET")
        print(f"   {batch:6d} {calls:7d} {best:13,.0f} {med:15,.0f} {1e6 / med:9.1f}  {verdict}")


# --------------------------------------------------------------------------- runners
# Each returns (x_log (4,), evaluations used, seconds, objective, stop message).

def quiet_identify(*args, **kwargs):
    """identify() without printing its IdentifiabilityWarnings (the tables count ``r.warnings``)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        return identify(*args, **kwargs)


def run_ours(model, measured, method, seed, budget=None):
    """Our optimiser through ``identify``; ``budget`` None = the method's own default stopping rules.

    At a budget: ``maxfev`` = budget (never exceeded; GA/PSO schedules run over what it affords),
    no iteration cap, the method's default stall test kept."""
    options = None if budget is None else {"maxiter": None, "maxfev": budget}
    r = quiet_identify(model, measured, method, seed=seed, options=options)
    return r.x_log, int(r.nfev), float(r.seconds), float(r.fun), str(r.message).split(";")[0]


def run_scipy_de(prob, budget, seed):
    npop = 15 * prob.n_var  # scipy: popsize × N members
    maxiter = max((budget - npop) // npop, 0)  # init + maxiter generations ≤ budget
    t0 = time.perf_counter()
    res = differential_evolution(lambda X: prob.evaluate(X.T), list(zip(prob.xl, prob.xu)), popsize=15,
                                 maxiter=maxiter, polish=False, vectorized=True, updating="deferred", rng=seed)
    return res.x, time.perf_counter() - t0, f"scipy: {res.message}"


def run_scipy_da(prob, budget, seed):
    # maxiter raised from 1000 so that the evaluation budget (maxfun) is what stops it
    t0 = time.perf_counter()
    res = dual_annealing(prob.evaluate, list(zip(prob.xl, prob.xu)), maxfun=budget, maxiter=10**7, rng=seed)
    msg = " ".join(res.message) if isinstance(res.message, (list, tuple)) else str(res.message)
    return res.x, time.perf_counter() - t0, "scipy: " + msg



if pymoo is not None:
    class PymooJoint(PymooProblem):
        """The same JointProblem for pymoo; the whole population in one vectorised call."""

        def __init__(self, jp: JointProblem):
            super().__init__(n_var=jp.n_var, n_obj=1, xl=jp.xl, xu=jp.xu)
            self.jp = jp

        def _evaluate(self, X, out, *args, **kwargs):
            out["F"] = self.jp.evaluate(X)


def run_pymoo(prob, budget, seed, which):
    algo = PymooGA() if which == "ga" else PymooPSO()  # pymoo defaults: GA pop 100, PSO swarm 25
    t0 = time.perf_counter()
    res = pymoo_minimize(PymooJoint(prob), algo, termination=("n_eval", budget), seed=seed, verbose=False)
    return np.asarray(res.X, float).reshape(-1), time.perf_counter() - t0, "pymoo: n_eval reached"


def run_third_party(model, measured, method, seed, budget):
    prob = JointProblem(model.coupler, measured.values)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if method == "scipy-de":
            x, sec, msg = run_scipy_de(prob, budget, seed)
        elif method == "scipy-da":
            x, sec, msg = run_scipy_da(prob, budget, seed)
        else:
            x, sec, msg = run_pymoo(prob, budget, seed, method.split("-")[1])
    used = prob.nfev
    return x, used, sec, float(prob.evaluate(x)), msg


# --------------------------------------------------------------------------- 2. side by side

def _hit_cap(message: str) -> bool:
    """True when a run stopped on its iteration / evaluation cap (i.e. on the budget)."""
    m = message.lower()
    return "maximum number of" in m or "n_eval" in m


HEAD = (f"   {'method':<10} {'budget':>9} {'evals used':>11} {'seconds':>8} {'objective m/N':>13} "
        + " ".join(f"{k + ' err %':>10}" for k in PARAMS))


def row(name, budget_label, runs, exact, budget=None, notes=None) -> str:
    """Median over seeds of each column separately. A run that stopped on its own
    criterion (convergence, stall) before the budget is marked *n, its stop
    message collected in ``notes``."""
    used = np.median([r[1] for r in runs])
    sec = np.median([r[2] for r in runs])
    fun = np.median([r[3] for r in runs])
    errs = np.median([[relative_errors(10.0 ** r[0], exact)[k] * 100 for k in PARAMS] for r in runs], axis=0)
    line = (f"   {name:<10} {budget_label:>9} {used:11,.0f} {sec:8.2f} {fun:13.3e} "
            + " ".join(f"{e:10.3g}" for e in errs))
    early = [r for r in runs if budget is not None and r[1] < budget and not _hit_cap(r[4])]
    if early and notes is not None:
        notes.append(f"{name}: {len(early)}/{len(runs)} seeds stopped early at "
                     + ", ".join(f"{r[1]:,}" for r in early) + f" evaluations — {early[0][4]}")
        line += f"  *{len(notes)}"
    return line


def side_by_side(model, measured, exact, quick: bool) -> dict:
    ga_seeds = SEEDS[:1] if quick else SEEDS  # the paper-default GA is ~0.9 M evaluations per seed
    print("\n2. Side by side — same objective (JointProblem.evaluate, log10 space, paper bounds), noise-free; "
          f"median over seeds {', '.join(map(str, SEEDS))} of each column")
    print("   A. Our methods with their default (paper) settings and their own budgets")
    print(HEAD)
    own = {}
    for m in OURS:
        seeds = ga_seeds if m == "ga" else SEEDS
        own[m] = [run_ours(model, measured, m, s) for s in seeds]
        note = "" if len(seeds) == len(SEEDS) else f"  (seed {seeds[0]} only in --quick)"
        print(row(m, "default", own[m], exact) + note, flush=True)
    caps = default_caps()
    print("   default caps — " + "; ".join(f"{m}: {c}" for m, c in caps.items()))

    hybrid_evals = int(np.median([r[1] for r in own["hybrid"]]))
    b1 = int(np.ceil(5 * hybrid_evals / 100.0) * 100)
    b2 = 20_000 if quick else 100_000
    for label, budget in (("B", b1), ("C", b2)):
        what = (f"5 × the hybrid's median {hybrid_evals:,} evaluations, rounded up" if label == "B"
                else "a larger budget")
        print(f"\n   {label}. Common budget {budget:,} points ({what}); the hybrid row is its default run "
              "(budget 'own') for reference")
        print(HEAD)
        notes: list[str] = []
        for m in ("ga", "sa", "pso"):
            runs = [run_ours(model, measured, m, s, budget) for s in SEEDS]
            print(row(m, f"{budget:,}", runs, exact, budget, notes), flush=True)
        print(row("hybrid", "own", own["hybrid"], exact))
        for m in THIRD_PARTY:
            if m.startswith("pymoo") and pymoo is None:
                print(f"   {m:<10} skipped: pymoo not installed")
                continue
            runs = [run_third_party(model, measured, m, s, budget) for s in SEEDS]
            print(row(m, f"{budget:,}", runs, exact, budget, notes), flush=True)
        for i, n in enumerate(notes, 1):
            print(f"   *{i} {n}")
    print("   Notes: objective = ‖h(p) − h̄‖₂ over 3000 frequencies (exact joint → ~1e-17, round-off). Our rows: "
          "seconds include identify()'s\n"
          "   confidence-interval step; at a budget our GA/SA/PSO keep their default stall criterion (so may stop "
          "early), run with\n"
          "   maxfev = budget and no iteration cap (GA/PSO schedules span what the budget affords).\n"
          "   scipy DE: popsize 15 (60 members), maxiter = (budget − 60) // 60, tol "
          "0.01 (may stop early),\n"
          "   no polish. dual_annealing: maxfun = budget, maxiter raised to 1e7 so the budget binds; its "
          "L-BFGS-B local searches\n"
          "   (finite-difference gradients) count. pymoo: termination ('n_eval', budget),\n"
          "   checked after each generation (may overshoot by < 1 generation). *n = stopped by its own "
          "convergence/stall criterion before the budget.")
    return own


def default_caps() -> dict:
    ga, pso, sa, hy = (make_algorithm(m) for m in ("ga", "pso", "sa", "hybrid"))
    P = ga.popsize
    ga_cap = P + (ga.maxiter - 1) * (P - max(1, int(round(ga.elite_fraction * P))))
    de = hy.global_stage
    return {
        "ga": f"≤ {ga_cap:,} (pop {P} × {ga.maxiter} gen, stall {ga.stall_iter})",
        "sa": f"{sa.chains} chains × ≤ {sa.maxiter} it + reanneals (stall {sa.stall_iter})",
        "pso": f"{pso.popsize * pso.maxiter:,} (swarm {pso.popsize} × {pso.maxiter} it)",
        "hybrid": f"DE {getattr(de, 'popsize', '?')}×4 members × ≤ {getattr(de, 'maxiter', '?')} gen + "
                  f"least squares from {hy.starts} starts",
    }


# --------------------------------------------------------------------------- 3. paper

def paper_reference(own: dict, exact) -> None:
    print("\n3. The paper's Table 1 (relative error %, numerical case) next to ours with default settings "
          "(median over seeds)")
    print(f"   {'method':<8} {'source':<7} " + " ".join(f"{k + ' %':>10}" for k in PARAMS))
    for m in ("ga", "sa", "pso"):
        print(f"   {m:<8} {'paper':<7} " + " ".join(f"{e:10.4g}" for e in PAPER_ERR[m]))
        ours = np.median([[relative_errors(10.0 ** r[0], exact)[k] * 100 for k in PARAMS] for r in own[m]], axis=0)
        print(f"   {'':<8} {'ours':<7} " + " ".join(f"{e:10.3g}" for e in ours))
    print("   Paper costs: " + "\n                ".join(f"{m.upper()}: {c}" for m, c in PAPER_COST.items()))


# --------------------------------------------------------------------------- 4. hybrid check

def hybrid_check(model, measured, exact) -> None:
    print("\n4. Hybrid check — all four parameters within 0.01 %, < 1 s, < 20 000 evaluations (seeds 0–9)")
    print(f"   {'seed':>4} {'evals':>7} {'seconds':>8} {'max err %':>10}  " + " ".join(f"{k + ' %':>9}" for k in PARAMS)
          + "  verdict")
    worst_err, worst_s, worst_n, ok_all = 0.0, 0.0, 0, True
    for s in range(10):
        r = quiet_identify(model, measured, "hybrid", seed=s)
        e = relative_errors(r.x, exact)
        m = max(e.values())
        ok = m < 1e-4 and r.seconds < 1.0 and r.nfev < 20000
        ok_all &= ok
        worst_err, worst_s, worst_n = max(worst_err, m), max(worst_s, r.seconds), max(worst_n, r.nfev)
        print(f"   {s:4d} {r.nfev:7d} {r.seconds:8.3f} {m * 100:10.2e}  "
              + " ".join(f"{e[k] * 100:9.1e}" for k in PARAMS) + f"  {'PASS' if ok else 'FAIL'}")
    print(f"   {'PASS' if ok_all else 'FAIL'}: worst max error {worst_err * 100:.2e} % (limit 0.01 %), "
          f"worst time {worst_s:.3f} s (limit 1 s), worst evaluations {worst_n:,} (limit 20 000)")


# --------------------------------------------------------------------------- 5. noise

def noise_coverage(model, measured, exact, trials: int) -> None:
    peak = float(np.abs(measured.values).max())
    sigma = 0.01 * peak
    print(f"\n5. Noise — 1 % complex Gaussian noise, σ = 0.01·max|h| = {sigma:.3e} m/N, (N(0,1)+iN(0,1))/√2; "
          f"{trials} trials (noise seed 1000+t, hybrid seed t)")
    inside = np.zeros((trials, 4), bool)
    infinite = np.zeros((trials, 4), bool)
    err = np.zeros((trials, 4))
    ratio = np.zeros((trials, 4))
    fun_rel, secs, evals, warned = [], [], [], 0
    for t in range(trials):
        rng = np.random.default_rng(1000 + t)
        noise = sigma * (rng.standard_normal(FREQ.size) + 1j * rng.standard_normal(FREQ.size)) / np.sqrt(2)
        r = quiet_identify(model, FRF(FREQ, measured.values + noise), "hybrid", seed=t)
        for i, k in enumerate(PARAMS):
            lo, hi = r.ci95[k]
            inside[t, i] = lo <= exact[i] <= hi
            infinite[t, i] = not (np.isfinite(hi) and lo > 0)
            err[t, i] = abs(r.x[i] - exact[i]) / exact[i]
            ratio[t, i] = hi / lo if lo > 0 else np.inf
        fun_rel.append(r.fun / (sigma * np.sqrt(FREQ.size)))  # ≈ 1 when the fit reaches the noise floor
        secs.append(r.seconds)
        evals.append(r.nfev)
        warned += bool(r.warnings)
    cov = inside.mean()
    print(f"   {'':<22} " + " ".join(f"{k:>9}" for k in PARAMS) + f" {'all':>9}")
    print(f"   {'coverage of 95 % CI':<22} " + " ".join(f"{c * 100:8.1f}%" for c in inside.mean(0))
          + f" {cov * 100:8.1f}%")
    print(f"   {'median rel. error %':<22} " + " ".join(f"{e:9.3g}" for e in np.median(err, 0) * 100))
    print(f"   {'median CI hi/lo':<22} " + " ".join(f"{q:9.4g}" for q in np.median(ratio, 0)))
    print(f"   {'infinite intervals':<22} " + " ".join(f"{n:9d}" for n in infinite.sum(0)))
    print(f"   objective / (σ√F): median {np.median(fun_rel):.3f} (≈ 1 at the noise floor), "
          f"max {np.max(fun_rel):.3f}; hybrid {np.median(evals):,.0f} evaluations, {np.median(secs):.3f} s "
          f"(medians); {warned}/{trials} trials with identifiability warnings")
    print(f"   {'PASS' if cov >= 0.90 else 'FAIL'}: {inside.sum()}/{inside.size} (parameter, trial) pairs inside the "
          f"95 % interval = {cov * 100:.1f} % (target ≥ 90 %)")


# --------------------------------------------------------------------------- main

def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help="smaller budgets (20 000 instead of 100 000), paper GA on seed 0 only, 10 noise trials")
    args = ap.parse_args(argv)
    t_start = time.perf_counter()
    machine_header(args.quick)
    model, exact, measured = load_case()
    throughput(args.quick)
    own = side_by_side(model, measured, exact, args.quick)
    paper_reference(own, exact)
    hybrid_check(model, measured, exact)
    noise_coverage(model, measured, exact, 10 if args.quick else 50)
    print(f"\ntotal {time.perf_counter() - t_start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
