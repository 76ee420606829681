"""The cost of an error bar: each scored observable's DEM error against grain-steps, from the committed
studies' files (results/study-disks: 2D, 2 pressures x 6 drives x 6-7 beds; results/study-spheres: 3D, 3 pressures
x 2 drives x 4 beds), fitted to compare.noise's law and checked by predicting each drive's errors from the others.

    .venv/bin/python bench/dem_cost_noise.py              # writes compare/noise.csv, bench/dem_cost_noise.{csv,png}
    .venv/bin/python bench/dem_cost_noise.py --plot-only  # redraws the PNG from the committed CSVs
    .venv/bin/python bench/dem_cost_noise.py --forward DIR   # + runs FORWARD (4 min on 2 cores): ..._forward.csv

Measured errors:
* full window: each drive's dem_err in the scorecard (the spread over its beds, std/sqrt(n));
* shorter windows (error against duration): a drive's error over the final fraction f of its steady window is
  split into a part every bed keeps for the whole run (its offset:
  dem_err^2 less the block error^2 of the seed-mean record over the full window) and the seed-mean record's
  block error over windows f as long (compare.plate.block_estimate), scaled to give dem_err over the full
  window: err_f^2 = offset^2 + (dem_err^2 - offset^2) (block_f / block_1)^2.
  u_w_inf and mu_w_inf from series_*.csv, delta_u from delta_*.csv; creep_length has no time record (its
  duration exponent comes from the drives' durations), t90 is a transient's time (no duration exponent);

The forward check (``--forward``): the committed study's scene at p_w = 10 (its calibration, new beds: seeds 8-15)
with one stress and one speed drive, and its width check, run now; each bed's plate record gives the errors of
subsets of beds and of shorter windows directly, and the laws' predictions for 8 beds are compared with them. A
rerun predicts with compare/noise.csv as it is then and replaces bench/dem_cost_noise_forward.csv.
"""
from __future__ import annotations

import argparse
import json
import re
from pathlib import Path

import numpy as np
import pandas as pd
from granstokes.compare import noise
from granstokes.compare.plate import STEADY_LAST, block_estimate
from granstokes.dem import config as dem_config
from granstokes.dem.calibrate import material_table
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import FuncFormatter
from scipy.stats import chi2

from granstokes.study import config as study_config
from granstokes.study.plan import plan_study

ROOT = Path(__file__).resolve().parents[1]
HERE = ROOT / "bench"
STUDY_2D, STUDY_3D = ROOT / "results" / "study-disks", ROOT / "results" / "study-spheres"
#: the DEM presets whose boxes the committed studies' beds have (each study's ``dem`` entry)
PRESET_2D, PRESET_3D = "quick", "spheres"
#: fractions of the steady window whose errors measure the duration exponent
FRACTIONS = (1.0, 0.5, 0.25, 0.125)
#: the record each observable's shorter windows come from: (file prefix, column)
RECORDS = {"u_w_inf": ("series", "u_w"), "mu_w_inf": ("series", "mu_w"), "delta_u": ("delta", "delta_u")}
#: the acceptance: a prediction within this factor of the error then measured
WITHIN = 1.5
#: lengths of the steady profile: one law for both drive kinds, their error in d independent of the pressure
#: (the layer's edge is placed to within the grains' structure at any pressure)
LENGTHS = ("delta_u", "creep_length")
#: the forward check: the disks study cut to one pressure, two drives and eight new beds, with its calibration
FORWARD = ["seeds=[8, 9, 10, 11, 12, 13, 14, 15]", "pressures=[10.0]",
           'drive=[{kind = "stress", mu_w_tilde = 0.45}, {kind = "speed", mu_w_tilde = 0.45}]']
CALIBRATION_2D = ROOT / "results" / "calibration-disks" / "p20" / "calibration.json"
PRESSURE_COLOURS = {5.0: "C0", 10.0: "C1", 20.0: "C2"}


