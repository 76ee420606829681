"""What a reader sees: numbers to the digits their errors support, and every observable and law of the reports in
words instead of its code name (the one place the pages, the findings and the verdicts take them from)."""
from __future__ import annotations

import html
import math

import numpy as np

from .rows import UNSCORED
from .scorecard import OBSERVABLES as STOKES_OBSERVABLES

#: significant digits a page prints at most (an error finer than that is shown to 1 digit beside it)
MAX_DIGITS = 6
#: values closer to zero than this are round-off of an exact zero (a fit's offset through the origin)
ROUND_OFF = 1e-12


def _decimals(err) -> int:
    """Decimals that print ``err`` to 2 significant digits."""
    return max(0, 1 - int(math.floor(math.log10(err))))


def _too_fine(value, decimals) -> bool:
    """``value`` to ``decimals`` would print more than MAX_DIGITS significant digits (or a long run of zeros)."""
    return decimals > MAX_DIGITS + 2 or bool(value) and decimals + int(math.floor(math.log10(abs(value)))) >= MAX_DIGITS


def fmt(value, err=None) -> str:
    """A number to the digits its error supports (the error to 2 significant digits), at most MAX_DIGITS
    significant digits; 4 significant digits without an error; an en dash when there is no number."""
    if value is None or not np.isfinite(value):
        return "–"
    value = 0.0 if abs(value) < ROUND_OFF else value
    if err is None or not np.isfinite(err) or err <= 0:
        return f"{value:.4g}"
    digits = _decimals(err)
    if _too_fine(value, digits):
        return f"{value:.{MAX_DIGITS}g} ± {err:.0e}"
    shown = f"{value:.{digits}f}"
    return f"{shown.lstrip('-') if float(shown) == 0 else shown} ± {err:.{digits}f}"


def fmt_band(band, err_like) -> str:
    """A band [lo, hi] to the decimals of ``err_like`` (fmt's), at most MAX_DIGITS significant digits."""
    lo, hi = band
    if not (err_like and np.isfinite(err_like) and err_like > 0):
        return f"[{lo:.3f}, {hi:.3f}]"
    if _too_fine(max(abs(lo), abs(hi)), _decimals(err_like)):
        return f"[{lo:.{MAX_DIGITS}g}, {hi:.{MAX_DIGITS}g}]"
    return f"[{lo:.{_decimals(err_like)}f}, {hi:.{_decimals(err_like)}f}]"


def fmt_cell(value) -> str:
    """A table cell: counts (and whole floats from JSON) as integers, other numbers through fmt, text escaped."""
    if isinstance(value, bool) or value is None:
        return html.escape(str(value))
    if isinstance(value, (int, np.integer)) or (isinstance(value, float) and value.is_integer()):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        return fmt(float(value))
    return html.escape(str(value))


#: a verdict's colour on a page (green consistent, red disagrees, grey not scored)
VERDICT_COLOUR = {"consistent": "#2a7", "disagrees": "#c33", **dict.fromkeys(UNSCORED, "#777")}
#: an observable of a scorecard row in words: the Stokes drives' (compare.scorecard.OBSERVABLES) and the
#: oscillating plate's (compare.oscillation.OBSERVABLES)
OBSERVABLE_WORDS = {
    **{name: words for name, (_, words) in STOKES_OBSERVABLES.items()},
    "response_amplitude": "amplitude of the plate's response",
    "phase_lag": "lag of the response behind the imposed sine",
    "yielded_depth": "depth of the dynamic zone over a cycle",
    "dissipation": "energy dissipated per cycle",
    "remobilization_strain": "strain to flow again after a reversal",
}
#: a law of a law row in words (compare.laws.LAWS, compare.oscillation.laws); a law with two quantities maps a word
#: its quantity holds to the words of that quantity
LAW_WORDS = {
    "delta_growth_exponent": "growth of the layer (its exponent in time)",
    "delta_growth_prefactor": "early depth of the layer (over the diffusive sqrt(nu_g t))",
    "u_w_sqrt_t": "early rise of the plate's speed (its exponent in time)",
    "mu_w_plateau": "early friction under an imposed speed (against mu_d)",
    "mu_w_decay_exponent": "decay of the friction towards its steady value (its exponent in time)",
    "delta_s_scaling": {"offset": "steady layer's depth beyond the yield depth delta_s (offset)",
                        "slope": "steady layer's depth against the yield depth delta_s (slope)"},
    "t_s_collapse": "response time against the layer's time scale t_s (slope)",
    "t_mud_scaling": "time for the friction to fall against the plate's speed (slope)",
    "steady_speed_law": {"exact": "steady plate speed over the paper's exact steady law",
                         "asymptote": "steady plate speed over the paper's asymptote, eq. (3.12)"},
    "creep_length_scaling": "creep length against the plate's pressure (slope)",
    "yielded_depth_exponent": "depth of the dynamic zone against the frequency (exponent)",
    "phase_lag_slope": "lag of the response against the frequency (slope in ln omega t_s)",
}

#: a model in words (the rows' ``model`` key; its long label is the scorecard's ``model_label``)
MODEL_WORDS = {"local": "local mu(I)", "paper": "the paper's model", "ngf": "NGF", "elastic": "elasto-plastic mu(I)"}


def words(name: str, quantity: str = "") -> str:
    """An observable's or a law's words (a law with two quantities: the one whose word ``quantity`` holds); a name
    this module does not know reads as its words with spaces for underscores."""
    said = LAW_WORDS.get(name, OBSERVABLE_WORDS.get(name))
    if isinstance(said, dict):
        said = next((w for key, w in said.items() if key in quantity), None)
    return said or name.replace("_", " ")
