"""The paper's figures with the DEM on them: every drive in the paper's rescaled variables (continuum.scales:
t~ = t/t_s, y~ = y/delta_s, u~ = u/U, mu~ = (mu_d - mu)/Dmu), so that a collapse, or its absence, shows at a
glance.  Renders a compare.comparison.Comparison; nothing is computed here but the drawing."""
from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np
from granstokes.continuum.closed_forms import uwall_asymp
from granstokes.continuum.paper.equations import eq
from granstokes.continuum.steady import steady_wall_speed
from matplotlib import colormaps
from matplotlib.figure import Figure

from .rows import Z95
from .scorecard import creep_length
from .style import DEM_COLOUR, MODEL_STYLE, figure_legend, plain_log, suptitle

#: the DEM's plate series are drawn as running means over this fraction of the record, at about POINTS times
SMOOTHING, POINTS = 0.01, 150
HOW_TO_READ = {
    "law_growth": "Left: each drive's layer depth delta_u (u = 5 % of u_w) over its calibrated delta_s against t/t_s, "
                  "log-log: DEM seed means as points (one colour per drive, darker = higher pressure), local mu(I) as "
                  "thin lines. The paper's self-similar regime is a slope of 1/2 (dotted guide) up to t/t_s of order "
                  "1; points before the elastic start (3 shear-wave transits) are left out. Right: the growth "
                  "exponent over its estimator family (compare.families: the depth at 5, 10, 20, 50 % of u_w and the "
                  "profile's moment, from 1, 3 and 10 transits), imposed stresses (circles) and speeds (squares): the "
                  "DEM with its 95 % statistical error, local mu(I) (open markers); a choice with no point is not "
                  "measurable (its row's choices say why). Last column: the primary choice's DEM value with its "
                  "statistical error and, beside it (grey), the family's systematic error (half its range of DEM - "
                  "model).",
    "law_wall": "Left, imposed stresses: the plate speed in the paper's unit U = g delta_s^2/(beta_w nu_g) against "
                "t/t_s; the paper predicts u~_w ~ sqrt(t~) early (dotted guide), then its steady value. Right, imposed "
                "speeds: (mu_w - mu_s)/Dmu against t~/u~_w^2 (the paper's figure 8): a plateau near 1 (mu_w near mu_d) "
                "until t~_mud ~ u~_w^2, then a decay as t^(-1/2) (dotted guide). Points: DEM seed means (running mean "
                f"over {SMOOTHING:.0%} of the record); lines: local mu(I).",
    "law_steady": "Left: steady plate speed u~_w^inf against mu~_w = (mu_d - mu_w)/Dmu: DEM imposed stresses (circles, "
                  "95 % error bars) and imposed speeds (squares, at the DEM's steady friction), the exact steady "
                  f"integral (line) and {eq('Uwall_asymp', named=True)} (dashed). Right: the creep length below "
                  "delta_s against p_w: DEM (points with errors over seeds) and NGF (crosses); local mu(I) has no "
                  "creep.",
    "law_profiles": "Velocity profiles at the snapshot times after the elastic start, u/u_w against the similarity "
                    "variable eta = depth/(2 Dmu sqrt(nu_g t)) (the paper's figure 5): if the layer grows "
                    "self-similarly the curves of every drive and time fall on one.",
}
GUIDE = dict(color="k", lw=0.8, ls=":")
#: the model whose law rows a family panel shows: the one whose curves the figures draw
FAMILY_MODEL = "local"
#: a family panel's marker and horizontal offset per kind of drive
KIND_MARKER = {"stress": ("o", -0.15), "speed": ("s", 0.15), "all": ("D", 0.0)}
#: the creep panel's pressure axis reaches this factor beyond the lowest and highest pressure
PRESSURE_PAD = 1.5
#: a family with no measured choice shows its primary's note, shortened to this many characters
NOTE_CHARS = 240


def _drives(c):
    return [dc for dc in c.drives if dc.predictions and dc.scales is not None]


def _colour(dc, drives):
    """Blues by pressure (darker = higher), spread within a pressure by the imposed value."""
    pressures = sorted({d.dem.spec.p_w for d in drives})
    k = pressures.index(dc.dem.spec.p_w)
    same = sorted({d.dem.spec.load.value for d in drives if d.dem.spec.p_w == dc.dem.spec.p_w})
    shade = 0.4 + 0.5 * (k + same.index(dc.dem.spec.load.value) / max(1, len(same))) / max(1, len(pressures))
    return colormaps["Blues"](min(shade, 0.95))


