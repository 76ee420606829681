"""``granstokes paper-figures`` and ``granstokes stability``."""
from __future__ import annotations

from pathlib import Path

from granstokes.lib.staging import claim, staged
from granstokes.lib.validate import read_json

#: what --calibration must hold (I0 in the DEM convention)
CALIBRATION_KEYS = ("mu_s", "mu_d", "I0")


def run_paper_figures(args) -> int:
    from .figures import paper_figures

    with staged(claim(args.out, "--out", "paper-figures"), "paper-figures") as work:
        result = paper_figures(work)
    names = sorted(k for k in result if k != "timing")
    print(f"wrote the paper's figures into {args.out}: " + ", ".join(names))
    return 0


def run_stability(args) -> int:
    from ..scales import Material
    from .stability import write_stability

    inputs = [args.calibration] if args.calibration is not None else []
    claim(args.out, "--out", "stability", inputs)
    calibrated = None
    if args.calibration is not None:
        cal = read_json(args.calibration, "--calibration", CALIBRATION_KEYS,
                        "a calibration.json (granstokes dem calibrate) or metrics.json (granstokes compare)")
        convention = cal.get("I_convention", cal.get("I0_convention"))
        calibrated = Material(mu_s=cal["mu_s"], mu_d=cal["mu_d"], I0=cal["I0"], I_convention=convention)
    with staged(args.out, "stability", inputs) as work:
        result = write_stability(work, calibrated)
    counts = result["table"].groupby(["method", "class"]).size().unstack(fill_value=0)
    print(counts.to_string())
    print(f"maps: {', '.join(p.name for p in result['maps'])}; well-posedness: {result['wellposedness'].name}")
    return 0


def register(sub) -> None:
    """Add ``paper-figures`` and ``stability`` to the ``granstokes`` parser."""
    f = sub.add_parser("paper-figures", help="regenerate the paper's figures 1-9 (PNG + CSV)")
    f.add_argument("--out", type=Path, required=True, help="output folder")
    f.set_defaults(func=run_paper_figures)

    s = sub.add_parser("stability", help="stability maps of every method, and the mu(I) well-posedness along the layer")
    s.add_argument("--out", type=Path, required=True, help="output folder")
    s.add_argument("--calibration", type=Path, help="metrics.json of a DEM calibration (mu_s, mu_d, I0, I0_convention)")
    s.set_defaults(func=run_stability)