def stem(drive: str) -> str:
    """The file stem of a drive (".../runs/p5/stress-mutilde0.6" -> "p5_stress_mutilde0_6")."""
    parts = Path(drive).parts
    return re.sub(r"\W", "_", f"{parts[-2]}_{parts[-1]}")


def full_windows(folder: Path, dimension: int, area: float) -> pd.DataFrame:
    """Every scored (drive, observable) of a committed study with its dem_err and the drive's size."""
    card = pd.read_csv(folder / "scorecard.csv").drop_duplicates(["drive", "observable"])
    drives = json.loads((folder / "metrics.json").read_text())["drives"]
    rows = []
    for r in card.itertuples():
        d = drives[r.drive]
        local = d["steady_local"]
        rows.append({"dimension": dimension, "drive": stem(r.drive), "kind": d["kind"], "observable": r.observable,
                     "p_w": d["p_w"], "seeds": d["seeds"], "area": area, "duration": d["duration"], "fraction": 1.0,
                     "grain_steps": d["grains_x_steps"], "value": r.dem, "err": r.dem_err, "how": r.dem_how,
                     "u_w": local["u_w"], "mu_w": local["mu_w"], "delta_s": local["delta_s"], "t_s": d["t_s"]})
    return pd.DataFrame(rows)


def shorter_windows(folder: Path, full: pd.DataFrame) -> pd.DataFrame:
    """The errors over the final fraction f of each drive's steady window (module docstring)."""
    rows = []
    for r in full[full.observable.isin(list(RECORDS))].itertuples():
        prefix, column = RECORDS[r.observable]
        rec = pd.read_csv(folder / f"{prefix}_{r.drive}.csv").dropna(subset=[column])
        t0 = STEADY_LAST * r.duration
        y = rec[column].to_numpy()[rec.t.to_numpy() >= t0]
        for f, err, block_full, offset in decomposed(y, r.err):
            rows.append({**r._asdict(), "fraction": f, "duration": r.duration * f, "grain_steps": r.grain_steps * f,
                         "err": err, "how": "offset + blocks", "block_full": block_full, "offset": offset})
    return pd.DataFrame(rows).drop(columns="Index")


def decomposed(y: np.ndarray, err: float) -> list[tuple[float, float, float, float]]:
    """(f, err_f, block error of the full window, offset) for each of FRACTIONS, from the seed-mean record ``y``
    over the steady window and the drive's error ``err`` over it (module docstring)."""
    block_full = block_estimate({"y": y})["stderr"]
    offset2 = max(err**2 - block_full**2, 0.0)
    out = []
    for f in FRACTIONS:
        parts = np.array_split(y, round(1 / f))
        block = float(np.sqrt(np.mean([block_estimate({"y": p})["stderr"] ** 2 for p in parts])))
        # the fluctuating part scaled to make the full window's error the measured one
        out.append((f, float(np.sqrt(offset2 + (err**2 - offset2) * (block / block_full) ** 2)), block_full,
                    float(np.sqrt(offset2))))
    return out


def duration_exponent(short: pd.DataFrame) -> float:
    """The mean over the drives of -d ln err / d ln duration across the shorter windows."""
    slopes = [-np.polyfit(np.log(g.fraction), np.log(g.err), 1)[0] for _, g in short.groupby("drive")]
    return float(np.mean(slopes))


def scale(rows: pd.DataFrame, observable: str) -> np.ndarray:
    name = noise.SCALES[observable]
    return np.ones(len(rows)) if name == "one" else rows[name].to_numpy(float)


#: the law's forms tried, by the exponents each holds, for a scaled observable; the LENGTHS (their error in d: r and
#: b held at 0) are fitted over both drive kinds at once or for each (LENGTH_FORMS). The form whose held-out
#: predictions (each drive from the other drives) err least, by the RMS of ln(predicted / measured), is kept per
#: (observable, kind)
FORMS = {"free": {}, "no pressure": {"b": 0.0}, "relative": {"r": 1.0, "b": 0.0}}
LENGTH_HELD = {"r": 0.0, "b": 0.0}
LENGTH_FORMS = ("both kinds", "each kind")


