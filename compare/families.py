"""Estimator families: each of the paper's laws (compare.laws) measured over a declared family of estimator choices,
identically on the DEM and on each model, and what the family's spread says about the law's verdict.

A ``Choice`` names what reads the response and how:

* ``estimator``: the layer's depth where u falls to each continuum.crossing.LAYER_FRACTIONS of the reference speed
  (delta_05, delta_10, delta_20, delta_50) or the velocity profile's first moment int u dy / u_ref ("moment"), both
  from continuum.crossing.layer_measures; "speed" (the plate's response under a held stress); "mu_w" (the plate's
  friction under a held speed); the time a speed takes to cover 90 % or 75 % of its change (RESPONSE_LEVELS); the
  steady speed averaged over the record's final quarter or half (STEADY_WINDOWS); the creep length fitted over
  one of compare.scorecard.CREEP_ZONES;
* ``reference``: the speed it is read against: "plate" (u_w), or "contact" (the grains touching the plate: the DEM's
  u_c in the plate record, or its coarse-grained speed at the plate's contact plane for a steady profile; a
  continuum model does not slip, so its contact speed is its u_w).  The layer's depths over time are stored against
  the plate's speed only (compare.analysis.layer_series), so the transient depths have that reference alone;
* ``from_transits``: the window's start in shear-wave transits over the bed (FROM_TRANSITS: at 3 it is compare.drive's
  elastic start, at 5 and 10 the wave has crossed the bed that many times; no start is earlier, where the load is
  still carried down by the elastic wave no rigid-plastic model has); None for a law of the steady state.

``FAMILIES`` holds each kind of law's family, its primary choice first: the depth delta_05 (U_FRACTION of the
plate's speed) from TRANSITS_BEFORE_COMPARISON transits, the plate's own speed and friction.  delta_05 is the depth
every other row of the comparison reports (the scorecard's delta_u, the steady layer's law), so a law row's headline
numbers are those of the observable the reader has seen; the verdict does not rest on that choice (below), and the
family shows how far the creep tail, which deepens the 5 % depth most, moves it.

Verdict (``family_note``): a choice is measured when it has a sigma; the law is consistent when every measured
choice is, disagrees only when every one does (each beyond its own error), and otherwise it "depends on the
estimator" (compare.rows.ESTIMATOR_DEPENDENT), with the choices on each side named.  ``systematic``: half the range,
(max - min)/2, of DEM - predicted over the measured choices: the difference, not the DEM's value, because the choices
measure different things by construction (delta_50 < delta_05 in every profile) and only the difference is scored;
NaN with fewer than two measured choices.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from granstokes.continuum.crossing import LAYER_FRACTIONS, U_FRACTION

from .drive import TRANSITS_BEFORE_COMPARISON
from .plate import STEADY_LAST
from .rows import ESTIMATOR_DEPENDENT, sigma, verdict
from .scorecard import CREEP_WINDOW, CREEP_ZONE_OFFSET, CREEP_ZONES, T90_LEVEL

#: the layer estimators: the depths at LAYER_FRACTIONS, smallest fraction (the deepest depth) first, and the moment
LAYER_ESTIMATORS = (*sorted(LAYER_FRACTIONS, key=LAYER_FRACTIONS.get), "moment")
#: the primary layer depth: delta_u, the depth at U_FRACTION of the reference speed
PRIMARY_ESTIMATOR = next(k for k, f in LAYER_FRACTIONS.items() if f == U_FRACTION)
#: the windows' starts, in shear-wave transits over the bed: the elastic start and later, never before it
FROM_TRANSITS = (TRANSITS_BEFORE_COMPARISON, 5.0, 10.0)
#: a response time: the fraction of the speed's change covered (compare.scorecard.t90's level)
RESPONSE_LEVELS = {"t90": T90_LEVEL, "t75": 0.75}
#: a steady speed: the mean over the record's final part from this fraction of it on (the final quarter:
#: compare.plate.STEADY_LAST, the DEM's steady window)
STEADY_WINDOWS = {"final quarter": STEADY_LAST, "final half": 0.5}
#: words for the estimators that are not a layer depth, given whose speed or friction they read
_WORDS = {"speed": "{whose} speed", "mu_w": "{whose} friction", "t90": "the time to 90 % of {whose} speed",
          "t75": "the time to 75 % of {whose} speed", "final quarter": "{whose} speed over the record's final quarter",
          "final half": "{whose} speed over the record's final half", "creep": "the creep length below delta_s",
          "creep_deep": f"the creep length from {CREEP_ZONE_OFFSET:g} d below delta_s",
          "creep_wide": f"the creep length over {2 * CREEP_WINDOW:g} d below delta_s"}


@dataclass(frozen=True)
class Choice:
    estimator: str
    reference: str = "plate"
    from_transits: float | None = TRANSITS_BEFORE_COMPARISON

    def describe(self) -> str:
        """'delta_05 of the plate's speed from 3 transits', 'the contact layer's speed'."""
        whose = "the plate's" if self.reference == "plate" else "the contact layer's"
        text = _WORDS.get(self.estimator, "{estimator} of {whose} speed").format(whose=whose, estimator=self.estimator)
        if self.from_transits is None:
            return text
        return f"{text} from {self.from_transits:g} transit{'' if self.from_transits == 1 else 's'}"


def _family(primary: Choice, choices) -> tuple[Choice, ...]:
    return (primary, *(c for c in choices if c != primary))


FAMILIES = {
    # the layer's growth: every depth against the plate's speed, every start
    "layer": _family(Choice(PRIMARY_ESTIMATOR),
                     [Choice(e, "plate", n) for e in LAYER_ESTIMATORS for n in FROM_TRANSITS]),
    # u_w(t) under a held stress: the plate's and the contact layer's speed, every start
    "speed": _family(Choice("speed"), [Choice("speed", r, n) for r in ("plate", "contact") for n in FROM_TRANSITS]),
    # mu_w(t) under a held speed: every start
    "friction": _family(Choice("mu_w"), [Choice("mu_w", "plate", n) for n in FROM_TRANSITS]),
    # the steady layer: every depth against the speed at the plate's contact plane
    "steady layer": _family(Choice(PRIMARY_ESTIMATOR, "contact", None),
                            [Choice(e, "contact", None) for e in LAYER_ESTIMATORS]),
    # a time to steady speed: to 90 % of the plate's and the contact layer's, to 75 % of the plate's
    "response time": (Choice("t90", "plate", None), Choice("t90", "contact", None), Choice("t75", "plate", None)),
    # the steady speed: the plate's over the final quarter and half, the contact layer's over the final quarter
    "steady speed": (Choice("final quarter", "plate", None), Choice("final half", "plate", None),
                     Choice("final quarter", "contact", None)),
    # the creep length: the steady profile's tail (against the speed at the plate's contact plane) over each zone
    "creep": tuple(Choice(zone, "contact", None) for zone in CREEP_ZONES),
}


def entry(choice: Choice, dem: float, dem_err: float, predicted: float, predicted_err: float, note: str,
          dof: float) -> dict:
    """One choice's entry in a law row's ``choices``: the choice, the DEM's and the model's values and errors,
    ``sigma`` when ``note`` (why the choice has no sigma) is empty, else NaN, and the degrees of freedom of its
    combined error (its verdict's threshold: compare.rows.critical)."""
    s = np.nan if note else sigma(dem - predicted, dem_err, predicted_err)
    return {"estimator": choice.estimator, "reference": choice.reference, "from_transits": choice.from_transits,
            "dem": float(dem), "dem_err": float(dem_err), "predicted": float(predicted),
            "predicted_err": float(predicted_err), "sigma": float(s), "dof": float(dof), "note": note}


def measured(e: dict) -> bool:
    return not e["note"] and bool(np.isfinite(e["sigma"]))


def describe(e: dict) -> str:
    """An entry's choice in words: its own ``words`` where its family names them (the oscillating plate's cycles,
    compare.oscillation.CycleChoice), else its Choice's."""
    return e.get("words") or Choice(e["estimator"], e["reference"], e["from_transits"]).describe()


def systematic(entries: list[dict]) -> float:
    """Half the range of DEM - predicted over the measured choices; NaN with fewer than two."""
    d = [e["dem"] - e["predicted"] for e in entries if measured(e)]
    return float((max(d) - min(d)) / 2) if len(d) >= 2 else np.nan


def headline(entries: list[dict]) -> int:
    """The entry a row's numbers come from: the primary (the first) when measured, else the first measured one,
    else the primary (whose note says why it has no number)."""
    return next((k for k, e in enumerate(entries) if measured(e)), 0) if not measured(entries[0]) else 0


def family_note(entries: list[dict]) -> str:
    """ESTIMATOR_DEPENDENT's note when the measured choices split between consistent and disagrees, else ""."""
    sides = {"consistent": [], "disagrees": []}
    for e in entries:
        if measured(e):
            sides[verdict(e["sigma"], dof=e["dof"])].append(e)
    if not (sides["consistent"] and sides["disagrees"]):
        return ""
    name = lambda side: "; ".join(f"{describe(e)} {e['sigma']:+.1f} sigma" for e in side)  # noqa: E731
    n = len(sides["consistent"]) + len(sides["disagrees"])
    return (f"{ESTIMATOR_DEPENDENT}: {len(sides['consistent'])} of {n} measured choices consistent "
            f"({name(sides['consistent'])}), {len(sides['disagrees'])} disagree ({name(sides['disagrees'])}); "
            f"systematic {systematic(entries):.3g}")