def _label(dc) -> str:
    spec = dc.dem.spec
    what = f"mu_w {spec.load.mu_w:.3g}" if spec.kind == "stress" else f"u_w {spec.load.u_w:.3g}"
    return f"p_w {spec.p_w:g}, {what}"


def _layer_mean(dc):
    lay = dc.dem.layers.groupby("t").delta_05.mean()
    return lay.index.to_numpy(dtype=float), lay.to_numpy(dtype=float)




def _smoothed(t, y, start: float):
    """The running mean of y(t) from ``start`` on, at about POINTS log-spaced times."""
    keep = t >= max(start, t[t > 0].min())
    tk, yk = np.asarray(t[keep]), np.asarray(y[keep])
    n = max(1, int(SMOOTHING * len(t)))
    smooth = np.convolve(yk, np.ones(n) / n, mode="same")
    pick = np.unique(np.searchsorted(tk, np.geomspace(tk[0], tk[-1], POINTS)).clip(0, len(tk) - 1))
    return tk[pick], smooth[pick]


def _local(dc):
    return next((p for p in dc.predictions if p.model == "local"), dc.predictions[0])


def _finish(fig, axes, title: str, path: Path, ncols: int) -> Path:
    """Legend below the axes, the title, the PNG written."""
    figure_legend(fig, axes, ncols=ncols, fontsize=7)
    suptitle(fig, title)
    fig.savefig(path, dpi=100)
    return path


def _choice_label(e: dict) -> str:
    return e["estimator"] + ("" if e["from_transits"] is None else f", from {e['from_transits']:g}")


def family_panel(ax, rows, what: str) -> None:
    """One law's rows (one per kind) over its estimator family: each measured choice's DEM value with its 95 %
    statistical error and the model's value, then the primary choice with its statistical and systematic errors."""
    rows = rows[rows.choices.map(len) > 0] if len(rows) else rows
    if rows.empty:
        ax.text(0.5, 0.5, "no law row with an estimator family", transform=ax.transAxes, ha="center")
        ax.set_axis_off()
        return
    if not any(np.isfinite(e["dem"]) for choices in rows.choices for e in choices):
        note = textwrap.shorten(str(rows.iloc[0].choices[0]["note"]), NOTE_CHARS, placeholder=" ...")
        ax.text(0.5, 0.5, "\n".join(textwrap.wrap(f"{what}: no choice measured on these drives. {note}", 48)),
                transform=ax.transAxes, ha="center", va="center", fontsize=9)
        ax.set_axis_off()
        return
    labels = [_choice_label(e) for e in rows.iloc[0].choices]
    n = len(labels)
    for r in rows.itertuples():
        marker, off = KIND_MARKER[r.kind]
        shown = [(i, e) for i, e in enumerate(r.choices) if np.isfinite(e["dem"]) and np.isfinite(e["predicted"])]
        if shown:
            x = np.array([i for i, _ in shown]) + off
            ax.errorbar(x, [e["dem"] for _, e in shown], yerr=[Z95 * np.nan_to_num(e["dem_err"]) for _, e in shown],
                        fmt=marker, ms=4, color=DEM_COLOUR, label=f"DEM, imposed {r.kind} (95 % statistical)")
            ax.plot(x, [e["predicted"] for _, e in shown], marker, ms=6, mfc="none", ls="none",
                    color=MODEL_STYLE[r.model]["color"], label=f"{r.model} (the same choice), imposed {r.kind}")
        if np.isfinite(r.dem):
            ax.errorbar(n + off - 0.06, r.dem, yerr=Z95 * np.nan_to_num(r.dem_err), fmt=marker, ms=4,
                        color=DEM_COLOUR)
            if np.isfinite(r.systematic):
                ax.errorbar(n + off + 0.06, r.dem, yerr=r.systematic, fmt="none", ecolor="0.55", elinewidth=4,
                            label="systematic: half the family's range of DEM - model")
    ax.axvline(n - 0.5, color="0.8", lw=0.8)
    ax.set_xticks(range(n + 1), [*labels, "primary: statistical | systematic"], rotation=60, ha="right", fontsize=7)
    ax.set(xlim=(-0.6, n + 0.6), ylabel=what, xlabel="estimator, from (shear-wave transits)",
           title=f"{what} by estimator choice")