def forms_of(obs: str) -> tuple[str, ...]:
    """The form names tried for ``obs``; the first is fit_laws' default."""
    return LENGTH_FORMS if obs in LENGTHS else tuple(FORMS)


def sigma_rows(g: pd.DataFrame) -> np.ndarray:
    """The rows' errors as estimates of sigma in log space: each a spread of its drive's beds, low by
    compare.noise.log_spread_bias on average."""
    return (g.err * np.exp(-noise.log_spread_bias(g.seeds))).to_numpy(float)


def fit_laws(full: pd.DataFrame, short: pd.DataFrame, forms: dict | None = None) -> dict[tuple[str, str], dict]:
    """One law per (observable, kind) from 2D rows, in the form ``forms[(observable, kind)]`` (default: the first
    of forms_of): a from the shorter windows (creep_length: from the drives' durations; t90: none), at least 0 (a
    longer window cannot add noise: a negative slope is the estimate's noise); then c and the exponents the form
    leaves free, over the drives' sigma_rows; with the pressures and scales fitted over."""
    out = {}
    for (obs, kind), _ in full.groupby(["observable", "kind"]):
        form = (forms or {}).get((obs, kind), forms_of(obs)[0])
        kinds = list(noise.SCORED) if form == "both kinds" else [kind]
        g = full[(full.observable == obs) & full.kind.isin(kinds)]
        s = short[(short.observable == obs) & short.kind.isin(kinds)]
        held = LENGTH_HELD if obs in LENGTHS else {"r": None, "b": None, **FORMS[form]}
        err, x = sigma_rows(g), scale(g, obs)
        if obs == "t90":
            a, a_from = 0.0, "none (a transient's time)"
        elif len(s):
            a, a_from = duration_exponent(s), "shorter windows"
        else:
            a, a_from = noise.fit(err, x, g.seeds, g.area, g.duration, g.p_w, **held)["a"], "durations"
        law = noise.fit(err, x, g.seeds, g.area, g.duration, g.p_w, a=max(a, 0.0), **held)
        scaled = noise.relative(obs)
        ranges = {"p_min": g.p_w.min(), "p_max": g.p_w.max(), "x_min": x.min() if scaled else np.nan,
                  "x_max": x.max() if scaled else np.nan}
        out[(obs, kind)] = {**law, "a_measured": a, "a_from": a_from, "form": form, **ranges}
    return out


def held_out(full: pd.DataFrame, short: pd.DataFrame, forms: dict | None = None) -> pd.DataFrame:
    """Each drive's errors predicted by the laws fitted to the other drives, in the given ``forms`` or, without,
    in the forms chosen on those other drives alone (choose_forms: the choice held out too): one row per (drive,
    observable) with the prediction and predicted / measured."""
    rows = []
    for drive in full.drive.unique():
        others, others_short = full[full.drive != drive], short[short.drive != drive]
        laws_d = fit_laws(others, others_short, forms if forms is not None else choose_forms(others, others_short)[0])
        for (obs, kind), g in full[full.drive == drive].groupby(["observable", "kind"]):
            predicted = predict(laws_d[(obs, kind)], g, obs)
            rows += [{"index": i, "observable": obs, "kind": kind, "drive": drive, "p_w": p_w, "seeds": n,
                      "predicted": x, "ratio": x / err} for i, p_w, n, x, err in zip(g.index, g.p_w, g.seeds, predicted,
                                                                                      g.err)]
    return pd.DataFrame(rows)


