"""What a drive imposes at the plate, defined once for every layer: the plate pressure p_w and either the wall
friction mu_w (an imposed shear stress tau_w = mu_w p_w) or the plate speed u_w, held from t = 0 (Stokes' first
problem, ``omega`` = 0) or as the amplitude of a sine, tau_w(t) = mu_w p_w sin(omega t) or u_w(t) = u_w sin(omega t)
(Stokes' second problem, the oscillating plate, ``omega`` > 0).  DEM units (rho_p g d, sqrt(g d), sqrt(g/d)).  dem's
sizing builds it, run.json stores it (``as_record``: kind, tau_w, u_w, omega), compare reads it back
(``from_record``) and the models take it: a solver on the scene reads the wall's value at time t (``wall``; ``wave``:
its factor of time) inside its rate, so a time-dependent wall never changes the problem."""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from granstokes.lib.validate import finite, require

from .scales import Material, Scales

KINDS = ("stress", "speed")


@dataclass(frozen=True)
class Load:
    kind: str
    p_w: float
    mu_w: float | None = None
    u_w: float | None = None
    omega: float = 0.0

    def __post_init__(self):
        require(self.kind in KINDS, "load kind", f"one of {KINDS}", self.kind)
        require(finite(self.p_w) and self.p_w > 0, "p_w", "a finite number > 0", self.p_w)
        given = "mu_w" if self.kind == "stress" else "u_w"
        other = "u_w" if self.kind == "stress" else "mu_w"
        value = getattr(self, given)
        require(finite(value) and value > 0, given, f"a finite number > 0 for an imposed {self.kind}", value)
        require(getattr(self, other) is None, other, f"left out of an imposed {self.kind}", getattr(self, other))
        require(finite(self.omega) and self.omega >= 0, "omega", "a finite angular frequency >= 0 (0: held)",
                self.omega)

    def plate_friction(self, t, s_top) -> np.ndarray:
        """tau_w/p_w at the time(s) ``t``: the imposed stress, or (an imposed speed) the stress the bed exerts on the
        plate, -sigma_xy at its first face (``s_top``, one per time)."""
        t = np.asarray(t, dtype=float)
        tau = -np.asarray(s_top, dtype=float) if self.kind == "speed" else np.broadcast_to(self.wall(t), t.shape)
        return tau / self.p_w

    @property
    def oscillating(self) -> bool:
        return self.omega > 0

    @property
    def period(self) -> float:
        """2 pi/omega (inf for a held load)."""
        return 2 * math.pi / self.omega if self.oscillating else math.inf

    def wave(self, t):
        """The imposed value's factor at time(s) t: sin(omega t), or 1 for a held load."""
        return np.sin(self.omega * np.asarray(t, dtype=float)) if self.oscillating else np.ones_like(t, dtype=float)

    def wall(self, t):
        """The imposed value in DEM units at time(s) t: value sin(omega t) (tau_w(t) or u_w(t); an array for an array
        t), or the held value (one number, whatever t: it is read at every rate evaluation)."""
        return self.value * self.wave(t) if self.omega > 0 else self.value

    @property
    def amplitude(self) -> float:
        """The imposed number of the load's own kind: mu_w (= tau_w/p_w) or u_w; a sine's amplitude."""
        return self.mu_w if self.kind == "stress" else self.u_w

    @property
    def tau_w(self) -> float | None:
        """The imposed wall shear stress (an imposed stress), else None."""
        return self.mu_w * self.p_w if self.kind == "stress" else None

    @cached_property
    def value(self) -> float:
        """The imposed number in DEM units: tau_w or u_w (kept: the wall reads it at every rate evaluation)."""
        return self.tau_w if self.kind == "stress" else self.u_w

    @property
    def imposed(self) -> dict:
        """The imposed number by name: {"mu_w": ...} or {"u_w": ...}."""
        return {"mu_w": self.mu_w} if self.kind == "stress" else {"u_w": self.u_w}

    def scales(self, material: Material) -> Scales:
        """The paper's scales of this load on ``material`` (for a speed: at its steady mu_w^inf)."""
        return (Scales(material, self.p_w, self.mu_w) if self.kind == "stress"
                else Scales.for_speed(material, self.p_w, self.u_w))

    def as_record(self) -> dict:
        """run.json's drive keys: the imposed stress or speed in DEM units (None for the other), omega."""
        return {"kind": self.kind, "tau_w": self.tau_w, "u_w": self.u_w, "omega": self.omega}

    @classmethod
    def from_record(cls, record: dict, p_w: float) -> Load:
        """The load of a run.json drive record (``as_record``) at plate pressure ``p_w``."""
        omega = float(record.get("omega", 0.0))
        if record["kind"] == "stress":
            return cls("stress", p_w, mu_w=record["tau_w"] / p_w, omega=omega)
        return cls("speed", p_w, u_w=record["u_w"], omega=omega)
