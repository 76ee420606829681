"""The oscillating plate's report: renders a compare.oscillation.OscillationComparison into metrics.json, CSV tables,
PNG figures and the pages of compare.experiment's shell (nothing is computed here but the words of the verdict):
index.html (after the verdict and the findings: the laws in omega, the calibration and the map across frequencies),
scorecard.html (every row) and drives.html (the drives, their zones, profiles and loops)."""
from __future__ import annotations

import html
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .drive import TRANSITS_BEFORE_COMPARISON  # noqa: E402
from .experiment import CSV_FLOAT, DRIVES, SCORECARD, FigureFile, Section, table  # noqa: E402
from .oscillation import LABELS, RESPONSE_FRACTION, SKIP, OscillationComparison, OscPrediction, unsettled  # noqa: E402
from .phase import PERIODIC_TOLERANCE  # noqa: E402
from .plate import SLIP_MAX  # noqa: E402
from .report import display_label, slug  # noqa: E402
from .rows import UNSCORED  # noqa: E402
from .style import DEM_COLOUR, DRIVE_MARKERS, MODEL_STYLE, plain_log, suptitle  # noqa: E402
from .words import MODEL_WORDS, fmt, fmt_band, words  # noqa: E402

DEFINITIONS = {
    "response_amplitude": ("sqrt(g d) or 1", "the fundamental's amplitude of the free response: u_w [sqrt(g d)] "
                                             "under an imposed stress, mu_w under an imposed speed"),
    "phase_lag": ("rad", "the response's lag behind the imposed sine A sin(omega t), in (-pi, pi] (> 0: it peaks "
                         "later)"),
    "yielded_depth": ("d", "the edge of the dynamic zone, the deepest depth where the phase-averaged |mu| = "
                           "|tau_xy|/p reaches the calibrated mu_s, averaged over the cycle"),
    "dissipation": ("rho_p g d^2", "energy per cycle and plate area, the integral of tau_w u_w dt"),
    "remobilization_strain": ("1", f"the plate's displacement from a reversal until the response regains "
                                   f"{RESPONSE_FRACTION:g} of its half-cycle peak, over the DEM's yielded depth"),
    "sigma": ("1", "(DEM - predicted)/sqrt(dem_err^2 + numerical_err^2 + calibration_sd^2) (phase differences "
                   "wrapped); consistent when |sigma| <= t_0.975(dof), Student-t's 97.5 % quantile at the "
                   "Welch-Satterthwaite degrees of freedom of the combined error (column dof: beds - 1 for the DEM's "
                   "error, a law's slope n_drives - 2)"),
    "cycles": ("-", f"estimates on the whole cycles after the first {SKIP} (the start-up); DEM errors: the beds' "
                    "spread"),
    "periodic state": ("1", f"a bed is periodic when its response's first harmonic moves by at most "
                            f"{PERIODIC_TOLERANCE:g} of its larger amplitude from its first to its last kept cycle, "
                            "and in the drive's state when it lies that close to another bed's; a drive with a bed "
                            "that is not keeps its rows, unscored"),
    "systematic": ("as the law", "half the range of DEM - model over a law's measured estimator choices (the cycles "
                                 "kept, the plate's or the contact layer's speed, the first harmonic or the peak; the "
                                 "stress edge or the velocity's depths)"),
}
TITLES = {"map": "The oscillating plate across frequencies", "zones": "Static and dynamic zones over a cycle",
          "profiles": "Velocity profiles at fixed phase", "loops": "The plate's loops"}
