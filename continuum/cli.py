"""``granstokes continuum``: solve the paper's problem (imposed wall stress or speed).

Bad input raises ``ValueError`` naming the parameter and its range before any work; the root parser
(granstokes.cli) prints it as one line with exit status 2; a solve that fails (continuum.stepper.StepperFailure,
raised before anything is written) as one line with exit status 1."""
from __future__ import annotations

import json
from pathlib import Path

from granstokes.lib.staging import claim, new_file, staged
from granstokes.lib.validate import finite, output_file, require

#: the CLI's default relative accuracy of every number (both drives; an imposed speed reaches it on 512
#: cells in 2-13 s CPU: bench/RESULTS.md "Imposed speed over its range")
ACCURACY = 1e-6
DEFAULT_CELLS = 64
COMMAND = "continuum"


def _friction_and_case(args):
    from .rheology import Friction

    fr = Friction(args.mu_s, args.mu_d)
    if args.mu_w is not None:
        return fr, "stress", fr.check_mu_w(args.mu_w)
    if args.mu_w_tilde is not None:
        return fr, "stress", fr.mu_w_from_tilde(args.mu_w_tilde)
    require(finite(args.u_w) and args.u_w > 0, "u_w", "a finite number > 0", args.u_w)
    return fr, "speed", args.u_w


def run_continuum(args) -> int:
    from .solver import Numerics, check_times, solve_speed, solve_stress

    fr, imposed, value = _friction_and_case(args)
    times = check_times(args.times)
    numerics = Numerics(n_cells=args.n_cells, rtol=args.rtol, method=args.method)
    accuracy = args.accuracy if args.accuracy is not None else ACCURACY
    from .solver import ACCURACY_RANGE

    require(finite(accuracy) and ACCURACY_RANGE[0] <= accuracy <= ACCURACY_RANGE[1], "--accuracy",
            f"in [{ACCURACY_RANGE[0]:g}, {ACCURACY_RANGE[1]:g}]", accuracy)
    if args.plot is not None:
        output_file(args.plot, "--plot", ".png")
    if args.save is not None:
        claim(args.save, "--save", COMMAND)
    solve = solve_stress if imposed == "stress" else solve_speed
    sol = solve(fr, value, times, numerics, accuracy=accuracy, estimate=True)
    if args.json:
        print(json.dumps(sol.summary()))
    else:
        print(format_table(sol))
    if args.plot is not None:
        plot_profiles(sol, args.plot)
    if args.save is not None:
        with staged(args.save, COMMAND, keep=True) as work:
            sol.save(work, save_stem(sol))
    return 0


def save_stem(sol) -> str:
    """The file stem of a saved solve, one per case, so that saving another case beside it keeps it."""
    case = f"mu_w{sol.mu_w_inf:.6g}" if sol.imposed == "stress" else f"u_w{sol.u_w_imposed:.6g}"
    return f"continuum_{sol.imposed}_{case}_mu_s{sol.friction.mu_s:.6g}_mu_d{sol.friction.mu_d:.6g}"


def format_table(sol) -> str:
    from .scales import UNITS
    from .solver import early_until

    asked = f"accuracy {sol.accuracy:g} reached" if sol.accuracy else "one solve, no accuracy asked"
    lines = [f"imposed {sol.imposed}: mu_s = {sol.friction.mu_s:.6g}, mu_d = {sol.friction.mu_d:.6g}, "
             f"mu_w_inf = {sol.mu_w_inf:.6g}, beta_w = {sol.beta_w:.6g}",
             f"units: {UNITS['tilde_variables']}",
             f"numerics: {sol.numerics.n_cells} cells, order {sol.numerics.order}, {sol.mesh.label}, "
             f"rtol {sol.numerics.rtol:.2g}; {asked}; +- are estimated absolute errors",
             *([f"early times: t~ < {early_until(sol.u_w_imposed, sol.numerics.early_span):.3g} solved on "
                f"{sol.early_mesh.label}, resampled"] if sol.early_mesh is not None else []),
             f"{'t~':>12} {'u~_w':>24} {'mu_w':>24} {'delta/delta_s':>24}"]
    err = sol.errors
    for k, t in enumerate(sol.t):
        cells = [f"{getattr(sol, q)[k]:.9f} +- {err[q][k]:.1e}" if q in err else f"{getattr(sol, q)[k]:.9f}"
                 for q in ("u_w", "mu_w", "delta")]
        lines.append(f"{t:12.4e} " + " ".join(f"{c:>24}" for c in cells))
    st = sol.steady
    lines.append(f"{'steady':>12} {st['u_w']:24.9f} {st['mu_w']:24.9f} {st['delta']:24.9f}  (exact)")
    return "\n".join(lines)


def plot_profiles(sol, path: Path) -> None:
    """tau~, mu~ and u~ profiles at the requested times."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(12, 4), layout="constrained")
    axes = fig.subplots(1, 3, sharey=True)
    for k, t in enumerate(sol.t):
        for ax, field in zip(axes, (sol.tau, sol.mu_tilde, sol.velocity)):
            ax.plot(field[k], sol.mesh.y, label=f"t~ = {t:.3g}")
    for ax, name in zip(axes, ("tau~ = tau/tau_w", "mu~ = (mu_d - mu)/Dmu", "u~ = u/U")):
        ax.set_xlabel(name)
    axes[0].set_ylabel("y~ = y/delta_s")
    axes[0].invert_yaxis()
    axes[-1].legend()
    fig.suptitle(f"imposed {sol.imposed}, mu_w_inf = {sol.mu_w_inf:.4f} (paper's dimensionless variables)")
    with new_file(path) as tmp:
        fig.savefig(tmp, dpi=120, format="png")


def register(sub) -> None:
    """Add the ``continuum`` subcommand to the ``granstokes`` parser."""
    p = sub.add_parser("continuum", help="solve the paper's problem (imposed wall stress or speed)")
    p.add_argument("--mu-s", type=float, required=True, help="static friction mu_s > 0")
    p.add_argument("--mu-d", type=float, required=True, help="dynamic friction mu_d > mu_s")
    case = p.add_mutually_exclusive_group(required=True)
    case.add_argument("--mu-w", type=float, help="imposed wall friction, mu_s < mu_w < mu_d")
    case.add_argument("--mu-w-tilde", type=float, help="imposed (mu_d - mu_w)/(mu_d - mu_s) in (0, 1)")
    case.add_argument("--u-w", type=float, help="imposed wall speed u~_w > 0 (paper's units)")
    p.add_argument("--times", type=float, nargs="+", required=True, help="output times t~ > 0, increasing")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    p.add_argument("--plot", type=Path, help="draw the profiles at the requested times into FILE.png")
    p.add_argument("--save", type=Path, metavar="DIR",
                   help="write STEM_profiles.csv, STEM_series.csv (every step) and STEM.json, STEM naming the case "
                        "(continuum_stress_mu_w0.5_mu_s0.38_mu_d0.64); other cases saved there are kept")
    p.add_argument("--accuracy", type=float, metavar="TOL",
                   help=f"refine until every estimated relative error is below TOL (default {ACCURACY:g})")
    p.add_argument("--n-cells", type=int, default=DEFAULT_CELLS, help="(starting) mesh cells (default %(default)s)")
    p.add_argument("--rtol", type=float, help="time-step tolerance (default: matched to the mesh's space error)")
    p.add_argument("--method", help="time stepper: sdirk4, tr-bdf2 or bdf (default: sdirk4 for an imposed "
                                    "stress, bdf for an imposed speed)")
    p.set_defaults(func=run_continuum)
