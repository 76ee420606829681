"""The cost of an error bar: each scored observable's DEM error against grain-steps, from the committed
studies' files (results/study-disks: 2D, 3 pressures x 6 drives x 4 beds; results/3d: 3D, 2 drives x 2 beds),
fitted to compare.noise's law and checked by predicting each pressure's errors from the other two.

    .venv/bin/python bench/dem_cost_noise.py              # writes compare/noise.csv, bench/dem_cost_noise.{csv,png}
    .venv/bin/python bench/dem_cost_noise.py --plot-only  # redraws the PNG from the committed CSVs

Measured errors:
* full window: each drive's dem_err in the scorecard (the spread over its beds, std/sqrt(n));
* shorter windows (error against duration): no per-bed record is committed, so a drive's error over the
  final fraction f of its steady window is split into a part every bed keeps for the whole run (its offset:
  dem_err^2 less the block error^2 of the seed-mean record over the full window) and the seed-mean record's
  block error over windows f as long (compare.plate.block_estimate), scaled to give dem_err over the full
  window: err_f^2 = offset^2 + (dem_err^2 - offset^2) (block_f / block_1)^2.
  u_w_inf and mu_w_inf from series_*.csv, delta_u from delta_*.csv; creep_length has no time record (its
  duration exponent comes from the drives' durations), t90 is a transient's time (no duration exponent);
* width: the study's width check (one drive in a bed twice as wide).
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
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import FuncFormatter

ROOT = Path(__file__).resolve().parents[1]
HERE = ROOT / "bench"
STUDY_2D, STUDY_3D = ROOT / "results" / "study-disks", ROOT / "results" / "3d"
#: the committed 3D drives ran the spheres preset's bed
PRESET_3D = "spheres"
#: fractions of the steady window whose errors measure the duration exponent
FRACTIONS = (1.0, 0.5, 0.25, 0.125)
#: the record each observable's shorter windows come from: (file prefix, column)
RECORDS = {"u_w_inf": ("series", "u_w"), "mu_w_inf": ("series", "mu_w"), "delta_u": ("delta", "delta_u")}
#: the acceptance: a prediction within this factor of the error then measured
WITHIN = 1.5
#: lengths of the steady profile: one law for both drive kinds, their error in d independent of the pressure
#: (the layer's edge is placed to within the grains' structure at any pressure)
LENGTHS = ("delta_u", "creep_length")
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
        series = pd.read_csv(folder / f"series_{stem(r.drive)}.csv")
        duration = float(d.get("duration", series.t.iloc[-1]))
        t_s = float(d.get("t_s", duration / 10.0))  # 3D: the drives ran 10 t_s
        local = d["steady_local"]
        rows.append({"dimension": dimension, "drive": stem(r.drive), "kind": d["kind"], "observable": r.observable,
                     "p_w": d["p_w"], "seeds": d["seeds"], "area": area, "duration": duration, "fraction": 1.0,
                     "grain_steps": d["grains_x_steps"], "value": r.dem, "err": r.dem_err, "how": r.dem_how,
                     "u_w": local["u_w"], "mu_w": local["mu_w"], "delta_s": local["delta_s"], "t_s": t_s})
    return pd.DataFrame(rows)


def shorter_windows(folder: Path, full: pd.DataFrame) -> pd.DataFrame:
    """The errors over the final fraction f of each drive's steady window (module docstring)."""
    rows = []
    for r in full[full.observable.isin(list(RECORDS))].itertuples():
        prefix, column = RECORDS[r.observable]
        rec = pd.read_csv(folder / f"{prefix}_{r.drive}.csv").dropna(subset=[column])
        t0 = STEADY_LAST * r.duration
        y = rec[column].to_numpy()[rec.t.to_numpy() >= t0]
        block_full = block_estimate({"y": y})["stderr"]
        offset2 = max(r.err**2 - block_full**2, 0.0)
        for f in FRACTIONS:
            parts = np.array_split(y, round(1 / f))
            block = float(np.sqrt(np.mean([block_estimate({"y": p})["stderr"] ** 2 for p in parts])))
            # the fluctuating part scaled to make the full window's error the measured one
            err = np.sqrt(offset2 + (r.err**2 - offset2) * (block / block_full) ** 2)
            rows.append({**r._asdict(), "fraction": f, "duration": r.duration * f, "grain_steps": r.grain_steps * f,
                         "err": float(err), "how": "offset + blocks",
                         "block_full": block_full, "offset": np.sqrt(offset2)})
    return pd.DataFrame(rows).drop(columns="Index")