HOW_TO_READ = {
    "map": "One column per observable, one row per drive kind, against omega t_s (t_s of the amplitude's steady "
           "layer) on a log axis: the DEM as points with their 95 % bars over beds (markers: amplitudes), each model "
           "as a line through its predictions at the same drives (shaded: its 95 % band).",
    "zones": "|mu|/mu_s over one cycle (phase across, depth down from the plate), phase-averaged: the DEM's beds on "
             "the left, each model beside it on the same depths; the black line is |mu| = mu_s, the edge of the "
             "dynamic zone (inside, |mu| > mu_s, the bed flows; outside it is static).",
    "profiles": "The velocity u(depth) averaged over the cycles at four phases of the imposed sine (0, pi/2, pi, "
                "3 pi/2; phase bins of 2 pi/24), at omega t_s nearest 1 and the largest amplitude: the DEM's mean over "
                "beds with its 95 % band, each model as a line on the same depths.",
    "loops": "The phase-averaged plate stress tau_w on the bed against the plate's speed u_w over a cycle: the area "
             "of a loop in the (x_w, tau_w) plane is the energy dissipated; a model's loop beside the DEM's.",
}


def metrics(c: OscillationComparison) -> dict:
    """The oscillating plate's entries of metrics.json beyond the shared ones (compare.experiment)."""
    drives = {}
    for d in c.drives:
        dr = d.drive
        drives[dr.label] = {"kind": dr.load.kind, "omega": dr.load.omega, "omega_ts": dr.omega_ts,
                            "amplitude": dr.load.amplitude, "amplitude_of": "mu_w" if dr.load.kind == "stress"
                            else "u_w", "p_w": dr.load.p_w, "t_s": dr.t_s, "period": dr.load.period,
                            "depth": dr.depth, "seeds": len(d.records), "whole_cycles": d.n_cycles, "slip": d.slip,
                            "periodic": [b["periodic"] for b in d.beds],
                            "periodic_change": [b["change"] for b in d.beds],
                            "same_state": [b["same_state"] for b in d.beds], "unsettled": unsettled(d),
                            **{k: {"dem": v[0], "dem_err": v[1]} for k, v in d.values.items()}}
    return {"drives": drives, "ngf": c.ngf_source,
            "calibration": {"source": c.calibration_source, "mu_s": c.setup.material.mu_s,
                            "mu_d": c.setup.material.mu_d, "I0_dem": c.setup.material.I0, "phi": c.setup.material.phi}}


def verdict(c: OscillationComparison) -> str:
    """The report's verdict in words (``verdict_parts`` joined)."""
    return " ".join(verdict_parts(c))


def verdict_parts(c: OscillationComparison) -> list[str]:
    """The verdict's sentences: per model, the observables' agreement; the history effect; the drives whose beds are
    not in one periodic state (the laws in omega have their own, ``law_sentences``)."""
    r, parts = c.rows, []
    for m in (m for m in LABELS if (r.model == m).any()):
        s = r[(r.model == m) & r.scored]
        if not len(s):
            note = r[r.model == m].note.iloc[0] if len(r[r.model == m]) else ""
            parts.append(f"{LABELS[m]}: not predicted ({note}).")
            continue
        per = "; ".join(f"{words(o)} {int((g.verdict == 'consistent').sum())}/{len(g)} consistent"
                        for o, g in s.groupby("observable", sort=False))
        parts.append(f"{LABELS[m]}: {per}.")
    h = r[(r.observable == "remobilization_strain") & r.scored & (r.model == "local")]
    if len(h):
        shows = h[(h.verdict == "disagrees") & (h.sigma > 0)]
        parts.append(f"History: after a reversal the DEM needs a strain of {h.dem.min():.2g} to {h.dem.max():.2g} to "
                     f"remobilize, local mu(I) {h.predicted.min():.2g} to {h.predicted.max():.2g}; the DEM's is larger "
                     f"beyond its error in {len(shows)} of {len(h)} drives (sigma up to {h.sigma.max():.1f}).")
    return parts + states_sentences(c)


