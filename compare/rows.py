"""The comparison's rows and the one rule that gives each its verdict.

Every experiment (compare.experiment) writes two kinds of row:

* a **scorecard row** per drive x model x observable (``ROW_KEYS``; an experiment adds its own keys after them):
  the DEM's value with its error and how it was estimated, the model's prediction with its numerical error and
  its calibration standard deviation (compare.band), the 95 % band predicted -+ Z95 sd, sigma and ``dof``;
* a **law row** per law x model (``LAW_KEYS``, plus the experiment's own): the same estimator fitted on the DEM and on
  each model over the same window and drives, the drives' ``kind`` it reads ("stress", "speed", or "both" for a law
  across kinds), its ``dof`` and, for a law fitted as a line, the DEM fit's reduced chi-square ``chi2_dof`` (NaN for
  a law that is not such a fit); a line whose DEM points are improbably far from it (``not_a_line``: chi2.sf(chi2,
  n - 2) < LACK_OF_FIT_P) is "not measurable: not a line".

sigma = (DEM - predicted) / sqrt(dem_err^2 + numerical_err^2 + calibration_sd^2), the difference of phases wrapped
into (-pi, pi] by the experiment.  Errors from a few beds, seeds or blocks are not Gaussian: every error carries its
degrees of freedom (a spread over n samples: n - 1; a slope through n points: n - 2; a numerical error or a
calibration band: infinite), and a row's ``dof`` is the Welch-Satterthwaite degrees of freedom of its combined error
(``effective_dof``).  ``verdict``: "consistent" when |sigma| <= t_0.975(dof), Student-t's 97.5 % quantile at the
row's dof (``critical``: 4.30 at 2 dof, 3.18 at 3, Z95 = 1.96 at infinitely many), else "disagrees": a 95 % test
whatever the number of samples.  The threshold is not a column: ``critical(dof)`` gives it from the row's dof.  A row
that cannot be scored carries a note that starts with why, and its verdict is that note's head: "not scored" (the
scene cannot support it), "not predicted" (the model has no prediction for it), "not measurable" (the data give no
value or no error).  A law row measured over an estimator family (compare.families) whose choices split, some
consistent and some not, has the note's head ESTIMATOR_DEPENDENT as its verdict: neither consistent nor disagrees.
"""
from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats

#: the verdict's confidence: a consistent row is within the two-sided CONFIDENCE interval of its difference
CONFIDENCE = 0.95
#: the two-sided 95 % normal quantile: a band is predicted -+ Z95 sd, and the verdict's threshold at infinite dof
Z95 = float(stats.norm.ppf((1 + CONFIDENCE) / 2))
#: what an unscored row's note starts with (its verdict)
UNSCORED = ("not scored", "not predicted", "not measurable")
#: the verdict of a law whose estimator family splits (compare.families.family_note)
ESTIMATOR_DEPENDENT = "depends on the estimator"
#: a law fitted as a line is "not a line" when the DEM's chi-square about it is this improbable (lack of fit)
LACK_OF_FIT_P = 0.01
ROW_KEYS = ("drive", "observable", "unit", "dem", "dem_err", "dem_how", "model", "model_label", "predicted", "band",
            "numerical_err", "calibration_sd", "sigma", "dof", "verdict", "scored", "note", "blind")
LAW_KEYS = ("law", "quantity", "unit", "kind", "model", "dem", "dem_err", "predicted", "predicted_err", "band",
            "sigma", "dof", "chi2_dof", "verdict", "n_drives", "window", "note", "choices", "systematic")


def critical(dof: float) -> float:
    """The |sigma| up to which a row is consistent at CONFIDENCE: Student-t's 97.5 % quantile at ``dof`` degrees of
    freedom (fractional ones too, as ``effective_dof`` gives them); Z95 at dof = inf."""
    if not dof > 0:
        raise ValueError(f"a verdict needs positive degrees of freedom, not {dof}")
    return Z95 if np.isinf(dof) else float(stats.t.ppf((1 + CONFIDENCE) / 2, dof))