def duration_exponent(short: pd.DataFrame) -> float:
    """The mean over the drives of -d ln err / d ln duration across the shorter windows."""
    slopes = [-np.polyfit(np.log(g.fraction), np.log(g.err), 1)[0] for _, g in short.groupby("drive")]
    return float(np.mean(slopes))


def scale(rows: pd.DataFrame, observable: str) -> np.ndarray:
    name = noise.SCALES[observable]
    return np.ones(len(rows)) if name == "one" else rows[name].to_numpy(float)


def fit_laws(full: pd.DataFrame, short: pd.DataFrame) -> dict[tuple[str, str], dict]:
    """One law per (observable, kind) from 2D rows: a from the shorter windows (creep_length: from the drives'
    durations; t90: none), at least 0 (a longer window cannot add noise: a negative slope is the estimate's
    noise); then c, r, b over the drives.  LENGTHS: over both kinds at once, b held at 0."""
    out = {}
    for (obs, kind), _ in full.groupby(["observable", "kind"]):
        kinds = list(noise.SCORED) if obs in LENGTHS else [kind]
        g = full[(full.observable == obs) & full.kind.isin(kinds)]
        s = short[(short.observable == obs) & short.kind.isin(kinds)]
        held = {"r": 0.0 if noise.SCALES[obs] == "one" else None, "b": 0.0 if obs in LENGTHS else None}
        if obs == "t90":
            a, a_from = 0.0, "none (a transient's time)"
        elif len(s):
            a, a_from = duration_exponent(s), "shorter windows"
        else:
            a, a_from = noise.fit(g.err, scale(g, obs), g.seeds, g.area, g.duration, g.p_w, **held)["a"], "durations"
        law = noise.fit(g.err, scale(g, obs), g.seeds, g.area, g.duration, g.p_w, a=max(a, 0.0), **held)
        out[(obs, kind)] = {**law, "a_measured": a, "a_from": a_from}
    return out


def predict(law: dict, rows: pd.DataFrame, obs: str, c: float | None = None) -> np.ndarray:
    c = law["c"] if c is None else c
    return (c * scale(rows, obs) ** law["r"] * (rows.seeds * rows.area) ** -noise.AVERAGING
            * rows.duration ** -law["a"] * rows.p_w ** -law["b"]).to_numpy(float)


def measure() -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame, dict]:
    """The measured table (full and shorter windows, 2D and 3D, with predictions), compare/noise.csv's table,
    the held-out check and the checks' figures."""
    width_2d = dem_config.preset("quick")[0].box.width
    box_3d = dem_config.preset(PRESET_3D)[0]
    full2 = full_windows(STUDY_2D, 2, width_2d)
    full3 = full_windows(STUDY_3D, 3, box_3d.box.width * box_3d.width_z)
    short = shorter_windows(STUDY_2D, full2)
    fitted = fit_laws(full2, short)
    table = []
    for (obs, kind), law in fitted.items():
        g3 = full3[(full3.observable == obs) & (full3.kind == kind)]
        c3 = law["c"] * float(np.exp(np.mean(np.log(g3.err / predict(law, g3, obs))))) if len(g3) else np.nan
        table.append({"observable": obs, "kind": kind, "scale": noise.SCALES[obs], "c2": law["c"], "c3": c3,
                      "r": law["r"], "a": law["a"], "b": law["b"], "a_measured": law["a_measured"],
                      "a_from": law["a_from"],
                      "c3_from": "; ".join(sorted(set(g3.how))) if len(g3) else ""})
    table = pd.DataFrame(table)
    # held out: each pressure's errors predicted by the laws fitted to the other two
    held = []
    for p in sorted(full2.p_w.unique()):
        laws_p = fit_laws(full2[full2.p_w != p], short[short.p_w != p])
        for (obs, kind), g in full2[full2.p_w == p].groupby(["observable", "kind"]):
            ratio = predict(laws_p[(obs, kind)], g, obs) / g.err.to_numpy()
            held.append({"observable": obs, "kind": kind, "p_w": p, "ratio": float(np.exp(np.mean(np.log(ratio)))),
                         "worst": float(ratio[np.argmax(np.abs(np.log(ratio)))]), "drives": len(g)})
            full2.loc[g.index, "heldout"] = predict(laws_p[(obs, kind)], g, obs)
    measured = pd.concat([full2, short, full3], ignore_index=True)
    measured["predicted"] = np.nan
    for row in table.itertuples():
        for dim, c in ((2, row.c2), (3, row.c3)):
            m = (measured.observable == row.observable) & (measured.kind == row.kind) & (measured.dimension == dim)
            measured.loc[m, "predicted"] = predict(row._asdict(), measured[m], row.observable, c)
    study = json.loads((STUDY_2D / "study.json").read_text())
    (wc,) = study["width_check"]
    u = short[(short.observable == "u_w_inf") & (short.fraction == 1.0)]
    m = short[(short.observable == "mu_w_inf") & (short.fraction == 1.0)]
    checks = {"width_ratio": wc["wide_err"] / wc["normal_err"], "width_ratio_law": 2 ** -noise.AVERAGING,
              "seed_over_block_u_w": float(np.median(u.err / u.block_full)),
              "seed_over_block_mu_w": float(np.median(m.err / m.block_full))}
    return measured, table, pd.DataFrame(held), checks