def choose_forms(full: pd.DataFrame, short: pd.DataFrame) -> tuple[dict, pd.DataFrame]:
    """Per (observable, kind): the form (FORMS, LENGTH_FORMS) whose held-out predictions err least; and every form's
    score."""
    scores, keys = [], list(full.groupby(["observable", "kind"]).groups)
    for k in range(max(len(FORMS), len(LENGTH_FORMS))):
        # the k-th form of every (observable, kind) that has one, all held out in one pass
        forms = {(obs, kind): forms_of(obs)[k] for obs, kind in keys if k < len(forms_of(obs))}
        for (obs, kind), g in held_out(full, short, forms).groupby(["observable", "kind"]):
            if (obs, kind) not in forms:
                continue
            scores.append({"observable": obs, "kind": kind, "form": forms[(obs, kind)],
                           "rms_log": float(np.sqrt(np.mean(np.log(g.ratio) ** 2))),
                           "within": int((np.abs(np.log(g.ratio)) <= np.log(WITHIN)).sum()), "cells": len(g)})
    scores = pd.DataFrame(scores)
    best = scores.loc[scores.groupby(["observable", "kind"]).rms_log.idxmin()]
    return {(r.observable, r.kind): r.form for r in best.itertuples()}, scores


def predict(law: dict, rows: pd.DataFrame, obs: str, c: float | None = None) -> np.ndarray:
    c = law["c"] if c is None else c
    return (c * scale(rows, obs) ** law["r"] * (rows.seeds * rows.area) ** -noise.AVERAGING
            * rows.duration ** -law["a"] * rows.p_w ** -law["b"]).to_numpy(float)


def measured_windows() -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """Each committed drive's full-window errors (2D, 3D) and the 2D drives' shorter windows."""
    width_2d = dem_config.preset(PRESET_2D)[0].box.width
    box_3d = dem_config.preset(PRESET_3D)[0].box
    full2 = full_windows(STUDY_2D, 2, width_2d)
    full3 = full_windows(STUDY_3D, 3, box_3d.width * box_3d.width_z)
    return full2, full3, shorter_windows(STUDY_2D, full2)


def measure() -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame, dict]:
    """The measured table (full and shorter windows, 2D and 3D, with predictions), compare/noise.csv's table,
    the held-out check and the checks' figures."""
    full2, full3, short = measured_windows()
    forms, scores = choose_forms(full2, short)
    fitted = fit_laws(full2, short, forms)
    table = []
    for (obs, kind), law in fitted.items():
        g3 = full3[(full3.observable == obs) & (full3.kind == kind)]
        c3 = law["c"] * float(np.exp(np.mean(np.log(sigma_rows(g3) / predict(law, g3, obs))))) if len(g3) else np.nan
        table.append({"observable": obs, "kind": kind, "scale": noise.SCALES[obs], "c2": law["c"], "c3": c3,
                      "r": law["r"], "a": law["a"], "b": law["b"], "a_measured": law["a_measured"],
                      "a_from": law["a_from"], "form": law["form"],
                      "c3_from": "; ".join(sorted(set(g3.how))) if len(g3) else "",
                      **{k: law[k] for k in noise.RANGE_COLUMNS}})
    table = pd.DataFrame(table)
    held = held_out(full2, short)
    full2.loc[held["index"], "heldout"] = held.predicted.to_numpy()
    measured = pd.concat([full2, short, full3], ignore_index=True)
    measured["predicted"] = np.nan
    for row in table.itertuples():
        for dim, c in ((2, row.c2), (3, row.c3)):
            m = (measured.observable == row.observable) & (measured.kind == row.kind) & (measured.dimension == dim)
            measured.loc[m, "predicted"] = predict(row._asdict(), measured[m], row.observable, c)
    u = short[(short.observable == "u_w_inf") & (short.fraction == 1.0)]
    m = short[(short.observable == "mu_w_inf") & (short.fraction == 1.0)]
    checks = {"seed_over_block_u_w": float(np.median(u.err / u.block_full)),
              "seed_over_block_mu_w": float(np.median(m.err / m.block_full))}
    checks["forms"] = scores
    return measured, table, held, checks


def check_law(path: Path) -> pd.DataFrame:
    """A law table's predictions (``path``: a compare/noise.csv) against every committed drive's measured
    full-window error: one row per (drive, observable)."""
    law_table = noise.laws(path)
    full2, full3, _ = measured_windows()
    rows = pd.concat([full2, full3], ignore_index=True)
    rows["predicted"] = [law_table[(r.observable, r.kind)].error(noise.DriveSize(
        r.kind, r.dimension, r.seeds, r.area, r.duration, r.p_w,
        {"u_w": r.u_w, "mu_w": r.mu_w, "delta_s": r.delta_s, "t_s": r.t_s})) for r in rows.itertuples()]
    rows["ratio"] = rows.predicted / rows.err
    return rows


