"""The continuum-vs-DEM report: renders a compare.comparison.Comparison (nothing is computed here but
the figures' drawing): metrics.json, CSV tables, PNG figures and the pages of compare.experiment's shell, index.html
(after the verdict and the findings: the paper's laws, the conclusions, the calibration and the figures across
drives), scorecard.html (the scorecard, its table and chart) and drives.html (the drives, their scene checks and
figures)."""
from __future__ import annotations

import html
import re
from pathlib import Path, PurePath

import numpy as np
import pandas as pd
from granstokes.continuum import ngf
from granstokes.continuum.calibration import LINEAR_I_MAX, mu_law
from granstokes.continuum.scales import UNITS
from granstokes.continuum.steady import steady_mu
from matplotlib import colormaps
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.ticker import LogLocator

from . import law_figures
from .analysis import nearest_frame
from .calibrate import PUBLISHED
from .comparison import Comparison, DriveComparison
from .experiment import CSV_FLOAT, DRIVES, SCORECARD, FigureFile, Section, table
from .laws import GROWTH_END
from .metrics import metrics  # noqa: F401  (the experiment's report module renders its metrics too)
from .rows import UNSCORED, Z95, critical, tally
from .scorecard import MODEL_UNSTEADY, T90_WINDOW, depth_needed
from .style import DEM_COLOUR, DRIVE_MARKERS, MODEL_STYLE, figure_legend, plain_log, suptitle
from .words import MODEL_WORDS, VERDICT_COLOUR, fmt, fmt_band, fmt_cell, words

PUBLISHED_COLOURS = ("C6", "C8", "C9")  # published laws beside the calibration
SIGMA_CLIP = 20.0                   # the scorecard figure's bars stop here (the value is written on the bar)
FIELD_LABELS = {"u_x": "u [sqrt(g d)]", "phi": "phi", "p": "p = sigma_yy [rho_p g d]", "tau": "tau [rho_p g d]",
                "mu": "mu = tau/p", "I_dem": "I_dem = |du/dy| d/sqrt(p/rho_p)"}
T_LABEL, DEPTH_LABEL = "t [sqrt(d/g)]", "depth below the plate [d]"
RESPONSE_LABEL = {"u_w": "u_w [sqrt(g d)]", "mu_w": "mu_w = <tau_w>/<p>"}


def slug(label: str) -> str:
    """A file-name stem of a label: letters and digits, every other run of characters one underscore."""
    return re.sub(r"[^0-9A-Za-z]+", "_", label).strip("_")


def display_label(label: str, labels=()) -> str:
    """A drive's label for a reader, "run: drive" ("gs-smoke: speed"): the run folder's name, with as many
    parent folders as keep it apart from the other ``labels``."""
    def parts(x):
        path = PurePath(x)
        return [q for q in path.parent.parts if q not in ("/", ".")], path.name

    run, name = parts(label)
    others = [parts(x) for x in labels if x != label]
    for k in range(1, len(run) + 1):
        if all(o[1] != name or o[0][-k:] != run[-k:] for o in others):
            return f"{'/'.join(run[-k:])}: {name}"
    return f"{'/'.join(run)}: {name}" if run else name


def display_labels(c: Comparison) -> dict:
    """Every drive label of ``c`` (and of its scorecard) to its display_label."""
    labels = list(dict.fromkeys([dc.label for dc in c.drives] + list(c.scorecard.rows.get("drive", []))))
    return {x: display_label(x, labels) for x in labels}


def _running(s: pd.Series, n: int) -> pd.Series:
    return s.rolling(max(1, n), center=True, min_periods=1).mean()


# --- figures -----------------------------------------------------------------------------------------

def drive_figure(dc: DriveComparison, bands: dict, out: Path, name: str | None = None) -> Path:
    """The free response against time, delta_u(t), and the steady velocity profile (linear and log);
    ``name``: the drive's display label."""
    g, spec, resp = dc.dem, dc.dem.spec, dc.dem.response
    fig = Figure(figsize=(12, 8.5), layout="constrained")
    ax = fig.subplots(2, 2).ravel()
    s = g.series
    n = int(T90_WINDOW * len(s))
    smooth = _running(s[resp], n)
    ax[0].plot(s.t, smooth, color=DEM_COLOUR, lw=1.8, label=f"DEM, running mean ({T90_WINDOW:.0%} of the record)")
    if spec.seeds > 1:
        ax[0].fill_between(s.t, _running(s[f"{resp}_lo"], n), _running(s[f"{resp}_hi"], n), color=DEM_COLOUR,
                           alpha=0.25,
                           label=f"DEM, 95 % band of the {spec.seeds}-seed mean per output "
                                 "(edges: running mean)")
    for p in dc.predictions:
        ax[0].plot(p.series.t, p.series[resp], label=p.label, **MODEL_STYLE[p.model])
        if (dc.label, p.model) in bands:
            b = bands[(dc.label, p.model)]
            ax[0].fill_between(b.t, b.lo, b.hi, color=MODEL_STYLE[p.model]["color"], alpha=0.15, lw=0)
    lo, hi = np.nanpercentile(smooth, [1, 99])
    top = max(hi, *(np.nanpercentile(p.series[resp], 99) for p in dc.predictions)) if dc.predictions else hi
    pad = 0.1 * (top - min(lo, 0))
    ax[0].set(xlabel=T_LABEL, ylabel=RESPONSE_LABEL[resp], ylim=(min(lo, 0) - pad, top + pad),
              title=f"free response: {RESPONSE_LABEL[resp]}")
    ax[0].ticklabel_format(useOffset=False)
    ax[1].plot(g.delta.t, g.delta.delta_u, "o", ms=3, color=DEM_COLOUR, label="DEM delta_u (coarse-grained u)")
    for p in dc.predictions:
        ax[1].plot(p.series.t, p.series.delta_u, label=p.label, **MODEL_STYLE[p.model])
    if dc.predictions:
        ax[1].axhline(dc.predictions[0].steady.delta_s, color="k", lw=0.7, ls=":", label="delta_s (calibrated)")
    ax[1].set(xscale="log", yscale="log", xlabel=T_LABEL, ylabel="delta_u [d] (u = 5 % of u_w)",
              title="layer thickness")
    plain_log(ax[1].yaxis)
    for axis in ax[:2]:  # the elastic start: the load is carried down by a shear wave, not compared
        axis.axvline(spec.transit_time, color="0.3", lw=0.8, ls="--", label="shear-wave transit over the bed")
        axis.axvspan(0, spec.compared_from, color="0.85", alpha=0.5, lw=0, label="elastic start (not compared)")
    p = g.steady_profile
    spread = f"{spec.seeds} seeds" if spec.seeds > 1 else "the window's frames"
    for a_, scale in ((ax[2], "linear"), (ax[3], "log")):
        a_.plot(p.u_x.clip(lower=1e-6) if scale == "log" else p.u_x, p.depth, color=DEM_COLOUR, lw=1.8,
                label="DEM steady window")
        a_.fill_betweenx(p.depth, p.u_x_lo.clip(lower=1e-6), p.u_x_hi.clip(lower=1e-6), color=DEM_COLOUR, alpha=0.25,
                         label=f"DEM steady window, band over {spread}")
        for pr in dc.predictions:
            u = pr.steady.u.clip(1e-6) if scale == "log" else pr.steady.u
            a_.plot(u, pr.steady.y, label=pr.label, **MODEL_STYLE[pr.model])
        a_.set(xscale=scale, xlabel="u [sqrt(g d)]" + (" (log: creep)" if scale == "log" else ""),
               ylabel=DEPTH_LABEL, ylim=(spec.depth, 0), title=f"steady velocity ({scale})")
        if scale == "log":
            a_.set_xlim(1e-4 * max(p.u_x.max(), 1e-6), 2 * max(p.u_x.max(), 1e-6))
    figure_legend(fig, ax)
    imposed = (f"tau_w = {spec.load.tau_w:.4g} rho_p g d" if spec.kind == "stress"
               else f"u_w = {spec.load.u_w:.4g} sqrt(g d)")
    suptitle(fig, f"{name or display_label(g.label)} – imposed {spec.kind} ({imposed}), p_w = {spec.p_w:g} rho_p g d; "
             "DEM units")
    path = out / f"drive_{slug(name or g.label)}.png"
    fig.savefig(path, dpi=100)
    return path


