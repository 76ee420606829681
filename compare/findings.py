"""One finding per effect: the scorecard rows and law rows that measure the same effect (``EFFECTS``) make one
finding, reported by its strongest robust evidence, the rows behind it and the scene checks that could fake it.

A row is *scored* when it has a sigma, its verdict is none of compare.rows.UNSCORED and (a scorecard row) it is
``scored``.  Its *robust* sigma is its sigma, or, where it carries estimator ``choices`` (compare.laws), the
choice's sigma of smallest |sigma|: the difference that survives every estimator.  A scored row *backs* its effect
when its verdict is "disagrees" with the robust sigma's sign the effect means (``Member.sign``; 0: either), and goes
*against* it when it disagrees the other way.  A finding is

* "shown": rows back it and none goes against; "mixed": both; "contradicted": only rows against it;
* "not shown": scored rows, none disagrees; "not measurable": no scored row (the rows' notes say why).

Its evidence is its scored row of largest robust |sigma|.  Its scene is every check the effect names
(``SCENE_CHECKS``) over the study's drives: which drives fail it and whether the evidence's own drive is one.
Rows that no effect claims make a finding of their own (their law or observable), so none is lost; one effect is
one finding however many rows, drives and models show it.
"""
from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np
import pandas as pd

from .plate import SLIP_MAX
from .rows import UNSCORED
from .words import MODEL_WORDS, fmt, words

#: the oscillating plate's fast cycles start at this omega t_s: from there the DEM's lag stops falling with the
#: frequency and the period nears the bed's shear-wave transit, so the remobilization after a reversal is the
#: reversal's wave, not the slow cycles' history (the committed oscillating study: a flat lag from 3 to 10)
FAST_CYCLES = 3.0
#: the failing drives a finding names per scene check (the rest are counted)
NAMED_DRIVES = 3
#: the statuses of findings no row disagrees with (see the module's docstring): a report lists them last, in this
#: order
QUIET = ("not shown", "not measurable")


def _number(v) -> float:
    """A field as a float, NaN where it is missing (None, a word)."""
    try:
        return float(v)
    except (TypeError, ValueError):
        return np.nan


@dataclass(frozen=True)
class Member:
    """The rows of an effect: a law's (``law``; only its quantities holding ``quantity``) or a scorecard observable's
    (``observable``); ``kind`` keeps the drives of one load kind ("stress" or "speed"; "": both), ``cycles`` "fast"
    or "slow" the oscillating drives on that side of FAST_CYCLES; ``sign`` the sign of DEM - model the effect means
    (0: a difference either way)."""

    law: str = ""
    quantity: str = ""
    observable: str = ""
    kind: str = ""
    cycles: str = ""
    sign: int = 0

    def takes(self, row: dict) -> bool:
        if self.kind and row.get("kind") != self.kind:
            return False
        if self.law:
            if row.get("law") != self.law or self.quantity not in str(row.get("quantity", "")):
                return False
        elif row.get("observable") != self.observable:
            return False
        if self.cycles:
            return (_number(row.get("omega_ts")) >= FAST_CYCLES) == (self.cycles == "fast")
        return True


@dataclass(frozen=True)
class Effect:
    """An effect in words, the rows that measure it (of ``models`` only; (): every model's), and the scene checks
    (SCENE_CHECKS keys) that could fake it."""

    name: str
    members: tuple[Member, ...]
    scene: tuple[str, ...] = ()
    models: tuple[str, ...] = ()

    def member(self, row: dict) -> Member | None:
        if self.models and row.get("model") not in self.models:
            return None
        return next((m for m in self.members if m.takes(row)), None)


@dataclass(frozen=True)
class SceneCheck:
    """A check of the scene in words: what it checks, what a drive that fails it shows (a report's ``scene`` gives
    it per drive)."""

    key: str
    what: str
    fails: str


SCENE_CHECKS = {c.key: c for c in (
    SceneCheck("slip", "the plate's grip", f"the plate slips by more than {SLIP_MAX * 100:g} %"),
    SceneCheck("stresses", "the stresses' balance", "the coarse-grained stresses miss the plate's or the bed's weight"),
    SceneCheck("base", "the base", "the flow reaches the base"),
    SceneCheck("depth", "the bed's depth", "the bed leaves less than the depth study's clearance below delta_s"),
    SceneCheck("transit", "the elastic transit", "the elastic transit is not short against the drive's time"),
    SceneCheck("record", "the record's length", "the record is short (the DEM or a model is not steady in it)"),
    SceneCheck("periodic", "the periodic state", "a bed is not periodic"),
)}