def states_sentences(c: OscillationComparison) -> list[str]:
    """The drives with a bed that jams, drifts or sits in another state than the others (compare.oscillation
    ``unsettled``), counted and named with how many of their beds: their rows are kept, not scored (the drives'
    page and the findings' scene give each bed's numbers)."""
    shown = names(c)
    bad = [(d, sum(_settled(b) is False for b in d.beds)) for d in c.drives if unsettled(d)]
    if not bad:
        return []
    listed = ", ".join(f"{shown.get(d.drive.label, d.drive.label)} ({k} of {len(d.beds)} beds)" for d, k in bad)
    return [f"Periodic state: in {len(bad)} of {len(c.drives)} drives a bed jams, drifts or sits in another state "
            f"than the others (its first harmonic moves by more than {PERIODIC_TOLERANCE:g} of its amplitude over "
            f"the kept cycles, or lies that far from every other bed's): {listed}; their rows are kept, not scored."]


def law_sentences(c: OscillationComparison) -> list[str]:
    """The laws in omega in words: per law, drive kind and amplitude, the DEM's value and each model's with the
    family's systematic spread and the fit's chi2/dof; a law that is not a line says so (the lag is then compared
    frequency by frequency, ``lag_sentences``)."""
    parts = []
    if c.laws.empty:  # no model scored: no law
        return parts
    for (_, kind, amp), g in c.laws.groupby(["law", "kind", "amplitude"], sort=False):
        head = (f"{words(g.law.iloc[0])}, {g.quantity.iloc[0]} (imposed {kind}, amplitude {amp:.3g}, "
                f"{g.n_drives.iloc[0]} drives)")
        measured = g[~g.verdict.isin(UNSCORED)]
        if measured.empty:
            parts.append(f"{head}: {g.note.iloc[0].removeprefix('not measurable: ')}.")
            continue
        err = measured.dem_err.iloc[0]
        models = ", ".join(f"{MODEL_WORDS.get(r.model, r.model)} {fmt(r.predicted, err).split(' ± ')[0]} "
                           f"({r.verdict}, {r.sigma:+.1f} sigma at {r.dof:.2g} degrees of freedom)"
                           for r in measured.itertuples())
        r = measured.iloc[0]
        parts.append(f"{head}: DEM {fmt(r.dem, err)} (chi2/dof {r.chi2_dof:.2g}; systematic {fmt(r.systematic)} over "
                     f"{len(r.choices)} estimator choices); {models}.")
    return parts


def lag_sentences(c: OscillationComparison) -> list[str]:
    """The lag compared frequency by frequency, per model: at each omega t_s, the drives whose lag agrees and those
    whose lag disagrees (with sigma), and how many are not scored."""
    shown, parts = names(c), []
    lag = c.rows[c.rows.observable == "phase_lag"]
    for m in LABELS:
        rows = lag[lag.model == m]
        if not rows.scored.any():
            continue
        said = []
        for w, g in rows.groupby("omega_ts"):
            s = g[g.scored]
            if s.empty:
                said.append(f"at omega t_s = {w:.3g}, none of its {len(g)} drive(s) scored")
                continue
            agree = ", ".join(shown.get(x, x) for x in s[s.verdict == "consistent"].drive)
            differ = ", ".join(f"{shown.get(r.drive, r.drive)} ({r.sigma:+.1f} sigma)"
                               for r in s[s.verdict == "disagrees"].itertuples())
            text = (f"at omega t_s = {w:.3g}, agrees for {(s.verdict == 'consistent').sum()} of {len(s)} scored "
                    f"drives" + (f" ({agree})" if agree else ""))
            text += f", disagrees for {differ}" if differ else ""
            text += f", {len(g) - len(s)} not scored" if len(g) > len(s) else ""
            said.append(text)
        parts.append(f"The lag frequency by frequency, {MODEL_WORDS.get(m, m)}: " + "; ".join(said) + ".")
    return parts


def _series(c: OscillationComparison, kind: str, amplitude: float, model: str | None, observable: str):
    """(omega t_s, value, 95 % half-width) of the DEM (model None) or a model over the drives of kind and amplitude."""
    s = c.rows[(c.rows.kind == kind) & (c.rows.amplitude == amplitude) & (c.rows.observable == observable)
               & (c.rows.model == (model or "local"))].sort_values("omega_ts")
    if model is None:
        return s.omega_ts.to_numpy(), s.dem.to_numpy(), 1.96 * s.dem_err.to_numpy()
    half = (s.band.map(lambda b: b[1]).to_numpy(float) - s.predicted.to_numpy(float))
    return s.omega_ts.to_numpy(), s.predicted.to_numpy(float), half


