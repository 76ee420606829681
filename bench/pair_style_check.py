"""The classic contact law (`gran/hooke/history`, the default) against `pair_style granular` in 3D: the spheres
grains' plane-shear calibration and one drive of each kind, run in both styles from the same seeds, compared within
their errors.

    .venv/bin/python bench/pair_style_check.py    # reads the committed results, writes bench/pair_style_check.csv

Classic: `results/calibration-spheres/p20` (its points from I = 0.0025 on) and the p_w = 10 drives of
`results/study-spheres` (4 beds each). Granular: `results/pair-style-spheres` (the same points and seeds, the same
drives' configs and seeds; its README gives the commands).  Each row compares one quantity's seed mean in the two
styles: Welch's t (each side's standard error of its seed mean, n - 1 degrees of freedom; the Welch-Satterthwaite
degrees of freedom of the difference), its two-sided p, the difference relative to the classic value with its 95 %
interval, and Holm's step-down over the whole table: the styles differ, at 95 % for the family, only where Holm
rejects. With 2-4 seeds a side a row that Holm does not reject is a difference too small to detect, not an
agreement: the intervals say how small.  Calibration rows: mu and phi at each inertial number
(the cells' own I differ by under 1 %); drive rows: each scored observable of the scorecard (the DEM's value, the
same under every model), the drives' DEM errors the spread over their beds.
"""
from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

ROOT = Path(__file__).resolve().parents[1]
CLASSIC_CALIBRATION = ROOT / "results" / "calibration-spheres" / "p20"
CLASSIC_STUDY = ROOT / "results" / "study-spheres"
GRANULAR = ROOT / "results" / "pair-style-spheres"
OUT = ROOT / "bench" / "pair_style_check.csv"
#: the drives compared: the classic study's p_w = 10 drives, the granular runs' same drives
PRESSURE = "p10"
#: the family's level
ALPHA = 0.05


def welch(a: float, ea: float, na: int, b: float, eb: float, nb: int) -> tuple[float, float, float, float]:
    """t, its Welch-Satterthwaite degrees of freedom, the two-sided p of a - b and the half-width of its 95 %
    interval, each side a mean of n samples with standard error e."""
    var = ea**2 + eb**2
    dof = var**2 / (ea**4 / (na - 1) + eb**4 / (nb - 1))
    t = (a - b) / np.sqrt(var)
    return float(t), float(dof), float(2 * stats.t.sf(abs(t), dof)), float(stats.t.ppf(0.975, dof) * np.sqrt(var))


def holm(p: np.ndarray, alpha: float = ALPHA) -> np.ndarray:
    """Holm's step-down: which of the p-values are rejected at family level ``alpha``."""
    order = np.argsort(p)
    reject = np.zeros(len(p), dtype=bool)
    for rank, k in enumerate(order):
        if p[k] > alpha / (len(p) - rank):
            break
        reject[k] = True
    return reject


def _cells(points: pd.DataFrame, targets: list[float]) -> dict[float, pd.DataFrame]:
    """Each target inertial number's cells (the nearest in log I, within 10 %)."""
    out = {}
    for target in targets:
        near = points[np.abs(np.log(points.I / target)) < 0.1]
        if len(near):
            out[target] = near
    return out


def calibration_rows() -> list[dict]:
    targets = json.loads((GRANULAR / "calibration" / "calibration.json").read_text())["protocol"]["points"]
    targets = [p["I"] for p in targets]
    classic = _cells(pd.read_csv(CLASSIC_CALIBRATION / "points.csv"), targets)
    granular = _cells(pd.read_csv(GRANULAR / "calibration" / "points.csv"), targets)
    rows = []
    for target in targets:
        if target not in classic or target not in granular:
            continue
        c, g = classic[target], granular[target]
        for q in ("mu", "phi"):
            a, b = g[q].to_numpy(), c[q].to_numpy()
            if len(a) < 2 or len(b) < 2:
                continue
            ea, eb = a.std(ddof=1) / np.sqrt(len(a)), b.std(ddof=1) / np.sqrt(len(b))
            rows.append({"part": "calibration", "where": f"I = {target:g}", "quantity": q,
                         "granular": a.mean(), "granular_err": ea, "granular_n": len(a),
                         "classic": b.mean(), "classic_err": eb, "classic_n": len(b)})
    return rows


def _dem_rows(metrics: Path, pressure: str | None = None) -> dict[tuple[str, str], dict]:
    """The DEM's value of each observable of the drives (of the run ``pressure`` only, if given) by (drive kind,
    observable), where it has a spread over beds."""
    rows = {}
    for r in json.loads(metrics.read_text())["scorecard"]:
        drive = str(r["drive"])
        if pressure is not None and f"/{pressure}/" not in f"/{drive}":
            continue
        n = re.search(r"spread over (\d+) seeds", str(r["dem_how"]))
        if n is None or not np.isfinite(r["dem_err"]):
            continue
        kind = drive.rsplit("/", 1)[-1].split("-")[0]
        rows[(kind, r["observable"])] = {"value": r["dem"], "err": r["dem_err"], "n": int(n.group(1))}
    return rows


def drive_rows() -> list[dict]:
    classic = _dem_rows(CLASSIC_STUDY / "metrics.json", PRESSURE)
    granular = _dem_rows(GRANULAR / "drives" / "metrics.json")
    rows = []
    for key in sorted(set(classic) & set(granular)):
        c, g = classic[key], granular[key]
        rows.append({"part": "drives", "where": f"p_w = 10, imposed {key[0]}", "quantity": key[1],
                     "granular": g["value"], "granular_err": g["err"], "granular_n": g["n"],
                     "classic": c["value"], "classic_err": c["err"], "classic_n": c["n"]})
    return rows


def check() -> pd.DataFrame:
    table = pd.DataFrame(calibration_rows() + drive_rows())
    tests = [welch(r.granular, r.granular_err, r.granular_n, r.classic, r.classic_err, r.classic_n)
             for r in table.itertuples()]
    table["t"], table["dof"], table["p"], half = np.array(tests).T
    # the difference granular - classic with its 95 % interval, relative to the classic value
    table["difference"] = (table.granular - table.classic) / table.classic.abs()
    table["ci95_low"], table["ci95_high"] = table.difference - half / table.classic.abs(), \
        table.difference + half / table.classic.abs()
    table["holm_rejects"] = holm(table.p.to_numpy())
    return table


def main() -> None:
    table = check()
    table.to_csv(OUT, index=False, float_format="%.6g")
    print("| part | where | quantity | granular (seeds) | classic (seeds) | t (dof) | p | granular/classic - 1, 95 % |")
    print("|---|---|---|---|---|---|---|---|")
    for r in table.itertuples():
        print(f"| {r.part} | {r.where} | {r.quantity} | {r.granular:.4g} ± {r.granular_err:.2g} ({r.granular_n}) | "
              f"{r.classic:.4g} ± {r.classic_err:.2g} ({r.classic_n}) | {r.t:+.2f} ({r.dof:.1f}) | {r.p:.3f} | "
              f"{100 * r.difference:+.1f} % [{100 * r.ci95_low:+.1f}, {100 * r.ci95_high:+.1f}] |")
    below = int((table.p < ALPHA).sum())
    print(f"\n{len(table)} rows; {below} with p < {ALPHA:g} (expected by chance: {ALPHA * len(table):.1f}); "
          f"Holm rejects {int(table.holm_rejects.sum())} at family level {ALPHA:g}")


if __name__ == "__main__":
    main()