OBS_LABELS = {"u_w_inf": "u_w_inf (stress drives)", "mu_w_inf": "mu_w_inf (speed drives)", "delta_u": "delta_u",
              "creep_length": "creep length", "t90": "t90"}
KIND_MARKERS = {"stress": "o", "speed": "s"}
PLAIN = FuncFormatter(lambda v, _: f"{v:g}")
#: minor ticks labelled at 2 and 5 times a power of ten only
SPARSE = FuncFormatter(lambda v, _: f"{v:g}" if f"{v:.0e}"[0] in "25" else "")


def plot(measured: pd.DataFrame, forward: pd.DataFrame | None, path: Path) -> Path:
    """One panel per observable: relative error against grain-steps (filled: a drive's full window; open and
    joined: its shorter windows; crosses: the fitted law; grey: 3D), and the held-out and forward checks."""
    fig = Figure(figsize=(12, 7.8), layout="constrained")
    axes = fig.subplots(2, 3).ravel()
    for ax, (obs, label) in zip(axes, OBS_LABELS.items()):
        g = measured[measured.observable == obs]
        for (_, kind, dim), d in g.groupby(["drive", "kind", "dimension"]):
            d = d.sort_values("grain_steps")
            colour = PRESSURE_COLOURS.get(d.p_w.iloc[0], "C7") if dim == 2 else "0.4"
            rel, pred = 100 * d.err / d.value.abs(), 100 * d.predicted / d.value.abs()
            marker = KIND_MARKERS[kind]
            if len(d) > 1:
                ax.plot(d.grain_steps, rel, marker, ls="-", lw=0.6, ms=4, color=colour, fillstyle="none")
                ax.plot(d.grain_steps, pred, ls="--", lw=0.8, color=colour)
            full = d[d.fraction == 1.0]
            ax.plot(full.grain_steps, 100 * full.err / full.value.abs(), marker, ms=7, color=colour)
            ax.plot(full.grain_steps, 100 * full.predicted / full.value.abs(), "x", ms=7, mew=1.5, color="k")
        ax.set(xscale="log", yscale="log", title=label, xlabel="grain-steps (beds x grains x steps)",
               ylabel="standard error / |value| [%]")
        ax.yaxis.set_major_formatter(PLAIN)
        ax.yaxis.set_minor_formatter(SPARSE)
    ax = axes[-1]
    for obs, marker in zip(OBS_LABELS, "o^sDv"):
        g = measured[(measured.observable == obs) & measured.heldout.notna()]
        ax.scatter(g.err, g.heldout, marker=marker, c=[PRESSURE_COLOURS[p] for p in g.p_w], s=22, label=obs)
    if forward is not None:
        f = forward[(forward.beds == forward.beds.max()) & (forward.fraction == 1.0)]
        ax.scatter(f.measured, f.predicted, marker="*", c="k", s=70, label="forward: 8 new beds, p_w = 10")
    lim = np.array([measured.err[measured.heldout.notna()].min() / 2, measured.err.max() * 2])
    ax.plot(lim, lim, "k-", lw=0.8)
    for k in (WITHIN, 1 / WITHIN):
        ax.plot(lim, k * lim, "k:", lw=0.8)
    ax.set(xscale="log", yscale="log", xlabel="measured error (spread over the beds)",
           ylabel="predicted (drive held out / before the run)",
           title=f"predicted against measured (dotted: x{WITHIN:g})")
    ax.legend(fontsize=7, loc="upper left", frameon=False)
    pressures_2d = set(measured.p_w[measured.dimension == 2])
    handles = [Line2D([], [], color=c, marker="o", ls="none", label=f"2D, p_w = {p:g}")
               for p, c in PRESSURE_COLOURS.items() if p in pressures_2d]
    handles += [Line2D([], [], color="0.4", marker="o", ls="none", label=f"3D ({STUDY_3D.name})"),
                Line2D([], [], color="k", marker="o", ls="none", label="imposed stress"),
                Line2D([], [], color="k", marker="s", ls="none", label="imposed speed"),
                Line2D([], [], color="k", marker="o", fillstyle="none", ls="-", lw=0.6,
                       label="shorter windows (offset + blocks)"),
                Line2D([], [], color="k", marker="x", ls="--", lw=0.8, label="fitted law (compare/noise.csv)")]
    fig.legend(handles=handles, loc="outside lower center", ncols=4, fontsize=8, frameon=False)
    fig.suptitle("The cost of an error bar: DEM standard error against grain-steps (committed studies, DEM units)",
                 fontsize=11)
    fig.savefig(path, dpi=110)
    return path