def profiles_figure(dc: DriveComparison, material, out: Path, name: str | None = None) -> Path:
    """Steady-window profiles (bands over seeds or frames) with the local model's steady state."""
    g, spec = dc.dem, dc.dem.spec
    p = g.steady_profile
    fig = Figure(figsize=(15, 4.6), layout="constrained")
    axes = fig.subplots(1, 6, sharey=True)
    spread = f"{spec.seeds} seeds" if spec.seeds > 1 else "the window's frames"
    for ax, f in zip(axes, FIELD_LABELS):
        ax.plot(p[f], p.depth, color=DEM_COLOUR, label="DEM steady window")
        ax.fill_betweenx(p.depth, p[f"{f}_lo"], p[f"{f}_hi"], color=DEM_COLOUR, alpha=0.25,
                         label=f"DEM, band over {spread}")
        ax.set_xlabel(FIELD_LABELS[f])
    local = dc.predictions[0].steady
    z = np.linspace(0, spec.depth, 200)
    style = MODEL_STYLE["local"]
    axes[0].plot(local.u, local.y, **style, label="local mu(I), steady")
    axes[1].axvline(material.phi, **style)
    axes[2].plot(spec.p_w + material.phi * material.rho_p * material.g * z, z, **style)
    axes[3].axvline(local.mu_w * spec.p_w, **style)
    mu = steady_mu(material.friction, local.mu_w, z / local.delta_s)
    axes[4].plot(mu, z, **style)
    axes[5].plot(material.friction.I_of_mu(mu, material.I0), z, **style)
    axes[1].set_xlim(0, 1)
    axes[4].set_xlim(0, 1)
    axes[5].set(xscale="log", xlim=(1e-5, 2))
    axes[5].xaxis.set_major_locator(LogLocator(numticks=4))
    axes[0].set(ylabel=DEPTH_LABEL, ylim=(spec.depth, 0))
    figure_legend(fig, axes[:1], ncols=3)
    suptitle(fig, f"{name or display_label(g.label)} – steady-window profiles (Lucy kernel, width in metrics.json); "
             "DEM units, I in the DEM convention")
    path = out / f"profiles_{slug(name or g.label)}.png"
    fig.savefig(path, dpi=100)
    return path


def transient_figure(dc: DriveComparison, material, out: Path, name: str | None = None) -> Path:
    """u, mu and I against depth at a few snapshot times (colour: time): DEM (seed-averaged) solid, local
    model dashed; one profile per time, the frame nearest it."""
    g, spec = dc.dem, dc.dem.spec
    vel = dc.predictions[0].profiles
    fig = Figure(figsize=(12, 5), layout="constrained")
    axes = fig.subplots(1, 3, sharey=True)
    times = g.snapshots
    for k, t in enumerate(times):
        dem, cont = nearest_frame(g.instant, t).sort_values("depth"), nearest_frame(vel, t).sort_values("depth")
        model = {"u_x": cont.u, "mu": cont.mu,
                 "I_dem": material.friction.I_of_mu(cont.mu.clip(upper=material.mu_d - 1e-9), material.I0)}
        early = " (elastic start: not compared)" if t < spec.compared_from else ""
        colour = colormaps["viridis"](0.9 * k / max(1, len(times) - 1))
        for ax, f in zip(axes, model):
            ax.plot(dem[f], dem.depth, color=colour, label=f"t = {t:.3g}{early}")
            ax.plot(model[f], cont.depth, color=colour, ls="--")
    for ax, f in zip(axes, ("u_x", "mu", "I_dem")):
        ax.set_xlabel(FIELD_LABELS[f])
    axes[1].set_xlim(0, 1)
    axes[2].set(xscale="log", xlim=(1e-5, 2))
    axes[0].set(ylabel=DEPTH_LABEL, ylim=(spec.depth, 0))
    handles, labels = axes[0].get_legend_handles_labels()
    handles += [Line2D([], [], color="k"), Line2D([], [], color="k", ls="--")]
    labels += ["DEM (solid)", "local mu(I) (dashed)"]
    fig.legend(handles, labels, loc="outside lower center", ncols=4, fontsize=8, frameon=False)
    suptitle(fig, f"{name or display_label(g.label)} – transient profiles at snapshot times t [sqrt(d/g)] (DEM units, "
             f"I in the DEM convention); shear-wave transit {spec.transit_time:.3g}, compared from "
             f"{spec.compared_from:.3g}")
    path = out / f"transient_{slug(name or g.label)}.png"
    fig.savefig(path, dpi=100)
    return path


