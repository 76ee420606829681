"""The continuum report: the paper's figures regenerated, the steady-state table and every place
where converged numerics disagree with a printed number, as one HTML page (figures beside it)."""
from __future__ import annotations

import html
import json
from pathlib import Path

import numpy as np
import pandas as pd

from granstokes.lib.page import page
from granstokes.lib.provenance import provenance

from ..closed_forms import SELF_SIMILAR_DELTA, UWALL_MUS_PRINTED_B2, WKB, uwall_asymp, uwall_mus
from ..scales import UNITS
from ..solver import solve_speed, solve_stress
from ..steady import steady_wall_speed
from .equations import eq
from .figures import FRICTION, paper_figures


def table_html(df: pd.DataFrame, caption: str) -> str:
    return f"<p><b>{html.escape(caption)}</b></p>" + df.to_html(index=False, justify="left",
                                                                 float_format=lambda v: f"{v:.6g}")


def figure_heading(name: str) -> str:
    """A figure's heading from its name: fig4_steady_wall_speed -> Fig. 4: steady wall speed."""
    number, _, rest = name.partition("_")
    return f"Fig. {number.removeprefix('fig')}: {rest.replace('_', ' ')}"


def steady_table() -> pd.DataFrame:
    fr = FRICTION
    rows = []
    for mt in (0.99, 0.9, 0.5, 0.1, 0.01):
        mu_w = fr.mu_w_from_tilde(mt)
        rows.append({"mu~_w": mt, "mu_w": mu_w, "beta_w": fr.beta(mu_w), "u~_w^inf exact": steady_wall_speed(fr, mu_w),
                     eq("Uwall_asymp"): uwall_asymp(fr, mt), f"{eq('Uwall_muS')} (derived b2)": uwall_mus(fr, mu_w),
                     f"{eq('Uwall_muS')} (printed b2=-5/2)": uwall_mus(fr, mu_w, UWALL_MUS_PRINTED_B2)})
    return pd.DataFrame(rows)


def discrepancies() -> pd.DataFrame:
    """Printed numbers against converged numerics, computed here (nothing hard-coded)."""
    fr = FRICTION
    stress = solve_stress(fr, fr.mu_w_from_tilde(0.9), [1e-4, 1e-3, 1.0])
    speed = solve_speed(fr, 1.334, [1e-4, 1e-3])
    coeff_stress = stress.delta[:2] / (fr.dmu * np.sqrt(stress.t[:2]))
    coeff_speed = speed.delta / (fr.dmu * np.sqrt(speed.t))
    wkb_err = [np.max(np.abs(WKB(fr, stress.mu_w_inf, printed=p).tau(stress.mesh.y, 1.0) - stress.tau[2]))
               for p in (True, False)]
    slow = solve_speed(fr, 0.198, [5 * 0.198**2])  # inside the 1/sqrt(t~) stage, t_mud < t~ < t_muw
    prefactor = (slow.mu_w[0] - fr.mu_s) * np.sqrt(slow.t[0]) / 0.198
    b = 0.01
    exact = steady_wall_speed(fr, fr.mu_s * (1 + b))
    mus_err = [abs(uwall_mus(fr, fr.mu_s * (1 + b), b2) / exact - 1) for b2 in (UWALL_MUS_PRINTED_B2, None)]
    return pd.DataFrame([
        {"item": "nu_g prefactor", "printed": "d/(2 phi Dmu I0) and d/(phi Dmu I0)",
         "numerics / derivation": "factor 2: the only one with U = g delta_s^2/(beta_w nu_g) consistent "
                                  f"with {eq('IreWritten')} (tests/continuum/test_steady_and_scales.py)"},
        {"item": "delta/(Dmu sqrt t~), imposed stress, mu~_w = 0.9", "printed": "4.66",
         "numerics / derivation": f"{coeff_stress.mean():.3f} at t~ = 1e-4..1e-3; erfc gives 2 erfcinv(1e-3) = "
                                  f"{SELF_SIMILAR_DELTA:.3f}"},
        {"item": "delta/(Dmu sqrt t~), imposed speed u~_w = 1.334", "printed": f"3.66 (with {eq('TimeScaleMu')})",
         "numerics / derivation": f"{coeff_speed.mean():.3f} at t~ = 1e-4..1e-3 (same 1e-3 threshold)"},
        {"item": f"{eq('TimeScaleMu')} prefactor of u~_w/sqrt(t~)",
         "printed": f"1/(3.66 Dmu) = {1 / (3.66 * fr.dmu):.2f}",
         "numerics / derivation": f"{prefactor:.2f} (u~_w = 0.198, t~ = 5 u~_w^2); a momentum balance in the tilde "
                                  "variables gives (mu_w - mu_s) ~ Dmu u~_w delta~/t~: Dmu belongs in the numerator"},
        {"item": f"{eq('Uwall_muS')} second-order coefficient", "printed": "-5/2",
         "numerics / derivation": f"2 mu_s/(3 Dmu) - 1/6 = {2 * fr.mu_s / (3 * fr.dmu) - 1 / 6:.3f}; relative error at "
                                  f"beta_w = 0.01: printed {mus_err[0]:.1e}, derived {mus_err[1]:.1e}"},
        {"item": f"{eq('SolutionLONG')} amplitude and Lambda_m", "printed": "y^(-1/8), Lambda_m integrated in dy^",
         "numerics / derivation": f"y^(+1/8) and projection in z; max |tau~ - numerics| at t~ = 1, mu~_w = 0.9: "
                                  f"printed {wkb_err[0]:.1e}, consistent {wkb_err[1]:.1e}"},
    ])