OBS_LABELS = {"u_w_inf": "u_w_inf (stress drives)", "mu_w_inf": "mu_w_inf (speed drives)", "delta_u": "delta_u",
              "creep_length": "creep length", "t90": "t90"}
KIND_MARKERS = {"stress": "o", "speed": "s"}
PLAIN = FuncFormatter(lambda v, _: f"{v:g}")


def plot(measured: pd.DataFrame, path: Path) -> Path:
    """One panel per observable: relative error against grain-steps (filled: a drive's full window; open and
    joined: its shorter windows; crosses: the fitted law; grey: 3D), and the held-out check."""
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
        ax.yaxis.set_minor_formatter(PLAIN)
    ax = axes[-1]
    for obs, marker in zip(OBS_LABELS, "o^sDv"):
        g = measured[(measured.observable == obs) & measured.heldout.notna()]
        ax.scatter(g.err, g.heldout, marker=marker, c=[PRESSURE_COLOURS[p] for p in g.p_w], s=22, label=obs)
    lim = np.array([measured.err[measured.heldout.notna()].min() / 2, measured.err.max() * 2])
    ax.plot(lim, lim, "k-", lw=0.8)
    for k in (WITHIN, 1 / WITHIN):
        ax.plot(lim, k * lim, "k:", lw=0.8)
    ax.set(xscale="log", yscale="log", xlabel="measured error (spread over 4 beds)",
           ylabel="predicted with its pressure held out", title=f"held-out check (dotted: x{WITHIN:g}, 1/{WITHIN:g})")
    ax.legend(fontsize=7, loc="upper left", frameon=False)
    handles = [Line2D([], [], color=c, marker="o", ls="none", label=f"2D, p_w = {p:g}")
               for p, c in PRESSURE_COLOURS.items()]
    handles += [Line2D([], [], color="0.4", marker="o", ls="none", label="3D, p_w = 10 (2 beds)"),
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


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--plot-only", action="store_true", help="redraw the PNG from bench/dem_cost_noise.csv")
    args = parser.parse_args()
    if args.plot_only:
        measured = pd.read_csv(HERE / "dem_cost_noise.csv")
        plot(measured, HERE / "dem_cost_noise.png")
        return
    measured, table, held, checks = measure()
    measured.to_csv(HERE / "dem_cost_noise.csv", index=False, float_format="%.6g")
    table.to_csv(noise.NOISE_CSV, index=False, float_format="%.6g")
    plot(measured, HERE / "dem_cost_noise.png")
    print("| observable | drives | C_2 | C_3 | r (scale) | a (measured, from) | b |")
    print("|---|---|---|---|---|---|---|")
    for r in table.itertuples():
        print(f"| {r.observable} | {r.kind} | {r.c2:.3g} | {r.c3:.3g} | {r.r:.2f} ({r.scale}) | {r.a:.2f} "
              f"({r.a_measured:.2f}, {r.a_from}) | {r.b:.2f} |")
    pivot = held.pivot_table(index=["observable", "kind"], columns="p_w", values=["ratio", "worst"])
    print("\nheld out (predicted / measured, geometric mean over the pressure's 3 drives; worst drive):")
    print("| observable | drives | " + " | ".join(f"p_w = {p:g}" for p in sorted(held.p_w.unique())) + " |")
    print("|---|---|" + "---|" * held.p_w.nunique())
    for (obs, kind), row in pivot.iterrows():
        cells = [f"x{row[('ratio', p)]:.2f} (x{row[('worst', p)]:.2f})" for p in sorted(held.p_w.unique())]
        print(f"| {obs} | {kind} | " + " | ".join(cells) + " |")
    inside = (np.abs(np.log(held.ratio)) <= np.log(WITHIN)).sum()
    print(f"\nwithin x{WITHIN:g}: {inside} of {len(held)} (observable, kind, pressure) cells")
    print(f"width: error ratio twice as wide {checks['width_ratio']:.3f} (law {checks['width_ratio_law']:.3f})")
    print(f"seed spread / block error of the seed-mean record, median: u_w {checks['seed_over_block_u_w']:.2f}, "
          f"mu_w {checks['seed_over_block_mu_w']:.2f}")


if __name__ == "__main__":
    main()