def forward_plan():
    """The FORWARD study's plan (its p10 run and width check), sized from the committed calibration."""
    study, _ = study_config.load(None, "disks", FORWARD)
    material, _, _ = material_table(CALIBRATION_2D)
    return plan_study(study, material, str(CALIBRATION_2D))


def run_forward(out: Path, jobs: int = 2):
    """Run (or resume) the FORWARD study's runs, one folder per run label under ``out``; its plan."""
    from granstokes.dem.layout import RUN_JSON
    from granstokes.dem.runner import run

    sp = forward_plan()
    for label, r in sp.runs.items():
        folder = out / label
        meta = folder / RUN_JSON
        stages = json.loads(meta.read_text()).get("stages", {}) if meta.exists() else {}
        if not stages or any(st.get("status") != "complete" for st in stages.values()):
            result = run(r.plan, r.text, folder, resume=meta.exists(), progress=False, jobs=jobs)
            if result.status != "complete":
                raise RuntimeError(f"{label}: {result.status} {result.message}")
    return sp


#: bed counts of the forward check's error against beds (random partitions of its beds into groups of k)
GROUPS, PARTITIONS = (1, 2, 4), 200


def forward_rows(sp, out: Path) -> pd.DataFrame:
    """Each forward drive's plate response and t90: the error measured from its beds (spread of the per-bed values)
    against the laws' prediction at its size, over shorter windows (with the decomposition's estimate from the
    seed-mean record, as on the committed study) and for groups of fewer beds."""
    from dataclasses import replace

    from granstokes.compare.analysis import _ensemble_series
    from granstokes.compare.drive import drive_specs
    from granstokes.compare.plate import PlateRecord, window_values
    from granstokes.compare.scorecard import t90

    table, rng, rows = noise.laws(), np.random.default_rng(1), []
    for label, r in sp.runs.items():
        plans = {d.drive.name: d for d in r.plan.drives}
        for spec in drive_specs(out / label):
            d = plans[spec.name]
            size = noise.drive_size(r.plan, d, r.p_w)
            plates = [PlateRecord.read(f.path) for f in spec.beds]
            resp = "u_w" if d.load.kind == "stress" else "mu_w"
            obs, n = f"{resp}_inf", len(plates)
            law = table[(obs, d.load.kind)]
            t = plates[0].t
            t0 = t[0] + STEADY_LAST * (t[-1] - t[0])
            base = {"run": label, "drive": spec.name, "kind": d.load.kind, "area": size.area}
            values = {}
            for f in FRACTIONS:
                start = t[-1] - f * (t[-1] - t0)
                values[f] = np.array([window_values(p, start)[resp]["value"] for p in plates])
            err = float(values[1.0].std(ddof=1) / np.sqrt(n))
            series = _ensemble_series(tuple(plates))
            seed_mean = series[resp].to_numpy()[series.t.to_numpy() >= t0]
            for f, estimate, block_full, _ in decomposed(seed_mean, err):
                rows.append({**base, "observable": obs, "beds": n, "fraction": f, "value": values[f].mean(),
                             "measured": float(values[f].std(ddof=1) / np.sqrt(n)), "decomposed": estimate,
                             "block_full": block_full,
                             "predicted": law.error(replace(size, duration=size.duration * f))})
            # one bed's own error estimate (blocks of its record) beside the spread of single beds
            one_bed = float(np.sqrt(np.mean([window_values(p, t0)[resp]["stderr"] ** 2 for p in plates])))
            for k in GROUPS:
                var = np.mean([np.var(rng.permutation(values[1.0]).reshape(-1, k).mean(axis=1), ddof=1)
                               for _ in range(PARTITIONS)])
                rows.append({**base, "observable": obs, "beds": k, "fraction": 1.0, "value": values[1.0].mean(),
                             "measured": float(np.sqrt(var)), "predicted": law.error(replace(size, seeds=k)),
                             "block_one_bed": one_bed if k == 1 else np.nan})
            times = np.array([t90(p.t, getattr(p, resp)) for p in plates])
            rows.append({**base, "observable": "t90", "beds": n, "fraction": 1.0, "value": times.mean(),
                         "measured": float(times.std(ddof=1) / np.sqrt(n)),
                         "predicted": table[("t90", d.load.kind)].error(size)})
    return pd.DataFrame(rows)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--plot-only", action="store_true", help="redraw the PNG from bench/dem_cost_noise.csv")
    parser.add_argument("--forward", type=Path, metavar="DIR", help="run (or resume) the forward check in DIR")
    parser.add_argument("--check-law", type=Path, metavar="CSV",
                        help="only print how the law table CSV (a compare/noise.csv) predicts the committed drives")
    args = parser.parse_args()
    if args.check_law:
        print(f"{args.check_law} against the committed studies' measured errors (predicted / measured):")
        print_ratios(check_law(args.check_law))
        return
    forward_csv = HERE / "dem_cost_noise_forward.csv"
    if args.plot_only:
        forward = pd.read_csv(forward_csv) if forward_csv.exists() else None
        plot(pd.read_csv(HERE / "dem_cost_noise.csv"), forward, HERE / "dem_cost_noise.png")
        return
    measured, table, held, checks = measure()
    measured.to_csv(HERE / "dem_cost_noise.csv", index=False, float_format="%.6g")
    table.to_csv(noise.NOISE_CSV, index=False, float_format="%.6g")
    if args.forward:
        forward = forward_rows(run_forward(args.forward), args.forward)
        forward.to_csv(forward_csv, index=False, float_format="%.6g")
    else:
        forward = pd.read_csv(forward_csv) if forward_csv.exists() else None
    plot(measured, forward, HERE / "dem_cost_noise.png")
    print("| observable | drives | form | C_2 | C_3 | r (scale) | a (measured, from) | b |")
    print("|---|---|---|---|---|---|---|---|")
    for r in table.itertuples():
        print(f"| {r.observable} | {r.kind} | {r.form} | {r.c2:.3g} | {r.c3:.3g} | {r.r:.2f} ({r.scale}) | {r.a:.2f} "
              f"({r.a_measured:.2f}, {r.a_from}) | {r.b:.2f} |")
    print(f"\nforms (held out: RMS of ln(predicted / measured), cells within x{WITHIN:g}):")
    names = [*FORMS, *LENGTH_FORMS]
    print("| observable | drives | " + " | ".join(names) + " |")
    print("|---|---|" + "---|" * len(names))
    for (obs, kind), g in checks["forms"].groupby(["observable", "kind"]):
        cells = {r.form: f"{r.rms_log:.2f} ({r.within} of {r.cells})" for r in g.itertuples()}
        print(f"| {obs} | {kind} | " + " | ".join(cells.get(f, "") for f in names) + " |")
    print("\nheld out (each drive predicted by the laws fitted to the other drives, their forms chosen on those "
          "drives; predicted / measured):")
    print_ratios(held)
    print("\n3D, in sample (C_3 fitted to these drives; predicted / measured):")
    in_sample = check_law(noise.NOISE_CSV)
    print_ratios(in_sample[in_sample.dimension == 3])
    print(f"seed spread / block error of the seed-mean record, median: u_w {checks['seed_over_block_u_w']:.2f}, "
          f"mu_w {checks['seed_over_block_mu_w']:.2f}")
    if forward is not None:
        print_forward(forward)