def _law_band(cal, I, q=(2.5, 97.5)):
    reps = np.array([mu_law(I, a, b, c) for a, b, c in
                     zip(cal.replicates["mu_s"], cal.replicates["mu_d"], cal.replicates["I0_dem"])])
    return np.percentile(reps, q, axis=0)


def fluidity_figure(dc: DriveComparison, material, out: Path, name: str | None = None) -> Path:
    """The steady fluidity g = |du/dy|/mu against depth: the DEM's (coarse-grained), NGF's, and the local
    g_loc(mu, p) of the same stress (zero below delta_s)."""
    g, spec = dc.dem, dc.dem.spec
    p = g.steady_profile
    fig = Figure(figsize=(6.5, 5), layout="constrained")
    ax = fig.subplots()
    with np.errstate(divide="ignore", invalid="ignore"):
        dem_g = p.gamma_dot_dem / p.mu
    ax.semilogx(dem_g.where(dem_g > 0), p.depth, color=DEM_COLOUR, lw=1.8, label="DEM: |du/dy|/mu (coarse-grained)")
    for pr in dc.predictions:
        if pr.steady.g is not None:
            ax.semilogx(pr.steady.g, pr.steady.y, label=pr.label, **MODEL_STYLE[pr.model])
    z = np.linspace(0, spec.depth, 400)
    pz = spec.p_w + material.phi * material.rho_p * material.g * z
    local = ngf.local_fluidity(material, ngf.NonlocalFluidity(A=0.0), dc.predictions[0].steady.mu_w * spec.p_w / pz,
                               pz)
    ax.semilogx(np.where(local > 0, local, np.nan), z, label="local g_loc (rigid below delta_s)",
                **MODEL_STYLE["local"])
    ax.set(xlabel="fluidity g = |du/dy|/mu [sqrt(g/d)]", ylabel=DEPTH_LABEL, ylim=(spec.depth, 0))
    suptitle(fig, f"{name or display_label(g.label)} – steady fluidity; DEM units")
    figure_legend(fig, [ax], ncols=2)
    path = out / f"fluidity_{slug(name or g.label)}.png"
    fig.savefig(path, dpi=100)
    return path


def calibration_figure(c: Comparison, out: Path) -> Path:
    """mu(I) and phi(I): the law with its 95 % bootstrap band; blind comparison: the plane-shear points
    it was measured on and the drives' steady pairs over it as a test (seed bands as error bars);
    published values beside it.  In-drive fit: the pairs and the fit through them."""
    cal, pairs, names = c.calibration, c.pairs, display_labels(c)
    fig = Figure(figsize=(12, 6.2), layout="constrained")
    a, b = fig.subplots(1, 2)
    lo_I = min(pairs.I_dem[pairs.I_dem > 0].min(), cal.points.I.min() if len(cal.points) else 1.0)
    I = np.geomspace(max(lo_I, 1e-4), max(pairs.I_dem.max(), cal.points.I.max() if len(cal.points) else 0) * 1.5, 200)
    what = "independent law (plane shear)" if c.blind else "fit on the drives (not a prediction)"
    a.plot(I, mu_law(I, cal.mu_s, cal.mu_d, cal.I0_dem), "k-",
           label=f"{what}: mu_s {cal.mu_s:.3f}, mu_d {cal.mu_d:.3f}, I0_dem {cal.I0_dem:.3f}")
    a.fill_between(I, *_law_band(cal, I), color="0.6", alpha=0.35, label="95 % bootstrap band")
    lin = I[I <= LINEAR_I_MAX]
    a.plot(lin, cal.mu_1 + cal.b * lin, color="0.3", ls="--", lw=0.9, label=f"linear: {cal.mu_1:.3f} + {cal.b:.2f} I")
    if c.blind:
        pts = cal.points
        a.errorbar(pts.I, pts.mu, xerr=pts.get("I_err"), yerr=pts.get("mu_err"), fmt="ks", ms=4, mfc="w",
                   label="plane-shear points (per seed)")
        b.errorbar(pts.I, pts.phi, xerr=pts.get("I_err"), yerr=pts.get("phi_err"), fmt="ks", ms=4, mfc="w",
                   label="plane-shear points")
    groups = list(pairs.groupby("drive", sort=False))
    for k, (label, g) in enumerate(groups):  # the DEM in blues, one marker per drive
        style = dict(fmt=DRIVE_MARKERS[k % len(DRIVE_MARKERS)], ms=4, alpha=0.8, lw=0.6,
                     color=colormaps["Blues"](0.95 - 0.45 * k / max(1, len(groups) - 1)))
        a.errorbar(g.I_dem, g.mu, xerr=g.I_err, yerr=g.mu_err, **style,
                   label=f"{names.get(label, label)} steady pairs" + (" (test)" if c.blind else ""))
        b.errorbar(g.I_dem, g.phi, yerr=g.phi_err, **style, label=f"{names.get(label, label)} steady pairs")
    dimension = c.drives[0].dem.spec.dimension
    for colour, pub in zip(PUBLISHED_COLOURS, [x for x in PUBLISHED if x["dimension"] == dimension], strict=False):
        if "mu_1" in pub:
            a.plot(lin, pub["mu_1"] + pub["b"] * lin, color=colour, ls=":", lw=1.4,
                   label=f"{pub['source'].split(',')[0]}: {pub['mu_1']:g} + {pub['b']:g} I")
        else:
            a.plot(I, mu_law(I, pub["mu_s"], pub["mu_d"], pub["I0"]), color=colour, ls=":", lw=1.4,
                   label=f"{pub['source'].split(',')[0]} (Jop form)")
        if "phi_max" in pub:
            b.plot(lin, pub["phi_max"] - pub["a"] * lin, color=colour, ls=":", lw=1.4,
                   label=f"{pub['source'].split(',')[0]}")
    if cal.I_min is not None:
        a.axvline(cal.I_min, color="0.6", ls=":", label="I_min (creep excluded from the fit)")
    a.set(xscale="log", xlabel=FIELD_LABELS["I_dem"], ylabel="mu = tau/p",
          title="mu(I): " + ("the drives as a blind test of the plane-shear law" if c.blind else "fit on the drives"))
    b.plot(lin, cal.phi_max - cal.phi_slope * lin, "k-", label=f"phi = {cal.phi_max:.3f} - {cal.phi_slope:.3f} I")
    b.set(xscale="log", xlabel=FIELD_LABELS["I_dem"], ylabel="phi", title="phi(I)")
    for ax in (a, b):
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncols=2, frameon=False)
    path = out / "calibration.png"
    fig.savefig(path, dpi=100)
    return path