def effective_dof(errors, dofs) -> float:
    """Welch-Satterthwaite degrees of freedom of sqrt(sum e_i^2): (sum e_i^2)^2 / sum(e_i^4 / dof_i).  An error with
    infinitely many (a numerical error, a calibration band) adds to the numerator only; inf when every error has
    infinitely many or none is above zero; NaN when an error is not finite."""
    e2 = np.square(np.asarray(errors, dtype=float))
    dofs = np.asarray(dofs, dtype=float)
    if not np.all(np.isfinite(e2)):
        return np.nan
    finite = np.isfinite(dofs) & (e2 > 0)
    with np.errstate(divide="ignore"):  # an error with no degree of freedom makes the whole have none
        denominator = float(np.sum(e2[finite] ** 2 / dofs[finite]))
    return float(np.sum(e2) ** 2 / denominator) if denominator > 0 else np.inf


def verdict(sigma: float, note: str = "", dof: float = np.inf) -> str:
    """The verdict of a row: its note's head when it has one (UNSCORED or ESTIMATOR_DEPENDENT), else consistent when
    |sigma| is within ``critical(dof)``, disagrees beyond."""
    if note:
        heads = (*UNSCORED, ESTIMATOR_DEPENDENT)
        head = next((h for h in heads if note.startswith(h)), None)
        if head is None:
            raise ValueError(f"a row's note must start with one of {heads}: {note!r}")
        return head
    return "consistent" if abs(sigma) <= critical(dof) else "disagrees"


def not_a_line(chi2: float, dof: int) -> str:
    """The lack-of-fit note of a line whose DEM points have the weighted squared residuals ``chi2`` about it with
    ``dof`` degrees of freedom (points - 2), or "" when chi2.sf(chi2, dof) is at least LACK_OF_FIT_P: a step or a bend
    through the points, whose slope is no number to score."""
    p = float(stats.chi2.sf(chi2, dof))
    return f"not measurable: not a line (chi2/dof = {chi2 / dof:.3g}, p = {p:.2g})" if p < LACK_OF_FIT_P else ""


def sigma(difference: float, *errors: float) -> float:
    """difference / the errors added in quadrature; NaN when they are all zero or one is not finite."""
    combined = float(np.sqrt(np.sum(np.square(errors))))
    return float(difference) / combined if np.isfinite(combined) and combined > 0 else np.nan


def band(predicted: float, sd: float) -> list[float]:
    """The 95 % band of a prediction with standard deviation ``sd``."""
    return [float(predicted - Z95 * sd), float(predicted + Z95 * sd)]


def _row(keys: tuple[str, ...], fields: dict, **derived) -> dict:
    """``keys`` first, then the experiment's own; ``derived``: key -> its value from the other fields."""
    missing = [k for k in keys if k not in fields and k not in derived]
    if missing:
        raise KeyError(f"a row needs {missing}")
    fields = {**fields, **{k: f(fields) for k, f in derived.items()}}
    return {**{k: fields[k] for k in keys}, **{k: v for k, v in fields.items() if k not in keys}}


def score_row(**fields) -> dict:
    """A scorecard row: ``ROW_KEYS`` first (verdict and scored from sigma, note and dof), the experiment's keys
    after."""
    return _row(ROW_KEYS, fields, verdict=lambda f: verdict(f["sigma"], f.get("note", ""), f["dof"]),
                scored=lambda f: not f.get("note", ""))


def law_row(**fields) -> dict:
    """A law row: ``LAW_KEYS`` first (band from predicted_err, verdict from sigma, note and dof), the experiment's
    after."""
    return _row(LAW_KEYS, fields, band=lambda f: band(f["predicted"], f["predicted_err"]),
                verdict=lambda f: verdict(f["sigma"], f.get("note", ""), f["dof"]))


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