def within_if_exact(seeds) -> np.ndarray:
    """The chance that a measured error (the spread of ``seeds`` beds: s / sigma ~ sqrt(chi2_{n-1} / (n-1))) lies
    within WITHIN of an exact prediction: the most a law can score."""
    dof = np.asarray(seeds, float) - 1
    return chi2.cdf(dof * WITHIN**2, dof) - chi2.cdf(dof / WITHIN**2, dof)


def print_ratios(rows: pd.DataFrame):
    """Per (observable, kind, dimension): the geometric mean and range of predicted / measured over the drives,
    how many lie within WITHIN, and how many an exact law would place there on average (within_if_exact)."""
    rows = rows.assign(dimension=rows.get("dimension", 2), log=np.log(rows.ratio), exact=within_if_exact(rows.seeds))
    print(f"| observable | drives | D | cells | geometric mean | range | within x{WITHIN:g} | an exact law |")
    print("|---|---|---|---|---|---|---|---|")
    for (obs, kind, dim), g in rows.groupby(["observable", "kind", "dimension"]):
        inside = int((g.log.abs() <= np.log(WITHIN)).sum())
        print(f"| {obs} | {kind} | {dim} | {len(g)} | x{np.exp(g.log.mean()):.2f} | x{g.ratio.min():.2f}-"
              f"x{g.ratio.max():.2f} | {inside} | {g.exact.sum():.1f} |")
    inside = int((rows.log.abs() <= np.log(WITHIN)).sum())
    print(f"within x{WITHIN:g}: {inside} of {len(rows)} (drive, observable) cells; an exact law: "
          f"{rows.exact.sum():.1f} on average")