def calibration_section(c: Comparison) -> str:
    """The report's calibration section: source, kind, values with intervals, published values, the test."""
    cal = c.calibration
    ci = cal.ci95
    names = (("mu_s", "mu_s"), ("mu_d", "mu_d"), ("I0 (DEM convention)", "I0_dem"), ("mu_1 in mu = mu_1 + b I", "mu_1"),
             ("b", "b"), ("phi_max", "phi_max"), ("a in phi = phi_max - a I", "phi_slope"))
    rows = [[name, fmt(getattr(cal, attr)), f"[{ci[attr][0]:.3g}, {ci[attr][1]:.3g}]"] for name, attr in names]
    pubs = "".join(f"<li>{html.escape(p['source'])}: {html.escape(p['system'])}; "
                   + html.escape(", ".join(f"{k} = {p[k]:g}"
                                           for k in ("mu_s", "mu_d", "I0", "mu_1", "b", "phi_max", "a")
                                           if k in p)) + f" (verified: {html.escape(p['verified'])})</li>"
                   for p in PUBLISHED)
    head = ("<p><b>Blind comparison</b>: mu(I) and phi come from an independent plane-shear calibration of the "
            f"same grains, <code>{html.escape(cal.source)}</code>; the drives' steady pairs are a test of it, "
            "not a fit.</p>" if c.blind else
            "<p><b>In-drive fit</b>: mu(I) is fitted on the drives' own steady windows, so the steady predictions "
            "are close to a restatement of the fit; pass <code>--calibration DIR/calibration.json</code> "
            "(<code>granstokes dem calibrate</code>) for a blind test.</p>")
    return (head + table(["parameter", "value", "95 % interval (bootstrap)"], rows)
            + f"<p>{len(cal.points)} points, rms residual of the Jop law {cal.rms_mu:.3f}.</p>"
            f"<p>Test of the law by the drives: {html.escape(c.law_test['verdict'])}.</p>"
            "<p>Published values (plane shear or rheometry; differences: friction mu_p, restitution and "
            "polydispersity differ from ours, mu_p = 0.5 here):</p><ul>" + pubs + "</ul>")


def sigma_figure(c: Comparison, out: Path) -> Path:
    """One bar per scorecard row: sigma = (DEM - predicted)/combined error in the model's colour, the threshold's
    infinite-dof limit -+Z95 shaded and each scored row's own threshold -+t_0.975(dof) marked, each row's label in
    its verdict's colour."""
    rows, names = c.scorecard.rows, display_labels(c)
    fig = Figure(figsize=(10.0, 0.32 * len(rows) + 2.0), layout="constrained")
    ax = fig.subplots()
    y = np.arange(len(rows))
    scored = rows.scored.to_numpy(dtype=bool)
    sigma = rows.sigma.to_numpy(dtype=float)
    ax.barh(y, np.where(scored, np.clip(sigma, -SIGMA_CLIP, SIGMA_CLIP), 0.0),
            color=[MODEL_STYLE[m]["color"] for m in rows.model])
    for k in np.flatnonzero(~scored):
        ax.text(-SIGMA_CLIP, k, f" {rows.verdict.iloc[k]} (see the row's note)", va="center", fontsize=7,
                color=VERDICT_COLOUR[rows.verdict.iloc[k]])
    for k in np.flatnonzero(scored & (np.abs(sigma) > SIGMA_CLIP)):
        ax.text(np.sign(sigma[k]) * SIGMA_CLIP, k, f" {sigma[k]:+.0f} ", va="center", fontsize=7,
                ha="left" if sigma[k] < 0 else "right", color="w")
    ax.axvspan(-Z95, Z95, color="0.88", zorder=0)
    limit = np.array([min(critical(d), SIGMA_CLIP) if s else np.nan for d, s in zip(rows.dof, scored, strict=True)])
    ax.scatter(np.r_[-limit, limit], np.r_[y, y], marker="|", color="k", s=60, zorder=3)
    ax.set_yticks(y, [f"{names.get(r.drive, r.drive)}, {words(r.observable)} ({MODEL_WORDS.get(r.model, r.model)})"
                      for r in rows.itertuples()], fontsize=7)
    for tick, verdict in zip(ax.get_yticklabels(), rows.verdict, strict=True):
        tick.set_color(VERDICT_COLOUR[verdict])
    ax.invert_yaxis()
    ax.set_xlim(-SIGMA_CLIP * 1.05, SIGMA_CLIP * 1.05)
    ax.set_xlabel(f"sigma = (DEM - predicted) / combined error (bars clipped at +-{SIGMA_CLIP:g})", fontsize=8)
    fig.suptitle("Scorecard: how far each prediction is from the DEM")
    handles = [Patch(color=MODEL_STYLE[m]["color"], label=label)
               for m, label in dict(zip(rows.model, rows.model_label, strict=True)).items()]
    handles += [Patch(color="0.88", label=f"|sigma| <= {Z95:.2f}: consistent at infinite dof"),
                Line2D([], [], marker="|", color="k", ls="", label="the row's threshold t_0.975(dof): consistent "
                                                                    "within")]
    shown = {VERDICT_COLOUR[v]: v for v in ("consistent", "disagrees")} | {VERDICT_COLOUR[UNSCORED[0]]: "not scored, "
                                                                          "predicted or measurable"}
    handles += [Patch(color=colour, label=f"row label: {verdict}") for colour, verdict in shown.items()]
    fig.legend(handles=handles, loc="outside lower center", ncols=2, fontsize=7, frameon=False)
    path = out / "scorecard.png"
    fig.savefig(path, dpi=100)
    return path


def noise_rows(c: Comparison, names: dict) -> pd.DataFrame:
    """The DEM's relative standard error of each scored observable per drive (the scorecard's DEM value and
    error; the steady response's when there is no scorecard), with the drive's work."""
    sc, rows = c.scorecard.rows, []
    for dc in c.drives:
        g = dc.dem
        st = g.steady[g.response]
        values = {f"{g.response}_inf": (st["value"], st["stderr"])}
        if len(sc):
            values.update({r.observable: (r.dem, r.dem_err)
                           for r in sc[sc.drive == dc.label].drop_duplicates("observable").itertuples()})
        for observable, (v, e) in values.items():
            if v and np.isfinite(v) and np.isfinite(e) and e > 0:
                rows.append({"drive": names.get(dc.label, dc.label), "observable": observable, "cost": g.spec.cost,
                             "seeds": g.spec.seeds, "percent": 100 * e / abs(v)})
    return pd.DataFrame(rows, columns=["drive", "observable", "cost", "seeds", "percent"])