def write_continuum_report(out_dir) -> Path:
    """Write out_dir/index.html with the paper's figures (out_dir/paper-figures) and tables."""
    out = Path(out_dir)
    figs_dir = out / "paper-figures"
    result = paper_figures(figs_dir)
    pngs = {k: Path(v) for k, v in result.items() if k != "timing"}
    steady, notes = steady_table(), discrepancies()
    steady.to_csv(out / "steady_wall_speed.csv", index=False)
    notes.to_csv(out / "paper_discrepancies.csv", index=False)
    body = ["<h1>granstokes: Stokes' first problem with mu(I), continuum side</h1>",
            "<h2>Units and conventions</h2><ul>" + "".join(
                f"<li><b>{html.escape(k)}</b>: {html.escape(v)}</li>" for k, v in UNITS.items()) + "</ul>",
            f"<p>Paper's case: mu_s = tan 21&deg; = {FRICTION.mu_s:.5f}, mu_d = tan 33&deg; = {FRICTION.mu_d:.5f}. "
            f"Computation of the figure set: {result['timing']['compute']['cpu_s']:.2f} s CPU; "
            f"plotting {result['timing']['plot']['cpu_s']:.2f} s.</p>",
            "<h2>Where the numerics disagree with printed numbers</h2>", table_html(notes, "Printed vs computed"),
            "<h2>Steady wall speed</h2>",
            table_html(steady, "u~_w^inf: exact quadrature vs the paper's approximations, "
                               f"{eq('Uwall_asymp', named=True)} and {eq('Uwall_muS', named=True)}"),
            "<h2>The paper's figures, regenerated</h2>"]
    body.append("<p>Every figure is in the paper's dimensionless tilde variables (above); each PNG has its data "
                "beside it as CSV.</p>")
    for name, png in sorted(pngs.items(), key=lambda kv: int(kv[0].partition("_")[0].removeprefix("fig"))):
        body.append(f"<h3>{html.escape(figure_heading(name))}</h3>"
                    f"<img src='{figs_dir.name}/{png.name}' alt='{html.escape(figure_heading(name))}'>")
    index = out / "index.html"
    index.write_text(page("granstokes continuum", "".join(body)))
    (out / "continuum_report.json").write_text(json.dumps(
        {"figures": {k: f"{figs_dir.name}/{v.name}" for k, v in pngs.items()}, "timing": result["timing"],
         "units": UNITS, "provenance": provenance()}, indent=2))
    return index