def print_forward(fwd: pd.DataFrame):
    """The forward check's tables for bench/RESULTS.md."""
    print("\nforward check (new beds, predicted from compare/noise.csv before the run):")
    print("| run | drive | observable | beds | window | value | measured | decomposed | predicted | pred./meas. |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in fwd.itertuples():
        dec = "" if pd.isna(getattr(r, "decomposed", np.nan)) else f"{r.decomposed:.3g}"
        print(f"| {r.run} | {r.drive} | {r.observable} | {r.beds} | {r.fraction:g} | {r.value:.4g} | {r.measured:.3g} "
              f"| {dec} | {r.predicted:.3g} | x{r.predicted / r.measured:.2f} |")
    for (run, drive), g in fwd[fwd.observable.isin(RECORDS) & (fwd.beds == fwd.beds.max())].groupby(["run", "drive"]):
        direct = -np.polyfit(np.log(g.fraction), np.log(g.measured), 1)[0]
        dec = -np.polyfit(np.log(g.fraction), np.log(g.decomposed), 1)[0]
        print(f"{run} {drive}: duration exponent from the beds {direct:.2f}, by the decomposition {dec:.2f}")
    for (run, drive), g in fwd[fwd.fraction.eq(1.0) & fwd.observable.isin(RECORDS) & fwd.beds.isin(GROUPS)].groupby(
            ["run", "drive"]):
        slope = -np.polyfit(np.log(g.beds), np.log(g.measured), 1)[0]
        one = g[g.beds == 1].iloc[0]
        print(f"{run} {drive}: bed-count exponent {slope:.2f} (law {noise.AVERAGING}); one bed's block error "
              f"{one.block_one_bed:.3g} against the spread of single beds {one.measured:.3g} "
              f"(x{one.measured / one.block_one_bed:.2f})")
    normal, wide = (fwd[(fwd.run == run) & (fwd.observable == "u_w_inf") & (fwd.beds == 8) & (fwd.fraction == 1.0)]
                    for run in ("p10", "p10-wide"))
    ratio = wide.measured.iloc[0] / normal.measured.iloc[0]
    print(f"width: u_w_inf error twice as wide / as wide x{ratio:.3f} (exponent {-np.log2(ratio):.2f}, law "
          f"{noise.AVERAGING})")


if __name__ == "__main__":
    main()