def cost_figure(c: Comparison, out: Path) -> Path:
    """The DEM's noise: relative standard error of each observable per drive.  Against the DEM's work
    (grains x steps x seeds) when the drives span at least three costs; else a labelled dot plot, each
    drive's cost beside it (one cost: in the title)."""
    rows = noise_rows(c, display_labels(c))
    costs = sorted(rows.cost.unique())
    scatter = len(costs) >= 3
    fig = Figure(figsize=(8, 4.6) if scatter else (8, 0.3 * len(rows) + 2.0), layout="constrained")
    ax = fig.subplots()
    markers = {o: "os^Dv<>"[k % 7] for k, o in enumerate(dict.fromkeys(rows.observable))}
    if rows.empty:
        ax.text(0.5, 0.5, "no DEM value with a standard error", ha="center", va="center", transform=ax.transAxes)
        ax.set_axis_off()
    elif scatter:
        drives = list(dict.fromkeys(rows.drive))
        colour = {d: colormaps["Blues"](0.95 - 0.5 * k / max(1, len(drives) - 1)) for k, d in enumerate(drives)}
        for r in rows.itertuples():
            ax.plot(r.cost, r.percent, markers[r.observable], color=colour[r.drive], ms=7)
        handles = [Line2D([], [], color="k", marker=m, ls="none", label=o) for o, m in markers.items()]
        handles += [Patch(color=colour[d], label=d) for d in drives]
        fig.legend(handles=handles, loc="outside lower center", ncols=4, fontsize=7, frameon=False)
        ax.set(xscale="log", yscale="log", xlabel="DEM work: grains x steps x seeds",
               ylabel="relative standard error [%]")
        suptitle(fig, "DEM cost vs noise: relative standard error of each observable against the DEM's work", 11)
    else:
        y = np.arange(len(rows))
        for k, r in enumerate(rows.itertuples()):
            ax.plot(r.percent, k, markers[r.observable], color=DEM_COLOUR, ms=7)
            ax.annotate(f"{r.percent:.2g} %", (r.percent, k), xytext=(6, 0), textcoords="offset points",
                        va="center", fontsize=7)
        ax.set_yticks(y, [f"{r.drive}, {r.observable}" for r in rows.itertuples()], fontsize=8)
        ax.set_ylim(len(rows) - 0.5, -0.5)
        for k in np.flatnonzero(rows.drive.to_numpy()[1:] != rows.drive.to_numpy()[:-1]):
            ax.axhline(k + 0.5, color="0.8", lw=0.8)
        if rows.percent.max() > 10 * rows.percent.min():
            ax.set_xscale("log")
            plain_log(ax.xaxis)
        if ax.get_xscale() == "log":
            ax.set_xlim(rows.percent.min() / 1.6, rows.percent.max() * 3)
        else:
            ax.set_xlim(0, rows.percent.max() * 1.25)
        ax.set_xlabel("relative standard error of the DEM value [%]")
        ax.grid(axis="x", color="0.92")
        if len(costs) == 1:
            seeds = "/".join(str(s) for s in sorted(rows.seeds.unique()))
            note = (f"every drive cost the same, {costs[0]:.2g} grains x steps x seeds ({seeds} "
                    f"seed{'' if seeds == '1' else 's'}): the noise differs by observable, not by work")
        else:
            note = "the drives span only two costs, too few for a trend; each drive's work is on the right"
            for d, g in rows.groupby("drive", sort=False):
                first = int(np.flatnonzero(rows.drive.to_numpy() == d)[0])
                ax.annotate(f"{g.cost.iloc[0]:.2g} grain-steps, {g.seeds.iloc[0]} seed"
                            + ("" if g.seeds.iloc[0] == 1 else "s"),
                            (1.01, first), xycoords=("axes fraction", "data"), va="center", fontsize=7,
                            annotation_clip=False)
        suptitle(fig, f"DEM noise per observable: {note}", 10)
    path = out / "cost_noise.png"
    fig.savefig(path, dpi=100)
    return path


# --- the page ------------------------------------------------------------------------------------------

def scorecard_html(c: Comparison) -> str:
    rows, names = [], display_labels(c)
    for r in c.scorecard.rows.itertuples():
        verdict = f"<b style='color:{VERDICT_COLOUR[r.verdict]}'>{html.escape(r.verdict)}</b>"
        if r.note:
            verdict += f"<br><small>{html.escape(r.note.removeprefix(r.verdict + ': '))}</small>"
        model = html.escape(r.model_label) + ("" if r.blind else " (not blind: fitted on the drives)"
                                              if not c.blind else " (not blind: fitted on this drive)")
        rows.append([html.escape(names.get(r.drive, r.drive)),
                     f"{html.escape(words(r.observable))} [{html.escape(r.unit)}]", fmt(r.dem, r.dem_err), model,
                     fmt(r.predicted), fmt_band(r.band, r.dem_err), f"{r.sigma:+.1f}",
                     f"{critical(r.dof):.2f}" if r.scored else "", verdict])
    if not rows:
        return f"<p>No scorecard rows: {html.escape(c.failure or 'no drive has a continuum prediction')}.</p>"
    return table(["drive", "observable [unit]", "DEM ± error", "model", "predicted", "95 % band", "sigma",
                   "consistent within |sigma| &le; t<sub>0.975</sub>(dof)", "verdict"], rows)


def laws_summary(c: Comparison) -> str:
    """One sentence per model: how many of the paper's laws the DEM can decide, and how they went."""
    rows = c.laws
    if rows.empty:
        return "No law was evaluated (no drive was predicted)."
    parts = []
    for model, g in rows.groupby("model", sort=False):
        v = g.verdict.value_counts()
        parts.append(f"{MODEL_WORDS.get(model, model)}: consistent on {v.get('consistent', 0)}, disagrees on "
                     f"{v.get('disagrees', 0)}, not predicted on {v.get('not predicted', 0)}")
    n = int((rows.drop_duplicates(["law", "quantity"]).verdict == "not measurable").sum())
    return (f"Of {rows[['law', 'quantity']].drop_duplicates().shape[0]} law quantities, {n} are not measurable with "
            f"these drives (each row says why); " + "; ".join(parts) + ".")