def growth_figure(c, out: Path) -> Path:
    drives = _drives(c)
    fig = Figure(figsize=(14, 7), layout="constrained")
    ax, fam = fig.subplots(1, 2, width_ratios=[3, 2])
    for dc in drives:
        sc, colour = dc.scales, _colour(dc, drives)
        t, d = _layer_mean(dc)
        keep = (t >= dc.dem.spec.compared_from) & np.isfinite(d) & (d > 0)
        ax.plot(t[keep] / sc.t_s, d[keep] / sc.delta_s, "o", ms=2.5, color=colour, label=f"DEM {_label(dc)}")
        p = _local(dc)
        tl = p.series.t.to_numpy()
        ax.plot(tl / sc.t_s, p.series.delta_u / sc.delta_s, lw=0.8, color=colour, alpha=0.8)
    x = np.geomspace(1e-3, 1, 20)
    ax.plot(x, np.sqrt(x), label="slope 1/2 (the paper's self-similar growth)", **GUIDE)
    ax.plot([], [], lw=0.8, color="0.4", label="local mu(I) on the DEM's scene (same colours)")
    ax.set(xscale="log", yscale="log", xlabel="t / t_s", ylabel="delta_u / delta_s (calibrated)")
    laws = c.laws
    family_panel(fam, laws[(laws.law == "delta_growth_exponent") & (laws.model == FAMILY_MODEL)] if len(laws) else laws,
                 "growth exponent n")
    return _finish(fig, [ax, fam], "Layer growth in the paper's variables (DEM units; delta_s, t_s from the "
                   "calibration) and its exponent over the estimator family", out / "law_growth.png", 3)


def wall_figure(c, out: Path) -> Path:
    drives = _drives(c)
    fig = Figure(figsize=(12, 6.5), layout="constrained")
    left, right = fig.subplots(1, 2)
    for dc in drives:
        sc, colour, spec = dc.scales, _colour(dc, drives), dc.dem.spec
        s, p = dc.dem.series, _local(dc)
        if spec.kind == "stress":
            t, u = _smoothed(s.t.to_numpy(), s.u_w.to_numpy(), spec.compared_from)
            left.plot(t / sc.t_s, u / sc.U, "o", ms=2, color=colour, label=f"DEM {_label(dc)}")
            left.plot(p.series.t / sc.t_s, p.series.u_w / sc.U, lw=0.8, color=colour)
        else:
            scale = sc.t_s * (spec.load.u_w / sc.U) ** 2
            m = sc.material
            t, mu = _smoothed(s.t.to_numpy(), s.mu_w.to_numpy(), spec.compared_from)
            right.plot(t / scale, (mu - m.mu_s) / (m.mu_d - m.mu_s), "o", ms=2, color=colour,
                       label=f"DEM {_label(dc)}")
            right.plot(p.series.t / scale, (p.series.mu_w - m.mu_s) / (m.mu_d - m.mu_s), lw=0.8, color=colour)
    x = np.geomspace(1e-3, 1, 20)
    left.plot(x, np.sqrt(x), label="slope 1/2", **GUIDE)
    left.set(xscale="log", yscale="log", xlabel="t / t_s", ylabel="u_w / U", title="imposed stress: u~_w(t~)")
    xr = np.geomspace(1, 100, 20)
    right.plot(xr, 1 / np.sqrt(xr), label="slope -1/2", **GUIDE)
    right.set(xscale="log", yscale="log", xlabel="t~ / u~_w^2", ylabel="(mu_w - mu_s) / (mu_d - mu_s)",
              title="imposed speed: mu_w(t) (the paper's figure 8)")
    for axis in (left, right):
        if not axis.lines[:-1]:
            axis.text(0.5, 0.5, "no drive of this kind", transform=axis.transAxes, ha="center")
    return _finish(fig, [left, right], "The plate's response in the paper's variables (points: DEM seed means; "
                   "lines: local mu(I))", out / "law_wall.png", 4)