#: the models with no flow below yield (the elasto-plastic one only loads elastically there): one effect of the layer
RIGID_BELOW_YIELD = ("local", "paper", "elastic")
#: the layer's rows: its steady depth, creep, early depth and growth, its offset beyond delta_s; ``sign``: a layer
#: deeper in the DEM (and so, deep from the start, growing more slowly)
_LAYER = (Member(observable="delta_u", sign=1), Member(observable="creep_length", sign=1),
          Member(law="delta_growth_prefactor", sign=1), Member(law="delta_growth_exponent", sign=-1),
          Member(law="delta_s_scaling", quantity="offset", sign=1), Member(law="creep_length_scaling"))
EFFECTS = (
    Effect("The DEM's layer is deeper than the models' that are rigid below yield: creep and elastic loading below "
           "the flowing layer", _LAYER, ("depth", "base", "transit", "record", "slip"), RIGID_BELOW_YIELD),
    Effect("NGF's layer differs from the DEM's", tuple(Member(m.law, m.quantity, m.observable) for m in _LAYER),
           ("depth", "base", "record", "slip"), ("ngf",)),
    Effect("The steady layer grows with the yield depth delta_s otherwise than the model's",
           (Member(law="delta_s_scaling", quantity="slope"),), ("depth", "base", "record")),
    Effect("Under an imposed stress the DEM responds more slowly than the model",
           (Member(observable="t90", kind="stress", sign=1), Member(law="t_s_collapse"), Member(law="u_w_sqrt_t")),
           ("transit", "record", "slip", "depth")),
    Effect("Under an imposed speed the DEM's friction falls sooner than the model's: below it early, steady sooner",
           (Member(law="mu_w_plateau", sign=-1), Member(observable="t90", kind="speed", sign=-1),
            Member(law="mu_w_decay_exponent"), Member(law="t_mud_scaling")), ("transit", "slip", "record", "depth")),
    Effect("The steady plate speed and friction differ from the model's",
           (Member(observable="u_w_inf"), Member(observable="mu_w_inf"), Member(law="steady_speed_law")),
           ("slip", "stresses", "record", "base", "depth")),
    Effect("The stress reversal travels down as an elastic wave: the lag stops following the frequency",
           (Member(observable="phase_lag"), Member(law="phase_lag_slope"),
            Member(observable="remobilization_strain", cycles="fast")), ("transit", "slip", "periodic")),
    Effect("After a slow reversal the DEM needs more strain than the model to flow again (history)",
           (Member(observable="remobilization_strain", cycles="slow", sign=1),), ("slip", "periodic")),
    Effect("The dynamic zone's depth differs from the model's",
           (Member(observable="yielded_depth"), Member(law="yielded_depth_exponent")), ("periodic", "slip", "transit")),
    Effect("The plate's response amplitude and the energy it dissipates differ from the model's",
           (Member(observable="response_amplitude"), Member(observable="dissipation")), ("slip", "periodic")),
)


def scored(row: dict) -> bool:
    """Whether a row is scored (see the module's docstring)."""
    return (row.get("verdict") not in UNSCORED and bool(row.get("scored", True))
            and np.isfinite(_number(row.get("sigma"))))


def choices(row: dict) -> list[dict]:
    """A row's estimator choices with a finite sigma (none when it has no ``choices``; a CSV's JSON text read)."""
    c = row.get("choices")
    if isinstance(c, str):
        c = json.loads(c) if c.strip() else []
    return [x for x in c if np.isfinite(_number(x.get("sigma")))] if isinstance(c, list) else []


def robust_sigma(row: dict) -> tuple[float, dict | None]:
    """A row's robust sigma and the estimator choice it comes from (None: the row has no choices)."""
    family = choices(row)
    if not family:
        return _number(row.get("sigma")), None
    best = min(family, key=lambda c: abs(_number(c["sigma"])))
    return _number(best["sigma"]), best