#: the model whose laws are the paper's predictions (continuum.scene_models.PAPER)
PAPER_MODEL = "paper"


def laws_verdict(c: Comparison) -> dict[str, list[str]]:
    """The paper's predictions in words, from its model's law rows: the laws the DEM supports and refutes (with
    sigma) and those this scene cannot decide (with why); empty lists are left out."""
    rows = c.laws[c.laws.model == PAPER_MODEL] if not c.laws.empty else c.laws
    verbs = {"consistent": "supports", "disagrees": "refutes"}
    out = {verb: [f"{words(r.law, r.quantity)} ({r.quantity}): DEM {fmt(r.dem, r.dem_err)} against "
                  f"{fmt(r.predicted)}, {r.sigma:+.1f} sigma" for r in rows.itertuples() if r.verdict == v]
           for v, verb in verbs.items()}
    out["cannot decide"] = [f"{words(r.law, r.quantity)} ({r.quantity}): "
                            + (r.note or "").removeprefix("not measurable: ").removeprefix("not predicted: ")
                            for r in rows.itertuples() if r.verdict not in verbs]
    return {k: v for k, v in out.items() if v}


def laws_verdict_html(c: Comparison) -> str:
    verdict = laws_verdict(c)
    if not verdict:
        return "<p><b>The paper's predictions.</b> No law of the paper was evaluated (no drive was predicted).</p>"
    items = "".join(f"<li>The DEM {html.escape(verb)}: {html.escape('; '.join(laws))}.</li>"
                    for verb, laws in verdict.items())
    return f"<p><b>The paper's predictions</b> (its model's rows; every model's in the table below)</p><ul>{items}</ul>"


def laws_html(c: Comparison) -> str:
    """The laws' rows (compare.laws) as a table, after one summary sentence."""
    grey = VERDICT_COLOUR[UNSCORED[0]]
    rows = [[html.escape(words(r.law, r.quantity)), html.escape(r.quantity),
             html.escape(MODEL_WORDS.get(r.model, r.model)), fmt(r.dem, r.dem_err), fmt(r.predicted),
             fmt_cell(r.sigma) if np.isfinite(r.sigma) else "",
             f"{critical(r.dof):.2f}" if np.isfinite(r.sigma) else "",
             f"<span style='color:{VERDICT_COLOUR.get(r.verdict, grey)}'>{html.escape(r.verdict)}</span>",
             str(r.n_drives), html.escape(r.note or r.window)] for r in c.laws.itertuples()]
    return (f"<p>{html.escape(laws_summary(c))}</p>"
            + table(["law", "quantity", "model", "DEM", "predicted", "sigma",
                     "consistent within |sigma| &le; t<sub>0.975</sub>(dof)", "verdict", "drives", "window or why not"],
                    rows))


def scene_html(c: Comparison) -> str:
    names = display_labels(c)
    rows = [[html.escape(names.get(r.drive, r.drive)), f"{html.escape(r.check)} [{html.escape(r.unit)}]",
             fmt(r.value, r.err), html.escape(r.target), html.escape(r.verdict), html.escape(r.how)]
            for r in c.scorecard.scene.itertuples()]
    return table(["drive", "check [unit]", "value ± error", "target", "verdict", "error from"], rows)


def conclusions(c: Comparison) -> list[str]:
    """Sentences written from the scorecard's numbers."""
    rows, out, names = c.scorecard.rows, [], display_labels(c)

    def name(label):
        return html.escape(names.get(label, label))

    if c.failure:
        return [f"The mu(I) calibration failed: {html.escape(c.failure)}. Nothing was predicted or scored with it."]
    if not c.blind:
        out.append(f"The calibration is an {html.escape(c.calibration_source)}: the predictions share data with what "
                   "they are compared with, so no row counts as support for a model.")
    for dc in c.drives:
        if dc.base:
            out.append(f"{name(dc.label)}: {html.escape(dc.base)}; its layer rows, and every row of the "
                       "half-space model, are not scored.")
    if rows.empty:  # every drive's prediction was refused or failed: each drive's note says why
        return out + ["No drive has a scored continuum prediction (each drive's section says why)."]
    scored = rows[rows.scored]
    for _, g in scored.groupby("model", sort=False):
        ok = g[g.verdict == "consistent"]
        bad = g[g.verdict != "consistent"]
        text = (f"<b>{html.escape(g.model_label.iloc[0])}</b>: {len(ok)} of {len(g)} predictions consistent "
                "(|sigma| &le; t<sub>0.975</sub>(dof))")
        if len(bad):
            worst = ", ".join(f"{html.escape(words(r.observable))} of {name(r.drive)} "
                              f"({(r.predicted / r.dem - 1) * 100:+.0f} %, {r.sigma:+.1f} sigma)"
                              for r in bad.itertuples() if r.dem)
            text += f"; it fails on {worst}"
        out.append(text + ".")
    shared = tally(rows)
    if len(shared) > 1:
        out.append(f"Ranked over the {int(shared.n.iloc[0])} scored blind row(s) every model has: "
                   + "; ".join(f"{html.escape(t.model)} {int(t.consistent)} of {int(t.n)} consistent (median |sigma| "
                               f"{t.median_abs_sigma:.1f})" for t in shared.itertuples()) + ".")
    fl = c.fluidity
    if fl is not None:
        lo, hi = fl.ci95
        text = (f"The nonlocal amplitude A = {fmt(fl.A, fl.err)} (95 % interval [{lo:.3g}, {hi:.3g}], {fl.how}) was "
                f"fitted on the shape of the steady creep profile of {name(fl.drive)} ({int(fl.points)} points, one "
                "per d); "
                "its rows for that drive are not blind, every other NGF row is.")
        if fl.at_bound:
            text += (" The fit ran into its search range: that profile does not determine A, and the NGF rows test "
                     "little.")
        out.append(text)
    steady_rows = rows[np.isfinite(rows.asymptote.astype(float))]
    late = steady_rows[~((steady_rows.predicted / steady_rows.asymptote - 1).abs() <= MODEL_UNSTEADY)]
    if len(late):
        out.append("Over the DEM's final quarter some models are still more than "
                   f"{MODEL_UNSTEADY:.0%} from their steady state: " + ", ".join(
                       f"{html.escape(r.model)} on {name(r.drive)} at {r.predicted:.3g} "
                       f"({(r.predicted / r.asymptote - 1) * 100:+.0f} % of its steady {r.asymptote:.3g})"
                       for r in late.itertuples()) + ": the record is shorter than those models' time scale; their "
                   "plate rows compare the same window (like with like), their layer rows are not scored.")
    creep = rows[(rows.observable == "creep_length") & (rows.model == "local")]
    if len(creep):
        out.append(f"Below the layer the DEM creeps with an e-folding length of "
                   f"{fmt(creep.dem.mean(), creep.dem_err.mean())} d, which local mu(I) cannot have (it is rigid "
                   "there).")
    scene = c.scorecard.scene
    for r in scene[scene.verdict.isin(["off", "slips"])].itertuples() if len(scene) else []:
        out.append(f"Scene check off: {html.escape(r.check)} = {fmt(r.value, r.err)} for {name(r.drive)} "
                   f"(target {html.escape(r.target)}); differences in that drive may be the scene's, not the "
                   "rheology's.")
    if len(scene):
        slips = scene[scene.check == "slip at the plate"]
        lo, hi = f"{slips.value.min() * 100:.1f} %", f"{slips.value.max() * 100:.1f} %"
        out.append(f"The plate slips by {lo if lo == hi else f'{lo} to {hi}'} over the drive(s); the "
                   "elastic start (a few shear-wave transits over the bed, shaded on the drive figures) is not "
                   "compared, since the continuum is rigid.")
    return out