#: the map's observables that span decades over the frequencies (log axes)
LOG_Y = ("dissipation", "remobilization_strain")


def map_figure(c: OscillationComparison, out: Path) -> str:
    kinds = sorted(c.rows.kind.unique())
    shown = ("yielded_depth", "phase_lag", "dissipation", "remobilization_strain")
    fig, axes = plt.subplots(len(kinds), len(shown), figsize=(16, 3.6 * len(kinds)), squeeze=False)
    for i, kind in enumerate(kinds):
        amps = sorted(c.rows[c.rows.kind == kind].amplitude.unique())
        for j, obs in enumerate(shown):
            ax = axes[i, j]
            for k, amp in enumerate(amps):
                x, y, e = _series(c, kind, amp, None, obs)
                what = f"mu_w = {amp:.3g}" if kind == "stress" else f"u_w = {amp:.3g}"
                ax.errorbar(x, y, e, fmt=DRIVE_MARKERS[k], color=DEM_COLOUR, ms=6, capsize=3,
                            label=f"DEM, {what}")
                for m in c.setup.models:
                    xm, ym, hm = _series(c, kind, amp, m, obs)
                    st = MODEL_STYLE.get(m, {})
                    ax.plot(xm, ym, marker=DRIVE_MARKERS[k], mfc="none", **st,
                            label=f"{m}, {what}" if j == 0 else None)
                    ax.fill_between(xm, ym - hm, ym + hm, color=st.get("color"), alpha=0.15, lw=0)
            ax.set_xscale("log")
            plain_log(ax.xaxis)
            if obs in LOG_Y:
                ax.set_yscale("log", nonpositive="mask")
            unit = c.rows[c.rows.observable == obs].unit.iloc[0]
            ax.set_xlabel("omega t_s")
            ax.set_ylabel(f"{obs.replace('_', ' ')} [{unit}]")
            ax.set_title(f"imposed {kind}: {obs.replace('_', ' ')}", fontsize=10)
        axes[i, 0].legend(fontsize=7)
    suptitle(fig, "Oscillating plate: DEM (points, 95 % over beds) and the models (lines, 95 % bands) "
                  "against the frequency")
    fig.tight_layout()
    path = out / "map.png"
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path.name


def _prediction(c: OscillationComparison, d, model: str):
    """The model's OscPrediction of drive ``d``, or None where its solver failed (its rows say why)."""
    p = c.predictions.get((d.drive.label, model))
    return p if isinstance(p, OscPrediction) else None


def _zones_amplitude(c: OscillationComparison, kind: str) -> float:
    """The amplitude whose zones and loops are drawn: the largest of the kind."""
    return max(d.drive.load.amplitude for d in c.drives if d.drive.load.kind == kind)


