"""The continuum-vs-DEM report: figures (PNG), tables (CSV), metrics.json and index.html."""
from __future__ import annotations

import html
import json
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from continuum.scales import UNITS
from continuum.closed_forms import SELF_SIMILAR_DELTA, self_similar_wall_speed
from continuum.steady import steady_mu
from granstokes.page import page

from .analysis import snapshot_times
from .calibrate import mu_law
from .comparison import Comparison, DriveComparison
from .metrics import DEFINITIONS, metrics

MODEL_STYLE = {0: dict(color="C1", ls="-"), 1: dict(color="C2", ls="--")}


def slug(label: str) -> str:
    return "".join(c if c.isalnum() else "_" for c in label)


def drive_figure(dc: DriveComparison, out: Path) -> Path:
    """u_w(t), mu_w(t), delta_u(t) DEM (band over seeds) against both continuum models, and the
    steady velocity profile (log scale: creep below delta_s)."""
    g, spec = dc.dem, dc.dem.spec
    fig = Figure(figsize=(12, 8.5), layout="constrained")
    ax = fig.subplots(2, 2).ravel()
    s = g.series
    for k, name in enumerate(("u_w", "mu_w")):
        ax[k].plot(s.t, s[name], color="C0", lw=0.5, alpha=0.5, label=f"DEM ({len(spec.folders)} seed(s))")
        smooth = s[name].rolling(max(1, len(s) // 50), center=True, min_periods=1).mean()
        ax[k].plot(s.t, smooth, color="C0", lw=1.8, label="DEM, running mean (2 % of the record)")
        if len(spec.folders) > 1:
            ax[k].fill_between(s.t, s[f"{name}_lo"], s[f"{name}_hi"], color="C0", alpha=0.25, label="95 % band")
        for i, p in enumerate(dc.predictions):
            ax[k].plot(p.series.t, p.series[name], label=p.model, **MODEL_STYLE[i])
        ax[k].set(xlabel="t [sqrt(d/g)]", ylabel={"u_w": "u_w [sqrt(g d)]", "mu_w": "mu_w = tau_w/p"}[name])
    if spec.kind == "stress":
        sc, tt = dc.scales, dc.predictions[0].series.t.to_numpy()
        ss = [sc.u(self_similar_wall_speed(sc.material.friction, sc.mu_w, sc.t_tilde(t))) for t in tt]
        ax[0].plot(tt, ss, color="C3", lw=0.8, ls=":", label="eq. SolutionSS (erfc), calibrated scales")
    ax[0].legend(fontsize=7)
    ax[2].plot(g.delta.t, g.delta.delta_u, "o", color="C0", label="DEM delta_u (coarse-grained u)")
    ax[2].plot(g.delta.t, dc.delta_mu, "x", color="C0", alpha=0.4, ms=4,
               label="DEM delta_mu (paper's 1e-3 mu threshold: noise-bound)")
    for i, p in enumerate(dc.predictions):
        ax[2].plot(p.series.t, p.series.delta_u, label=p.model, **MODEL_STYLE[i])
    ax[2].axhline(dc.predictions[0].steady["delta_s"], color="k", lw=0.7, ls=":", label="delta_s (calibrated)")
    tt = dc.predictions[0].series.t
    ax[2].plot(tt, SELF_SIMILAR_DELTA * dc.scales.dmu * np.sqrt(dc.scales.nu_g * tt), color="C3", lw=0.8, ls=":",
               label="eq. SolutionSS: 4.65 Dmu sqrt(nu_g t) (mu threshold)")
    t = g.delta.t[g.delta.t > 0]
    if len(t):
        ref = g.delta.delta_u[g.delta.t > 0].iloc[0] * np.sqrt(t / t.iloc[0])
        ax[2].plot(t, ref, color="0.5", lw=0.8, ls="-.", label="~ sqrt(t)")
    ax[2].set(xscale="log", yscale="log", xlabel="t [sqrt(d/g)]", ylabel="delta_u [d] (u = 5 % of u_w)")
    for axis in ax[:3]:  # the elastic start: the load is carried down by a shear wave, not compared
        axis.axvline(spec.transit_time, color="0.3", lw=0.8, ls="--", label="shear-wave transit over the bed")
        axis.axvspan(0, spec.compared_from, color="0.85", alpha=0.5, lw=0, label="elastic start (not compared)")
    ax[2].legend(fontsize=7)
    p = g.steady_profile
    ax[3].semilogx(p.u_x.clip(lower=1e-6), p.depth, color="C0", label="DEM steady window")
    for i, pr in enumerate(dc.predictions):
        last = pr.profiles[pr.profiles.t == pr.profiles.t.max()]
        ax[3].semilogx(last.u.clip(lower=1e-6), last.depth, label=pr.model, **MODEL_STYLE[i])
    ax[3].set(xlabel="u [sqrt(g d)] (log: creep)", ylabel="depth below the plate [d]", ylim=(spec.depth, 0))
    fig.suptitle(f"{g.label}: imposed {spec.kind} ({'tau_w' if spec.kind == 'stress' else 'u_w'} = {spec.value:.4g}), "
                 f"p_w = {spec.p_w:g}; DEM units")
    path = out / f"drive_{slug(g.label)}.png"
    fig.savefig(path, dpi=110)
    return path


def profiles_figure(dc: DriveComparison, material, out: Path) -> Path:
    """Steady-window profiles u, phi, p, tau, mu, I (bands over seeds or frames) with the continuum's."""
    g, spec = dc.dem, dc.dem.spec
    p = g.steady_profile
    fig = Figure(figsize=(15, 4.2), layout="constrained")
    axes = fig.subplots(1, 6, sharey=True)
    fields = ("u_x", "phi", "p", "tau", "mu", "I_dem")
    vel = dc.predictions[0]
    last = vel.profiles[vel.profiles.t == vel.profiles.t.max()]
    for ax, f in zip(axes, fields):
        ax.plot(p[f], p.depth, color="C0", label="DEM")
        ax.fill_betweenx(p.depth, p[f"{f}_lo"], p[f"{f}_hi"], color="C0", alpha=0.25)
        ax.set_xlabel(f if f != "I_dem" else "I_dem = |du/dy| d/sqrt(p/rho_p)")
    z = np.linspace(0, spec.depth, 200)
    axes[0].plot(last.u, last.depth, **MODEL_STYLE[0], label="velocity form")
    axes[1].axvline(material.phi, **MODEL_STYLE[0])
    axes[2].plot(spec.p_w + material.phi * material.rho_p * material.g * z, z, **MODEL_STYLE[0])
    tau_w = vel.steady["mu_w"] * spec.p_w
    axes[3].axvline(tau_w, **MODEL_STYLE[0])
    mu = steady_mu(material.friction, vel.steady["mu_w"], z / vel.steady["delta_s"])
    axes[4].plot(mu, z, **MODEL_STYLE[0])
    axes[5].plot(material.friction.I_of_mu(mu, material.I0), z, **MODEL_STYLE[0])
    axes[5].set_xscale("log")
    axes[0].set(ylabel="depth below the plate [d]", ylim=(spec.depth, 0))
    axes[0].legend(fontsize=7)
    fig.suptitle(f"{g.label}: steady profiles (kernel width and bands: see metadata); continuum from the calibration")
    path = out / f"profiles_{slug(g.label)}.png"
    fig.savefig(path, dpi=110)
    return path


def transient_figure(dc: DriveComparison, material, out: Path) -> Path:
    """u, phi, p, tau, mu, I against depth at a few snapshot times: DEM (instantaneous, seed-averaged)
    solid, the velocity-form prediction at the same times dashed (its phi is the calibrated constant,
    p hydrostatic, I from the calibrated law)."""
    g, spec = dc.dem, dc.dem.spec
    vel = dc.predictions[0].profiles
    fig = Figure(figsize=(16, 4.5), layout="constrained")
    axes = fig.subplots(1, 6, sharey=True)
    fields = ("u_x", "phi", "p", "tau", "mu", "I_dem")
    for k, t in enumerate(snapshot_times(g)):
        dem = g.instant[np.isclose(g.instant.t, t)]
        depth = dem.depth
        cont = vel[np.isclose(vel.t, t)]
        p = spec.p_w + material.phi * material.rho_p * material.g * cont.depth
        model = {"u_x": cont.u, "phi": np.full(len(cont), material.phi), "p": p, "tau": cont.mu * p,
                 "mu": cont.mu, "I_dem": material.friction.I_of_mu(cont.mu.clip(upper=material.mu_d - 1e-9),
                                                                   material.I0)}
        for ax, f in zip(axes, fields):
            early = " (elastic start: not compared)" if t < spec.compared_from else ""
            ax.plot(dem[f], depth, color=f"C{k}", label=f"t = {t:.3g}{early}")
            ax.plot(model[f], cont.depth, color=f"C{k}", ls="--")
    for ax, f in zip(axes, fields):
        ax.set_xlabel(f)
    axes[4].set_xlim(0, 1)
    axes[5].set(xscale="log", xlim=(1e-5, 2))
    axes[0].set(ylabel="depth below the plate [d]", ylim=(spec.depth, 0))
    axes[0].legend(fontsize=7, title="solid DEM, dashed velocity form", title_fontsize=7)
    fig.suptitle(f"{g.label}: transient profiles (DEM units; I in the DEM convention); shear-wave transit "
                 f"{spec.transit_time:.3g}, compared from {spec.compared_from:.3g}")
    path = out / f"transient_{slug(g.label)}.png"
    fig.savefig(path, dpi=110)
    return path


def calibration_figure(c: Comparison, out: Path) -> Path:
    cal, pairs = c.calibration, c.pairs
    fig = Figure(figsize=(11, 4.2), layout="constrained")
    a, b = fig.subplots(1, 2)
    for label, g in pairs.groupby("drive"):
        a.scatter(g.I_dem, g.mu, s=8, label=label)
        b.scatter(g.I_dem, g.phi, s=8, label=label)
    I = np.geomspace(max(pairs.I_dem[pairs.I_dem > 0].min(), 1e-4), pairs.I_dem.max() * 1.5, 200)
    a.plot(I, mu_law(I, cal.mu_s, cal.mu_d, cal.I0_dem), "k-",
           label=f"mu_s = {cal.mu_s:.3f}, mu_d = {cal.mu_d:.3f}, I0_dem = {cal.I0_dem:.3f}")
    a.axvline(cal.I_min, color="0.6", ls=":", label="I_min (creep excluded)")
    a.set(xscale="log", xlabel="I_dem = |du/dy| d/sqrt(p/rho_p)", ylabel="mu = tau/p", title="mu(I), steady windows")
    b.plot(I, cal.phi_max - cal.phi_slope * I, "k-", label=f"phi = {cal.phi_max:.3f} - {cal.phi_slope:.3f} I")
    b.set(xscale="log", xlabel="I_dem", ylabel="phi", title="phi(I)")
    a.legend(fontsize=7)
    b.legend(fontsize=7)
    path = out / "calibration.png"
    fig.savefig(path, dpi=110)
    return path


def cost_figure(m: dict, out: Path) -> Path:
    """DEM cost against noise: relative standard error of u_w_inf and delta_s per drive against
    grains x steps (x seeds): what each extra grain-step buys."""
    fig = Figure(figsize=(6.5, 4.2), layout="constrained")
    ax = fig.subplots()
    for label, d in m["drives"].items():
        cost = d["grains_x_steps"]
        ax.loglog(cost, d["u_w_inf"]["dem_stderr"] / abs(d["u_w_inf"]["dem"]), "o", label=f"u_w_inf {label}")
        if d["delta_s"]["dem_stderr"] is not None and np.isfinite(d["delta_s"]["dem_stderr"]):
            ax.loglog(cost, d["delta_s"]["dem_stderr"] / d["delta_s"]["dem"], "s", label=f"delta_s {label}")
    ax.set(xlabel="grains x steps (x seeds)", ylabel="relative standard error", title="DEM cost vs noise")
    ax.legend(fontsize=7)
    path = out / "cost_noise.png"
    fig.savefig(path, dpi=110)
    return path


def _fmt(v):
    if isinstance(v, dict):
        return ", ".join(f"{k}: {_fmt(x)}" for k, x in v.items())
    return f"{v:.4g}" if isinstance(v, (float, np.floating)) else html.escape(str(v))


def write_report(c: Comparison, out_dir) -> dict:
    """Render ``c`` into ``out_dir``: metrics.json, CSV tables, figures, index.html; returns the metrics."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    m = metrics(c)
    (out / "metrics.json").write_text(json.dumps(m, indent=2, default=float))
    c.pairs.to_csv(out / "calibration_pairs.csv", index=False)
    figs = [calibration_figure(c, out), cost_figure(m, out)]
    for dc in c.drives:
        g, stem = dc.dem, slug(dc.label)
        g.series.to_csv(out / f"series_{stem}.csv", index=False)
        g.steady_profile.to_csv(out / f"steady_profile_{stem}.csv", index=False)
        g.delta.assign(delta_mu=dc.delta_mu).to_csv(out / f"delta_{stem}.csv", index=False)
        for i, p in enumerate(dc.predictions):
            p.series.assign(model=p.model).to_csv(out / f"prediction_{stem}_{i}.csv", index=False)
        if dc.predictions:
            figs += [drive_figure(dc, out), profiles_figure(dc, c.material, out), transient_figure(dc, c.material, out)]
    ch = c.checks
    ch.width.to_csv(out / "width_check.csv", index=False)
    ch.crosscheck.to_csv(out / "lammps_crosscheck.csv", index=False)
    cross_rows = "".join(f"<tr><th>{q}</th><td>{v:.1%}</td></tr>" for q, v in ch.crosscheck_bulk.items())
    rows = "".join(f"<tr><th>{html.escape(k)}</th><td>{_fmt(v)}</td></tr>" for k, v in m.items()
                   if k not in ("drives", "definitions", "calibration", "runs"))
    drive_rows = "".join(f"<h3>{html.escape(k)}</h3><table>" + "".join(
        f"<tr><th>{html.escape(a)}</th><td>{_fmt(b)}</td></tr>" for a, b in d.items()) + "</table>"
        for k, d in m["drives"].items())
    body = [
        "<h1>granstokes: continuum vs DEM</h1>",
        f"<p>Runs: {html.escape(', '.join(m['runs']))}. Everything in DEM units ({html.escape(UNITS['dem_units'])}); "
        f"inertial number: {html.escape(UNITS['inertial_number'])}.</p>",
        "<h2>How to read it</h2><p>Each drive figure puts the DEM (blue, band over seeds) against two continuum "
        "predictions made from the DEM's own calibration only: the velocity form on the DEM's scene (orange: "
        "bed at rest, finite depth, plate mass) and the paper's stress-diffusion model (green dashed). Agreement "
        "of the steady values tests the local mu(I) law; the early slopes test the sqrt(t) growth; the "
        "log-scale velocity profile shows the creep below delta_s that local mu(I) cannot have.</p>",
        "<h2>Metrics</h2><table>" + rows + "</table>",
        "<h2>Definitions</h2><ul>" + "".join(f"<li><b>{html.escape(k)}</b>: {html.escape(v)}</li>"
                                              for k, v in DEFINITIONS.items()) + "</ul>",
        "<h2>Figures</h2>" + "".join(f"<p><img src='{f.name}' alt='{f.stem}'></p>" for f in figs),
        "<h2>Per drive</h2>" + drive_rows,
        f"<h2>Checks of the coarse-graining ({html.escape(ch.drive)})</h2>"
        "<p>Width check (fraction of heights where a field plateaus, |f_w - f_2w| within 5 %, going from width "
        "w to the next; last 30 % of the run; width_check.csv):</p>" + ch.plateau.to_html(float_format="{:.0%}".format)
        + "<p>Against LAMMPS's own 1 d chunk averages (profiles.csv; mean |CG - LAMMPS| / mean |LAMMPS| in the bulk; "
        "lammps_crosscheck.csv). They differ because LAMMPS bins grain centres (no kernel), puts the virial at grain "
        "centres (no stress line) and has no wall term:</p><table>" + cross_rows + "</table>",
    ]
    (out / "index.html").write_text(page("granstokes compare", "".join(body)))
    return m