HOW_TO_READ = {**law_figures.HOW_TO_READ,
    "scorecard": "Each bar is one scorecard row, in its model's colour: how many combined standard errors the DEM "
                 "lies from the prediction. The threshold is per row: consistent within the black ticks, -+ "
                 "Student-t's 97.5 % quantile at the degrees of freedom of the row's error "
                 f"({critical(2):.2f} at 2, {critical(3):.2f} at 3); the grey band is its limit at infinitely many, "
                 f"-+{Z95:.2f}. Each row's label has its verdict's colour (green consistent, red disagrees, grey not "
                 "scored).",
    "drive": "Top left: the free response (u_w under an imposed stress, mu_w under an imposed speed), the DEM as a "
             "running mean with its band over seeds, each model as a line with its 95 % band from the calibration's "
             "uncertainty (linearised). Top right: the layer thickness delta_u on log axes "
             "(sqrt(t) growth is a slope of 1/2). Bottom: the steady velocity profile, linear and log; on the log "
             "panel a straight DEM tail below delta_s is creep, which local mu(I) cannot have.",
    "profiles": "Steady-window depth profiles of the DEM (band: seeds or frames) with the local model's steady state: "
                "velocity, solid fraction, pressure, shear stress, friction and inertial number.",
    "transient": "Depth profiles at a few snapshot times, DEM solid and the local model dashed in the same colour.",
    "fluidity": "The steady fluidity g = |du/dy|/mu on a log scale: the DEM's from its coarse-grained profile, the NGF "
                "model's, and the local law's g_loc, which vanishes below delta_s. A straight DEM line below the layer "
                "is the exponential decay NGF predicts with length A d/sqrt(|mu - mu_s|).",
    "calibration": "The mu(I) law with its 95 % bootstrap band and the linear form, the published values beside it "
                   "(dotted). Blind comparison: the plane-shear points it was measured on (squares) and the drives' "
                   "steady (mu, I) pairs, one per d of depth away from the walls, with their errors, as a test of the "
                   "law; in-drive fit: the pairs and the fit through them.",
    "cost_noise": "How noisy the DEM is: the relative standard error of each scored DEM value (error / |value|), per "
                  "drive and observable. When the drives span three or more costs, against the DEM's work (grains x "
                  "steps x seeds); otherwise as dots, with the drives' work written beside them.",
}
FIGURE_TITLES = {"scorecard": "Scorecard", "calibration": "mu(I) calibration", "cost_noise": "DEM noise and cost",
                 "drive": "Free response and steady velocity", "profiles": "Steady-window profiles",
                 "transient": "Transient profiles", "fluidity": "Steady fluidity", **law_figures.TITLES}


def files(c: Comparison, out: Path) -> list[FigureFile]:
    """Write the Stokes drives' CSV files (calibration pairs, each drive's series, profiles, layer depths and
    predictions, the coarse-graining checks) and figures into ``out``; the figures in the report's order."""
    c.pairs.to_csv(out / "calibration_pairs.csv", index=False, float_format=CSV_FLOAT)
    names = display_labels(c)
    figs = [FigureFile("scorecard", sigma_figure(c, out), page=SCORECARD)] if len(c.scorecard.rows) else []
    figs += [FigureFile("calibration", calibration_figure(c, out)),
             FigureFile("cost_noise", cost_figure(c, out), page=DRIVES)]
    if any(dc.predictions and dc.scales is not None for dc in c.drives):
        figs += [FigureFile(kind, draw(c, out)) for kind, draw in law_figures.FIGURES.items()]
    for dc in c.drives:
        g, name = dc.dem, names[dc.label]
        stem = slug(name)
        g.series.to_csv(out / f"series_{stem}.csv", index=False, float_format=CSV_FLOAT)
        g.steady_profile.to_csv(out / f"steady_profile_{stem}.csv", index=False, float_format=CSV_FLOAT)
        g.delta.to_csv(out / f"delta_{stem}.csv", index=False, float_format=CSV_FLOAT)
        for p in dc.predictions:
            p.series.assign(model=p.model).to_csv(out / f"prediction_{stem}_{p.model}.csv", index=False,
                                                  float_format=CSV_FLOAT)
        if dc.predictions:
            figs += [FigureFile("drive", drive_figure(dc, c.scorecard.bands, out, name), name, DRIVES),
                     FigureFile("profiles", profiles_figure(dc, c.material, out, name), name, DRIVES),
                     FigureFile("transient", transient_figure(dc, c.material, out, name), name, DRIVES),
                     FigureFile("fluidity", fluidity_figure(dc, c.material, out, name), name, DRIVES)]
    c.checks.width.to_csv(out / "width_check.csv", index=False, float_format=CSV_FLOAT)
    c.checks.crosscheck.to_csv(out / "lammps_crosscheck.csv", index=False, float_format=CSV_FLOAT)
    return figs