@dataclass(frozen=True)
class SceneState:
    """One scene check over the drives: how many have it, which fail it (with why), how many cannot tell."""

    check: SceneCheck
    drives: int
    failing: tuple[str, ...]
    unknown: int
    evidence_fails: bool

    @property
    def holds(self) -> bool | None:
        """True when every drive passes, False when one fails, None when no drive can tell."""
        return False if self.failing else (None if self.unknown == self.drives else True)

    def text(self) -> str:
        """The failing drives in words (named up to NAMED_DRIVES), or the check with "holds" or "not known"."""
        if not self.failing:
            return f"{self.check.what}: {'holds' if self.holds else 'not known'}"
        named = "; ".join(self.failing[:NAMED_DRIVES]) + ("; …" if len(self.failing) > NAMED_DRIVES else "")
        own = ", the evidence's drive among them" if self.evidence_fails else ""
        return f"{self.check.fails} in {len(self.failing)} of {self.drives} drives ({named}){own}"


@dataclass(frozen=True)
class Finding:
    """One effect's finding: status, evidence (its row, robust sigma and choice), the rows behind it, the scene."""

    effect: str
    status: str
    evidence: dict | None
    robust: float
    choice: dict | None
    scored: int
    backing: int
    against: int
    unscored: int
    why: tuple[str, ...]
    scene: tuple[SceneState, ...]


def _scene(effect: Effect, scene: list[dict], evidence: dict | None, names: dict) -> tuple[SceneState, ...]:
    out = []
    for key in effect.scene:
        checks = [s for s in scene if s["check"] == key]
        failing = [s for s in checks if s["holds"] is False]
        out.append(SceneState(
            SCENE_CHECKS[key], len({s["drive"] for s in checks}),
            tuple(f"{names.get(s['drive'], s['drive'])}: {s['detail']}" for s in failing),
            len([s for s in checks if s["holds"] is None]),
            evidence is not None and any(s["drive"] == evidence.get("drive") for s in failing)))
    return tuple(out)


def _finding(effect: Effect, rows: list[dict], scene: list[dict], names: dict) -> Finding:
    kept = [r for r in rows if scored(r)]
    backing = against = 0
    for r in kept:
        if r.get("verdict") == "disagrees":
            sign = effect.member(r).sign
            if sign == 0 or np.sign(robust_sigma(r)[0]) == sign:
                backing += 1
            else:
                against += 1
    evidence = max(kept, key=lambda r: abs(robust_sigma(r)[0])) if kept else None
    robust, choice = robust_sigma(evidence) if evidence is not None else (np.nan, None)
    status = ("not measurable" if not kept else "mixed" if backing and against else "shown" if backing
              else "contradicted" if against else "not shown")
    why = tuple(dict.fromkeys(str(r.get("note") or r.get("verdict")) for r in rows if not scored(r)))
    return Finding(effect.name, status, evidence, robust, choice, len(kept), backing, against, len(rows) - len(kept),
                   why, _scene(effect, scene, evidence, names))


def _records(table: pd.DataFrame | None, kinds: dict) -> list[dict]:
    """A table's rows as dicts, each with its load ``kind`` (its own, else its drive's in ``kinds``, else "")."""
    rows = [] if table is None or table.empty else table.to_dict("records")
    return [{**r, "kind": r["kind"] if isinstance(r.get("kind"), str) and r["kind"] else kinds.get(r.get("drive"), "")}
            for r in rows]


def findings(rows: pd.DataFrame | None, laws: pd.DataFrame | None, scene: list[dict] = (), names: dict | None = None,
             kinds: dict | None = None, effects: tuple[Effect, ...] = EFFECTS) -> list[Finding]:
    """The findings of a study's scorecard ``rows`` and ``laws``: one per effect with rows, then one per law or
    observable no effect claims, in a report's order (``_order``).  ``scene``: each drive's checks
    ({"check": a SCENE_CHECKS key, "drive", "holds": True, False or None, "detail": why in words}); ``names``: the
    drives' labels as a reader sees them; ``kinds``: each drive's load kind, for rows that do not carry theirs."""
    names, kinds = names or {}, kinds or {}
    every = _records(rows, kinds) + _records(laws, kinds)
    claimed, out = set(), []
    for effect in effects:
        members = [k for k, r in enumerate(every) if effect.member(r) is not None]
        claimed.update(members)
        if members:
            out.append(_finding(effect, [every[k] for k in members], list(scene), names))
    rest = {}
    for k, r in enumerate(every):
        if k not in claimed:
            member = Member(law=r["law"]) if "law" in r else Member(observable=r["observable"])
            rest.setdefault(member, []).append(r)
    for member, group in rest.items():
        name = words(member.law or member.observable, str(group[0].get("quantity", "")))
        out.append(_finding(Effect(name[:1].upper() + name[1:], (member,)), group, list(scene), names))
    return sorted(out, key=_order)