def zones_figure(c: OscillationComparison, out: Path, kind: str) -> str:
    amp = _zones_amplitude(c, kind)
    drives = sorted([d for d in c.drives if d.drive.load.kind == kind and d.drive.load.amplitude == amp],
                    key=lambda d: d.drive.omega_ts)
    cols = ["DEM", *c.setup.models]
    mu_s = c.setup.material.mu_s
    fig, axes = plt.subplots(len(drives), len(cols), figsize=(4 * len(cols) + 1, 2.6 * len(drives) + 0.6),
                             squeeze=False, sharey=True, layout="constrained")
    image = None
    for i, d in enumerate(drives):
        for j, col in enumerate(cols):
            ax = axes[i, j]
            pred = None if col == "DEM" else _prediction(c, d, col)
            if col != "DEM" and pred is None:
                ax.text(0.5, 0.5, "the solver failed", transform=ax.transAxes, ha="center")
                continue
            zones = d.zones if col == "DEM" else pred.zones
            ph, depth = zones.index.to_numpy(float), zones.columns.to_numpy(float)
            ratio = np.abs(zones.to_numpy(float).T) / mu_s
            image = ax.pcolormesh(ph, depth, ratio, cmap="RdYlBu_r", vmin=0, vmax=2, shading="nearest")
            ax.contour(ph, depth, ratio, levels=[1.0], colors="k", linewidths=1.2)
            ax.set_ylim(depth.max(), 0)
            ax.set_title(f"{col}: omega t_s = {d.drive.omega_ts:.3g}", fontsize=9)
            if i == len(drives) - 1:
                ax.set_xlabel("phase omega t [rad]")
            if j == 0:
                ax.set_ylabel("depth [d]")
    fig.colorbar(image, ax=axes, label="|mu| / mu_s", shrink=0.8)
    what = f"mu_w = {amp:.3g}" if kind == "stress" else f"u_w = {amp:.3g} sqrt(g d)"
    suptitle(fig, f"Static (blue) and dynamic (red) zones over a cycle, imposed {kind} ({what})")
    path = out / f"zones_{kind}.png"
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return path.name


#: the phases of the velocity profiles drawn, as fractions of the cycle
PROFILE_PHASES = (0.0, 0.25, 0.5, 0.75)


def profiles_figure(c: OscillationComparison, out: Path) -> str:
    kinds = sorted(c.rows.kind.unique())
    fig, axes = plt.subplots(len(kinds), len(PROFILE_PHASES), figsize=(3.4 * len(PROFILE_PHASES), 3.4 * len(kinds)),
                             squeeze=False, sharey="row", layout="constrained")
    for i, kind in enumerate(kinds):
        amp = _zones_amplitude(c, kind)
        d = min((d for d in c.drives if d.drive.load.kind == kind and d.drive.load.amplitude == amp),
                key=lambda d: abs(np.log(d.drive.omega_ts)))
        depth = d.velocity.columns.to_numpy(float)
        for j, frac in enumerate(PROFILE_PHASES):
            ax = axes[i, j]
            row = int(np.argmin(np.abs(d.velocity.index.to_numpy() - (2 * np.pi * frac + np.pi / len(d.velocity)))))
            u, e = d.velocity.iloc[row].to_numpy(float), 1.96 * d.velocity_err.iloc[row].to_numpy(float)
            ax.fill_betweenx(depth, u - e, u + e, color=DEM_COLOUR, alpha=0.25, lw=0)
            ax.plot(u, depth, "o-", ms=3, color=DEM_COLOUR, label="DEM")
            for m in c.setup.models:
                if (pred := _prediction(c, d, m)) is None:
                    continue
                v = pred.velocity
                ax.plot(v.iloc[row].to_numpy(float), v.columns.to_numpy(float), **MODEL_STYLE.get(m, {}), label=m)
            ax.axvline(0, color="0.7", lw=0.8)
            ax.set_ylim(depth.max(), 0)
            ax.set_title(f"{kind}, omega t_s = {d.drive.omega_ts:.3g}, phase {frac:g} x 2 pi", fontsize=9)
            ax.set_xlabel("u [sqrt(g d)]")
        axes[i, 0].set_ylabel("depth [d]")
    axes[0, 0].legend(fontsize=7)
    suptitle(fig, "Velocity profiles averaged over the cycles at fixed phase (DEM: mean over beds, 95 % band)")
    path = out / "profiles.png"
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return path.name


