"""The ``granstokes`` command: a thin layer over the library.

Every error from bad input is one line on stderr naming the parameter and its valid range, with
exit status 2, raised before any computation or file is written.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


from .rheology import Friction, finite, require
from .scales import UNITS
from .solver import Numerics, Solution, check_times, solve_speed, solve_stress
from compare.cli import register as compare_register
from dem.cli import register as dem_register


class OneLineParser(argparse.ArgumentParser):
    """argparse that reports errors on a single line."""

    def error(self, message):
        self.exit(2, f"granstokes: error: {message}\n")


def _friction_and_case(args) -> tuple[Friction, str, float]:
    fr = Friction(args.mu_s, args.mu_d)
    if args.mu_w is not None:
        return fr, "stress", fr.check_mu_w(args.mu_w)
    if args.mu_w_tilde is not None:
        return fr, "stress", fr.mu_w_from_tilde(args.mu_w_tilde)
    require(finite(args.u_w) and args.u_w > 0, "u_w", "a finite number > 0", args.u_w)
    return fr, "speed", args.u_w


def run_continuum(args) -> int:
    fr, imposed, value = _friction_and_case(args)
    times = check_times(args.times)
    numerics = Numerics(n_cells=args.n_cells, rtol=args.rtol, method=args.method)
    if args.plot is not None:
        require(args.plot.suffix.lower() == ".png", "--plot", "a file name ending in .png", str(args.plot))
    solve = solve_stress if imposed == "stress" else solve_speed
    sol = solve(fr, value, times, numerics)
    if args.json:
        print(json.dumps(sol.summary()))
    else:
        print(format_table(sol))
    if args.plot is not None:
        plot_profiles(sol, args.plot)
    if args.save is not None:
        sol.save(args.save)
    return 0


def format_table(sol: Solution) -> str:
    lines = [f"imposed {sol.imposed}: mu_s = {sol.friction.mu_s:.6g}, mu_d = {sol.friction.mu_d:.6g}, "
             f"mu_w_inf = {sol.mu_w_inf:.6g}, beta_w = {sol.beta_w:.6g}",
             f"units: {UNITS['tilde_variables']}",
             f"{'t~':>12} {'u~_w':>12} {'mu_w':>12} {'delta/delta_s':>14}"]
    lines += [f"{t:12.4e} {u:12.6f} {m:12.6f} {d:14.6f}" for t, u, m, d in zip(sol.t, sol.u_w, sol.mu_w, sol.delta)]
    st = sol.steady
    lines.append(f"{'steady':>12} {st['u_w']:12.6f} {st['mu_w']:12.6f} {st['delta']:14.6f}")
    return "\n".join(lines)


def plot_profiles(sol: Solution, path: Path) -> None:
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
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)


def run_paper_figures(args) -> int:
    from .figures import paper_figures

    result = paper_figures(args.out)
    names = sorted(k for k in result if k != "timing")
    print(f"wrote the paper's figures into {args.out}: " + ", ".join(names))
    return 0


def run_demo(args) -> int:
    from compare.demo import run_demo as demo

    index = demo(args.out)
    print(f"report: {index.resolve()}")
    return 0


def run_stability(args) -> int:
    from .stability import write_stability
    from .scales import Material

    calibrated = None
    if args.calibration is not None:
        require(args.calibration.is_file(), "--calibration", "an existing metrics.json from granstokes compare",
                str(args.calibration))
        cal = json.loads(args.calibration.read_text())
        calibrated = Material(mu_s=cal["mu_s"], mu_d=cal["mu_d"], I0=cal["I0"], I_convention=cal["I0_convention"])
    result = write_stability(args.out, calibrated)
    counts = result["table"].groupby(["method", "class"]).size().unstack(fill_value=0)
    print(counts.to_string())
    print(f"maps: {', '.join(p.name for p in result['maps'])}; well-posedness: {result['wellposedness'].name}")
    return 0


def add_continuum_parser(sub) -> None:
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
                   help="write continuum_profiles.csv, continuum_series.csv (every step) and continuum.json")
    p.add_argument("--n-cells", type=int, default=Numerics.n_cells, help="mesh cells (default %(default)s)")
    p.add_argument("--rtol", type=float, default=Numerics.rtol, help="time-step tolerance (default %(default)s)")
    p.add_argument("--method", default=Numerics.method, help="time stepper: sdirk4 or tr-bdf2")
    p.set_defaults(func=run_continuum)

    f = sub.add_parser("paper-figures", help="regenerate the paper's figures 1-9 (PNG + CSV)")
    f.add_argument("--out", type=Path, required=True, help="output folder")
    f.set_defaults(func=run_paper_figures)

    s = sub.add_parser("stability", help="stability maps of every method, and the mu(I) well-posedness along the layer")
    s.add_argument("--out", type=Path, required=True, help="output folder")
    s.add_argument("--calibration", type=Path, help="metrics.json of a DEM calibration (mu_s, mu_d, I0, I0_convention)")
    s.set_defaults(func=run_stability)

    d = sub.add_parser("demo", help="the quick continuum-vs-DEM comparison: paper figures, quick DEM presets, report")
    d.add_argument("--out", type=Path, default=Path("demo-out"), help="output folder (default %(default)s)")
    d.set_defaults(func=run_demo)


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(prog="granstokes", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True, parser_class=OneLineParser)
    # subcommands
    add_continuum_parser(sub)
    dem_register(sub)
    compare_register(sub)
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except ValueError as err:
        print(f"granstokes: error: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