def _order(f: Finding) -> tuple[int, float]:
    """Findings whose rows disagree first, then QUIET's in order; within each, strongest robust evidence first."""
    return 1 + QUIET.index(f.status) if f.status in QUIET else 0, -abs(np.nan_to_num(f.robust))


def where(row: dict, names: dict) -> str:
    """Where a row was measured, in words: its drive, or the drives its law pools (their kind and amplitude)."""
    if "drive" in row:
        return names.get(row["drive"], row["drive"])
    n = int(_number(row.get("n_drives"))) if np.isfinite(_number(row.get("n_drives"))) else 0
    kind = f" of imposed {row['kind']}" if isinstance(row.get("kind"), str) and row["kind"] else ""
    amplitude = _number(row.get("amplitude"))
    return f"across {n} drives{kind}" + (f", amplitude {amplitude:.3g}" if np.isfinite(amplitude) else "")


def evidence_text(f: Finding, names: dict | None = None) -> str:
    """The finding's strongest robust evidence in one sentence (empty when no row is scored)."""
    r = f.evidence
    if r is None:
        return ""
    what = words(r.get("law") or r.get("observable"), str(r.get("quantity", "")))
    unit = "" if r.get("unit") in ("1", "-", None) else f" {r['unit']}"
    dof = _number(r.get("dof"))
    text = (f"{what}, {where(r, names or {})}, {MODEL_WORDS.get(r['model'], r['model'])}: DEM "
            f"{fmt(_number(r.get('dem')), _number(r.get('dem_err')))}{unit} against {fmt(_number(r.get('predicted')))}"
            f"{unit}, {f.robust:+.1f} σ" + (f" with {dof:.0f} degrees of freedom" if np.isfinite(dof) else ""))
    if f.choice is not None:
        text += f"; the smallest over its {len(choices(r))} estimator choices ({_choice_words(f.choice)})"
    return text


def _choice_words(choice: dict) -> str:
    parts = [str(choice.get("estimator", "")), str(choice.get("reference", ""))]
    start = _number(choice.get("from_transits"))
    parts.append(f"from {start:g} transits" if np.isfinite(start) else "")
    return ", ".join(p for p in parts if p)


def rows_text(f: Finding) -> str:
    """How many rows stand behind a finding, in words."""
    if not f.scored:
        return f"none of {f.unscored} scored"
    text = f"{f.backing} of {f.scored} scored rows disagree as it says"
    if f.against:
        text += f", {f.against} the other way"
    return text + (f"; {f.unscored} not scored" if f.unscored else "")


def scene_text(f: Finding) -> str:
    """The scene checks that could fake a finding: those that fail, then those that hold, then those no drive can
    tell."""
    out = [s.text() for s in f.scene if s.holds is False]
    for state, said in ((True, "holds in every drive"), (None, "not known")):
        checks = [s.check.what for s in f.scene if s.holds is state]
        if checks:
            out.append(f"{', '.join(checks)}: {said}")
    return "; ".join(out)


def as_dict(f: Finding, names: dict | None = None) -> dict:
    """A finding as metrics.json holds it: its words, its evidence row's identity and numbers, its counts, scene."""
    r = f.evidence or {}
    identity = {k: r[k] for k in ("law", "quantity", "drive", "observable", "model", "kind", "amplitude") if k in r}
    return {"finding": f.effect, "status": f.status, "evidence": evidence_text(f, names),
            "evidence_row": {**identity, **{k: r.get(k) for k in ("dem", "dem_err", "predicted", "sigma", "dof")
                                            if k in r}, "robust_sigma": f.robust, "choice": f.choice} if r else None,
            "rows_scored": f.scored, "rows_backing": f.backing, "rows_against": f.against,
            "rows_not_scored": f.unscored, "why_not_scored": list(f.why),
            "scene": [{"check": s.check.key, "holds": s.holds, "drives": s.drives, "failing": list(s.failing),
                       "text": s.text()} for s in f.scene]}