def loops_figure(c: OscillationComparison, out: Path) -> str:
    kinds = sorted(c.rows.kind.unique())
    per = {k: sorted([d for d in c.drives if d.drive.load.kind == k and d.drive.load.amplitude
                      == _zones_amplitude(c, k)], key=lambda d: d.drive.omega_ts) for k in kinds}
    n = max(len(v) for v in per.values())
    fig, axes = plt.subplots(len(kinds), n, figsize=(3.2 * n, 3.2 * len(kinds)), squeeze=False)
    for i, k in enumerate(kinds):
        for j, d in enumerate(per[k]):
            ax = axes[i, j]
            loop = d.loop
            ax.plot(np.r_[loop["mean"], loop["mean"][:1]], np.r_[loop.tau_w, loop.tau_w[:1]], "o-", ms=3,
                    color=DEM_COLOUR, label="DEM")
            for m in c.setup.models:
                if (pred := _prediction(c, d, m)) is None:
                    continue
                lp = pred.loop
                ax.plot(np.r_[lp["mean"], lp["mean"][:1]], np.r_[lp.tau_w, lp.tau_w[:1]], **MODEL_STYLE.get(m, {}),
                        label=m)
            ax.set_title(f"{k}, omega t_s = {d.drive.omega_ts:.3g}", fontsize=9)
            ax.set_xlabel("u_w [sqrt(g d)]")
            ax.set_ylabel("tau_w [rho_p g d]")
        for j in range(len(per[k]), n):
            axes[i, j].axis("off")
    axes[0, 0].legend(fontsize=7)
    suptitle(fig, "The plate's stress on the bed against its speed over a cycle (phase-averaged)")
    fig.tight_layout()
    path = out / "loops.png"
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return path.name


def files(c: OscillationComparison, out: Path) -> list[FigureFile]:
    """Write the phase-averaged tables (zones, loops: the DEM's and each model's) and the figures into ``out``."""
    for d in c.drives:
        stem = slug(d.drive.label)
        d.zones.to_csv(out / f"zones_{stem}_dem.csv", float_format=CSV_FLOAT)
        d.loop.to_csv(out / f"loop_{stem}_dem.csv", index=False, float_format=CSV_FLOAT)
        for model in c.setup.models:
            if (p := _prediction(c, d, model)) is None:
                continue
            p.zones.to_csv(out / f"zones_{stem}_{model}.csv", float_format=CSV_FLOAT)
            p.loop.to_csv(out / f"loop_{stem}_{model}.csv", index=False, float_format=CSV_FLOAT)
    figures = [FigureFile("map", map_figure(c, out))]
    figures += [FigureFile("zones", zones_figure(c, out, k), f"imposed {k}", DRIVES)
                for k in sorted(c.rows.kind.unique())]
    return figures + [FigureFile("profiles", profiles_figure(c, out), page=DRIVES),
                      FigureFile("loops", loops_figure(c, out), page=DRIVES)]


def _sigma(value: float) -> str:
    return f"{value:+.1f}" if np.isfinite(value) else "–"


