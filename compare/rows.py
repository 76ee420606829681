"""The comparison's rows and the one rule that gives each its verdict.

Every experiment (compare.experiment) writes two kinds of row:

* a **scorecard row** per drive x model x observable (``ROW_KEYS``; an experiment adds its own keys after them):
  the DEM's value with its error and how it was estimated, the model's prediction with its numerical error and
  its calibration standard deviation (compare.band), the 95 % band predicted -+ Z95 sd, and sigma;
* a **law row** per law x model (``LAW_KEYS``, plus the experiment's own): the same estimator fitted on the DEM and on
  each model over the same window and drives.

sigma = (DEM - predicted) / sqrt(dem_err^2 + numerical_err^2 + calibration_sd^2), the difference of phases wrapped
into (-pi, pi] by the experiment.  ``verdict``: "consistent" when |sigma| <= SIGMA_CONSISTENT, else "disagrees"; a
row that cannot be scored carries a note that starts with why, and its verdict is that note's head: "not scored"
(the scene cannot support it), "not predicted" (the model has no prediction for it), "not measurable" (the data
give no value or no error).  A law row measured over an estimator family (compare.families) whose choices split, some
consistent and some not, has the note's head ESTIMATOR_DEPENDENT as its verdict: neither consistent nor disagrees.
"""
from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats

#: |sigma| at or below which a prediction is consistent with the DEM
SIGMA_CONSISTENT = 2.0
#: the two-sided 95 % normal quantile: a band is predicted -+ Z95 sd
Z95 = float(stats.norm.ppf(0.975))
#: what an unscored row's note starts with (its verdict)
UNSCORED = ("not scored", "not predicted", "not measurable")
#: the verdict of a law whose estimator family splits (compare.families.family_note)
ESTIMATOR_DEPENDENT = "depends on the estimator"
ROW_KEYS = ("drive", "observable", "unit", "dem", "dem_err", "dem_how", "model", "model_label", "predicted", "band",
            "numerical_err", "calibration_sd", "sigma", "verdict", "scored", "note", "blind")
LAW_KEYS = ("law", "quantity", "unit", "model", "dem", "dem_err", "predicted", "predicted_err", "band", "sigma",
            "verdict", "n_drives", "window", "note", "choices", "systematic")


def verdict(sigma: float, note: str = "") -> str:
    """The verdict of a row: its note's head when it has one (UNSCORED or ESTIMATOR_DEPENDENT), else consistent or
    disagrees by |sigma|."""
    if note:
        heads = (*UNSCORED, ESTIMATOR_DEPENDENT)
        head = next((h for h in heads if note.startswith(h)), None)
        if head is None:
            raise ValueError(f"a row's note must start with one of {heads}: {note!r}")
        return head
    return "consistent" if abs(sigma) <= SIGMA_CONSISTENT else "disagrees"


def sigma(difference: float, *errors: float) -> float:
    """difference / the errors added in quadrature; NaN when they are all zero or one is not finite."""
    combined = float(np.sqrt(np.sum(np.square(errors))))
    return float(difference) / combined if np.isfinite(combined) and combined > 0 else np.nan


def band(predicted: float, sd: float) -> list[float]:
    """The 95 % band of a prediction with standard deviation ``sd``."""
    return [float(predicted - Z95 * sd), float(predicted + Z95 * sd)]


def _row(keys: tuple[str, ...], fields: dict) -> dict:
    missing = [k for k in keys if k not in fields]
    if missing:
        raise KeyError(f"a row needs {missing}")
    return {**{k: fields[k] for k in keys}, **{k: v for k, v in fields.items() if k not in keys}}


def score_row(**fields) -> dict:
    """A scorecard row: ``ROW_KEYS`` first (verdict and scored from sigma and note), the experiment's keys after."""
    note = fields.get("note", "")
    fields.update(verdict=verdict(fields["sigma"], note), scored=not note)
    return _row(ROW_KEYS, fields)


def law_row(**fields) -> dict:
    """A law row: ``LAW_KEYS`` first (band from predicted_err, verdict from sigma and note), the experiment's after."""
    fields.update(band=band(fields["predicted"], fields["predicted_err"]),
                  verdict=verdict(fields["sigma"], fields.get("note", "")))
    return _row(LAW_KEYS, fields)


def tally(rows: pd.DataFrame) -> pd.DataFrame:
    """Per model, over the scored blind rows that every such model has (same drive and observable): rows,
    consistent rows, their share and the median |sigma|, best first; empty when no row is shared."""
    use = rows[rows.scored & rows.blind] if len(rows) else rows
    if use.empty:
        return pd.DataFrame(columns=["model", "label", "n", "consistent", "share", "median_abs_sigma"])
    keys = set.intersection(*(set(zip(g.drive, g.observable)) for _, g in use.groupby("model")))
    shared = use[[k in keys for k in zip(use.drive, use.observable)]]
    out = shared.groupby("model", sort=False).agg(
        label=("model_label", "first"), n=("sigma", "size"),
        consistent=("verdict", lambda v: int((v == "consistent").sum())),
        median_abs_sigma=("sigma", lambda v: float(np.median(np.abs(v))))).reset_index()
    out["share"] = out.consistent / out.n
    return out.sort_values(["share", "median_abs_sigma"], ascending=[False, True], ignore_index=True)