def steady_figure(c, out: Path) -> Path:
    drives = _drives(c)
    fig = Figure(figsize=(12, 5.5), layout="constrained")
    left, right = fig.subplots(1, 2)
    fr = c.material.friction
    grid = np.linspace(0.02, 0.98, 60)
    mu_grid = fr.mu_d - grid * fr.dmu
    left.plot(grid, [steady_wall_speed(fr, m) for m in mu_grid], color="k", lw=1, label="exact steady integral")
    left.plot(grid, uwall_asymp(fr, grid), color="k", lw=1, ls="--", label=eq("Uwall_asymp"))
    for dc in drives:
        sc, st, colour = dc.scales, dc.dem.steady, _colour(dc, drives)
        if dc.dem.spec.kind == "stress":
            left.errorbar(sc.mu_w_tilde, st["u_w"]["value"] / sc.U, yerr=1.96 * st["u_w"]["stderr"] / sc.U, fmt="o",
                          color=colour, label=f"DEM {_label(dc)}")
        else:
            mu = st["mu_w"]["value"]
            mt = (fr.mu_d - mu) / fr.dmu
            left.errorbar(mt, dc.dem.spec.load.u_w / sc.U, xerr=1.96 * st["mu_w"]["stderr"] / fr.dmu, fmt="s",
                          color=colour, label=f"DEM {_label(dc)}")
        creep = [creep_length(s.depth, s.u_x, sc.delta_s, dc.dem.spec.depth) for s in dc.dem.samples]
        creep = np.array([x for x in creep if np.isfinite(x)])
        if len(creep):
            err = 1.96 * creep.std(ddof=1) / np.sqrt(len(creep)) if len(creep) > 1 else 0.0
            right.errorbar(dc.dem.spec.p_w * (1 + 0.02 * (sc.mu_w_tilde - 0.5)), creep.mean(), yerr=err,
                           fmt="o" if dc.dem.spec.kind == "stress" else "s", color=colour)
        for p in dc.predictions:
            if p.model == "ngf":
                value = creep_length(p.steady.y, p.steady.u, sc.delta_s, dc.dem.spec.depth)
                right.plot(dc.dem.spec.p_w, value, "x", color=MODEL_STYLE["ngf"]["color"], label="NGF")
    left.set(xlabel="mu~_w = (mu_d - mu_w) / (mu_d - mu_s)", ylabel="u~_w^inf = u_w / U", yscale="log",
             title="steady plate speed (the paper's figure 4)")
    pressures = [dc.dem.spec.p_w for dc in drives]
    right.set(xlabel="p_w [rho_p g d]", ylabel="creep length below delta_s [d]", xscale="log",
              title="creep length (local mu(I): none)")
    if pressures:  # at least a factor PRESSURE_PAD each side, one pressure included
        right.set_xlim(min(pressures) / PRESSURE_PAD, max(pressures) * PRESSURE_PAD)
    plain_log(right.xaxis)
    right.plot([], [], "o", color=DEM_COLOUR, label="DEM (circles: stress, squares: speed)")
    return _finish(fig, [left, right], "Steady states against the paper's steady law (calibrated material; DEM units)",
                   out / "law_steady.png", 4)


def profiles_figure(c, out: Path) -> Path:
    drives = _drives(c)
    fig = Figure(figsize=(8, 6.5), layout="constrained")
    ax = fig.subplots()
    for dc in drives:
        sc, colour, inst = dc.scales, _colour(dc, drives), dc.dem.instant
        for k, (t, g) in enumerate(inst.groupby("t")):
            if t < dc.dem.spec.compared_from or t <= 0:
                continue
            g = g[g.depth >= 0].sort_values("depth")
            u_w = float(np.interp(t, dc.dem.series.t, dc.dem.series.u_w))
            eta = g.depth / (2 * sc.dmu * np.sqrt(sc.nu_g * t))
            ax.plot(eta, g.u_x / u_w, color=colour, lw=1, label=f"DEM {_label(dc)}" if k == len(inst.t.unique()) - 1
                    else None)
    ax.set(xlim=(0, 4), ylim=(-0.05, 1.1), xlabel="eta = depth / (2 Dmu sqrt(nu_g t))", ylabel="u / u_w")
    return _finish(fig, [ax], "Velocity profiles against the similarity variable (DEM snapshots after the elastic "
                   "start)", out / "law_profiles.png", 3)


FIGURES = {"law_growth": growth_figure, "law_wall": wall_figure, "law_steady": steady_figure,
           "law_profiles": profiles_figure}
TITLES = {"law_growth": "The paper's law: layer growth", "law_wall": "The paper's law: the plate's response",
          "law_steady": "The paper's law: steady states", "law_profiles": "The paper's law: self-similar profiles"}