def sections(c: OscillationComparison, m: dict) -> list[Section]:
    """The report's sections: on index.html the laws in omega and the calibration, on scorecard.html every row, on
    drives.html the drives."""
    shown = names(c)
    rows = [[html.escape(shown.get(r.drive, r.drive)), html.escape(words(r.observable)), fmt(r.dem, r.dem_err),
             html.escape(MODEL_WORDS.get(r.model, r.model)),
             fmt(r.predicted, np.hypot(r.numerical_err, r.calibration_sd)) if np.isfinite(r.predicted) else "–",
             fmt_band(r.band, r.dem_err) if np.isfinite(r.predicted) else "–",
             _sigma(r.sigma), html.escape(r.verdict), html.escape(r.note.removeprefix(r.verdict + ": "))]
            for r in c.rows.itertuples()]
    laws = [[html.escape(words(r.law)), html.escape(r.quantity), html.escape(r.kind), fmt(r.amplitude),
             html.escape(MODEL_WORDS.get(r.model, r.model)), fmt(r.dem, r.dem_err), fmt(r.predicted, r.predicted_err),
             _sigma(r.sigma), fmt(r.chi2_dof), fmt(r.systematic), str(len(r.choices)), html.escape(r.verdict),
             html.escape(r.note.removeprefix(r.verdict + ": "))]
            for r in c.laws.itertuples()]
    drives = [[html.escape(shown.get(label, label)), d["kind"], fmt(d["amplitude"]), fmt(d["omega"]),
               fmt(d["omega_ts"]), str(d["seeds"]), str(d["whole_cycles"]), f"{100 * d['slip']:.1f} %",
               ", ".join("untested" if p is None else f"{x:.2f}" for p, x in zip(d["periodic"], d["periodic_change"])),
               html.escape(d["unsettled"] or "every bed periodic, in one state")]
              for label, d in m["drives"].items()]
    cal = m["calibration"]
    said = law_sentences(c) + lag_sentences(c)
    return [Section("The laws in omega", "<ul>" + "".join(f"<li>{html.escape(p)}</li>" for p in said)
                    + "</ul>" + table(["law", "quantity", "kind", "amplitude", "model", "DEM", "predicted", "sigma",
                                       "chi2/dof", "systematic", "estimator choices", "verdict", "note"], laws),
                    "laws"),
            Section("Calibration", f"<p>Calibration: {html.escape(c.calibration_source)} (mu_s = {fmt(cal['mu_s'])}, "
                    f"mu_d = {fmt(cal['mu_d'])}, I0 = {fmt(cal['I0_dem'])} in the DEM convention, phi = "
                    f"{fmt(cal['phi'])}); {html.escape(c.ngf_source)}. Units: {html.escape(m['units'])}; "
                    f"{html.escape(m['I_convention'])}.</p>", "calibration"),
            Section("The scorecard", table(["drive", "observable", "DEM", "model", "predicted", "95 % band", "sigma",
                                            "verdict", "note"], rows), "scorecard", SCORECARD),
            Section("The drives", table(["drive", "kind", "amplitude", "omega", "omega t_s", "beds", "whole cycles",
                                         "slip rms(u_c - u_w)/rms(u_w)", "per bed: the change of its first harmonic "
                                         "from its first to its last kept cycle over the larger amplitude (periodic: "
                                         f"at most {PERIODIC_TOLERANCE:g}; untested below 2 cycles)",
                                         "the beds' periodic state (not scored otherwise)"], drives), "drives",
                    DRIVES)]


def names(c: OscillationComparison) -> dict:
    """The drives' labels as a reader sees them (compare.report.display_label)."""
    labels = [d.drive.label for d in c.drives]
    return {x: display_label(x, labels) for x in labels}


def _periodic(settled: list) -> bool | None:
    """Every bed in the drive's periodic state (True), one bed not (False), no bed tested (None)."""
    return False if any(s is False for s in settled) else (None if all(s is None for s in settled) else True)


def _settled(bed: dict) -> bool | None:
    """A bed periodic and in the state of another (False when either fails, None when neither could be tested)."""
    tests = (bed["periodic"], bed["same_state"])
    return False if False in tests else (None if all(t is None for t in tests) else True)


def scene(c: OscillationComparison) -> list[dict]:
    """Each drive's scene checks in compare.findings' terms: the plate's slip (at most SLIP_MAX), the beds'
    periodic state (compare.oscillation.unsettled: no bed jams, drifts or sits in another state than the others),
    and the shear wave's transits per period (at least TRANSITS_BEFORE_COMPARISON, as a Stokes drive's comparison
    starts after them; unknown where the run recorded no transit time)."""
    out = []
    for d in c.drives:
        dr = d.drive
        out.append({"check": "slip", "drive": dr.label, "holds": bool(d.slip <= SLIP_MAX),
                    "detail": f"slip {d.slip * 100:.1f} %"})
        settled = [_settled(b) for b in d.beds]
        out.append({"check": "periodic", "drive": dr.label, "holds": _periodic(settled),
                    "detail": unsettled(d) or f"{len(settled)} beds periodic, in one state"})
        transits = dr.load.period / dr.transit_time if np.isfinite(dr.transit_time) and dr.transit_time > 0 else np.nan
        out.append({"check": "transit", "drive": dr.label,
                    "holds": bool(transits >= TRANSITS_BEFORE_COMPARISON) if np.isfinite(transits) else None,
                    "detail": f"{transits:.2g} shear-wave transits per period" if np.isfinite(transits)
                    else "the run recorded no transit time"})
    return out