def sections(c: Comparison, m: dict) -> list[Section]:
    """The report's sections: on index.html the paper's laws, the conclusions and the calibration; on scorecard.html
    the scorecard; on drives.html the drives, their scene checks and the coarse-graining's checks."""
    names = display_labels(c)
    out = [Section("The paper's laws", laws_verdict_html(c) + laws_html(c), "laws"),
           Section("Conclusions", "<ul>" + "".join(f"<li>{s}</li>" for s in conclusions(c)) + "</ul>", "conclusions"),
           Section("Calibration", f"<p>Runs: {html.escape(', '.join(m['runs']))}. Calibration: "
                   f"{html.escape(c.calibration_source)}. DEM units: {html.escape(UNITS['dem_units'])}. Inertial "
                   f"number: {html.escape(UNITS['inertial_number'])}.</p>" + calibration_section(c), "calibration"),
           Section("The scorecard", scorecard_html(c) + f"<p>Bands: {c.scorecard.replicates} calibration replicates "
                   f"per steady prediction (band edges change by at most {c.scorecard.edge_stability:.0%} of the band "
                   "width from half to all replicates); t90 by linearised propagation. sigma = (DEM - "
                   "predicted)/combined error; consistent when |sigma| &le; t<sub>0.975</sub>(dof), Student-t's 97.5 % "
                   "quantile at the degrees of freedom of the row's combined error (column dof: "
                   f"{critical(2):.2f} at 2, {critical(3):.2f} at 3, {Z95:.2f} at infinitely many).</p>", "scorecard",
                   SCORECARD),
           Section("The drives", drives_html(m, names), "drives", DRIVES),
           Section("The scene's own checks", scene_html(c), "scene", DRIVES)]
    ch = c.checks
    return out + [Section(f"Checks of the coarse-graining ({names.get(ch.drive, ch.drive)})", checks_html(c),
                          "coarse-graining", DRIVES)]


def names(c: Comparison) -> dict:
    """The drives' labels as a reader sees them (display_label)."""
    return display_labels(c)


def kinds(c: Comparison) -> dict:
    """Each drive's load kind (its scorecard rows do not carry it)."""
    return {dc.label: dc.dem.spec.kind for dc in c.drives}


def _record(dc: DriveComparison, models: list[str]) -> tuple[bool, str]:
    """Whether drive ``dc``'s record is long enough: the DEM registers a steady state and every model is steady
    within it (``models``: those that are not); why not, in words."""
    t_steady = dc.dem.steady.get("t_steady")
    if t_steady is None or not np.isfinite(t_steady):
        return False, "the DEM never registers steady"
    if models:
        return False, f"{', '.join(MODEL_WORDS.get(k, k) for k in models)} not steady by its end"
    return True, ""


def scene(c: Comparison) -> list[dict]:
    """Each drive's scene checks in compare.findings' terms: the plate's slip and the stresses' balance (the
    scorecard's scene checks), the base (compare.scorecard.base_reach), the bed's depth (compare.scorecard.short_bed),
    the elastic start against the growth window
    (it must end before GROWTH_END t_s) and the record (the DEM steady in it, every model steady by its end)."""
    out = []
    by_check = {"slip at the plate": "slip", "bulk CG tau - plate <tau_w>": "stresses",
                "pressure slope / (mean phi rho_p g)": "stresses"}
    for r in c.scorecard.scene.itertuples() if len(c.scorecard.scene) else []:
        detail = f"slip {r.value * 100:.1f} %" if by_check[r.check] == "slip" else f"{r.check} = {fmt(r.value, r.err)}"
        out.append({"check": by_check[r.check], "drive": r.drive, "detail": detail,
                    "holds": r.verdict in ("grips", "within error")})
    rows = c.scorecard.rows
    for dc in c.drives:
        spec = dc.dem.spec
        out.append({"check": "base", "drive": dc.label, "holds": not dc.base, "detail": dc.base})
        if dc.scales is not None:
            need = depth_needed(dc.scales.delta_s)
            out.append({"check": "depth", "drive": dc.label, "holds": bool(spec.depth >= need),
                        "detail": f"bed {spec.depth:.3g} d, needs {need:.3g} d"})
        if dc.scales is not None and np.isfinite(spec.compared_from):
            ratio = spec.compared_from / dc.scales.t_s
            out.append({"check": "transit", "drive": dc.label, "holds": bool(ratio < GROWTH_END),
                        "detail": f"the elastic start ends at {ratio:.2g} t_s"})
        short = sorted(rows[(rows.drive == dc.label) & rows.note.str.contains("record is shorter")].model.unique()
                       ) if len(rows) else []
        holds, detail = _record(dc, short)
        out.append({"check": "record", "drive": dc.label, "holds": holds, "detail": detail})
    return out


def drives_html(m: dict, names: dict) -> str:
    rows = [[html.escape(names.get(label, label)), d["kind"], fmt(d["imposed"]), html.escape(d["imposed_unit"]),
             fmt_cell(d["seeds"]), fmt(d["u_w_inf"]["dem"], d["u_w_inf"]["dem_err"]),
             fmt(d["mu_w_inf"]["dem"], d["mu_w_inf"]["dem_err"]), fmt(d["t_steady"]), fmt_cell(d["frames"]),
             fmt_cell(d["dropped_frames"]), "yes" if d["base_confined"] else "no"]
            for label, d in m["drives"].items()]
    return table(["drive", "kind", "imposed", "unit", "seeds", f"{words('u_w_inf')} [sqrt(g d)]",
                  html.escape(words("mu_w_inf")), "steady from t [sqrt(d/g)]", "frames", "dropped frames",
                  "flow reaches the base"], rows)


def checks_html(c: Comparison) -> str:
    """The coarse-graining's checks on the first drive: the kernel width's plateau and LAMMPS's chunk averages."""
    ch = c.checks
    plateau = ch.plateau
    plateau_rows = [[html.escape(f)] + [f"{v * 100:.0f} %" for v in plateau.loc[f]] for f in plateau.index]
    cross_rows = [[html.escape(q), f"{v * 100:.1f} %"] for q, v in ch.crosscheck_bulk.items()]
    return ("<p>Width check: fraction of heights where a field plateaus (relative change within 5 %) going from the "
            "next smaller kernel width to this one, over the last 30 % of the run (width_check.csv):</p>"
            + table(["field"] + [f"w = {w:g} d" for w in plateau.columns], plateau_rows)
            + "<p>Against LAMMPS's own 1 d chunk averages (profiles.csv): mean |CG - LAMMPS| / mean |LAMMPS| in the "
            "bulk (lammps_crosscheck.csv). They differ because LAMMPS bins grain centres (no kernel), puts the virial "
            "at grain centres (no stress line) and has no wall term; p_mop and tau_mop are method-of-planes "
            "values.</p>" + table(["quantity", "relative difference"], cross_rows))
