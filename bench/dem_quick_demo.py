"""The quick DEM scene at a glance: plate speed / wall friction, velocity profiles, layer growth, mu(y).

    .venv/bin/python bench/dem_quick_demo.py [--run DIR]   # DIR: an existing quick run (else runs it)

Writes bench/dem_quick_demo.png.  The layer thickness delta(t) is the depth where the time-averaged
grain velocity falls to 10 % of the plate speed (profiles averaged over 0.2 time units, 1 d bins).
"""
from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from granstokes.continuum.steady import steady_wall_speed  # noqa: E402
from granstokes.dem import config  # noqa: E402
from granstokes.dem.runner import run  # noqa: E402
from granstokes.dem.sizing import plan  # noqa: E402

HERE = Path(__file__).resolve().parent


def layer_depth(plate: pd.DataFrame, prof: pd.DataFrame, fraction: float = 0.1) -> pd.DataFrame:
    surface = plate["y"].iloc[: max(1, len(plate) // 20)].mean() - 0.5
    rows = []
    for t, g in prof.groupby("t"):
        u_w = plate.loc[(plate["t"] > t - 0.2) & (plate["t"] <= t), "u_x"].mean()
        moving = g[(g["u_x"] > fraction * u_w) & (g["y"] < surface)]
        rows.append((t, u_w, surface - moving["y"].min() + 0.5 if len(moving) else 0.0))
    return pd.DataFrame(rows, columns=["t", "u_w", "delta"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--run", type=Path, help="existing quick run folder")
    args = ap.parse_args()
    cfg, text = config.preset("quick")
    out, p = args.run, plan(cfg)
    if out is None:
        out = Path(tempfile.mkdtemp(prefix="dem-quick-")) / "quick"
        assert run(p, text, out).ok
    fig, ax = plt.subplots(2, 2, figsize=(11, 8))
    for dp, colour in zip(p.drives, ("C0", "C1")):
        d = out / "seed-1" / dp.drive.name
        plate, prof = pd.read_csv(d / "plate.csv"), pd.read_csv(d / "profiles.csv")
        s = dp.scales
        smooth = plate.rolling(25, center=True).mean()
        if dp.drive.kind == "stress":
            ax[0, 0].plot(plate["t"], plate["u_x"], colour, lw=0.8, label=f"{dp.drive.name}: plate speed u_w")
        else:
            ax[0, 0].plot(smooth["t"], smooth["mu_w"] * 10, colour, lw=0.8,
                          label=f"{dp.drive.name}: 10 x mu_w (0.5 time-unit mean)")
        steady = s.U * steady_wall_speed(cfg.material.friction, s.mu_w) if dp.load.u_w is None else 10 * s.mu_w
        ax[0, 0].axhline(steady, color=colour, ls=":")
        surface = plate["y"].mean() - 0.5
        for t in (1.0, 3.0, 10.0, p.drives[0].duration):
            g = prof[np.isclose(prof["t"], prof["t"].iloc[(prof["t"] - t).abs().argmin()]) & (prof["count"] > 0)]
            ax[0, 1].plot(g["u_x"], surface - g["y"], colour, lw=1, alpha=0.4 + 0.6 * t / p.drives[0].duration)
        lay = layer_depth(plate, prof)
        ax[1, 0].loglog(lay["t"], lay["delta"], "o", ms=2, color=colour, label=dp.drive.name)
        late = prof[prof["t"] > 0.5 * prof["t"].max()].groupby("y_plane").mean(numeric_only=True)
        ok = late["p_mop"] > 0
        ax[1, 1].plot(late["tau_mop"][ok] / late["p_mop"][ok], surface - late.index[ok], colour,
                      label=f"{dp.drive.name}: tau/p (method of planes)")
        y = np.linspace(0, s.delta_s, 50)
        ax[1, 1].plot(s.mu_w / (1 + s.beta_w * y / s.delta_s), y, colour, ls=":",
                      label="continuum steady state (expected mu(I))" if colour == "C0" else None)
    t = np.logspace(-0.7, 1.3, 10)
    ax[1, 0].loglog(t, 4.5 * np.sqrt(t), "k--", lw=0.8, label="sqrt(t)")
    ax[0, 0].set(xlabel="t [sqrt(d/g)]", title="drives (dotted: continuum steady values, expected mu(I))")
    ax[0, 1].set(xlabel="u_x [sqrt(g d)]", ylabel="depth below plate [d]", title="velocity profiles, t = 1, 3, 10, end")
    ax[0, 1].invert_yaxis()
    ax[1, 0].set(xlabel="t", ylabel="delta [d]", title="layer thickness (u_x > 10 % u_w)")
    ax[1, 1].set(xlabel="mu = tau/p", ylabel="depth [d]", title="late-time friction profile")
    ax[1, 1].invert_yaxis()
    for a in (ax[0, 0], ax[1, 0], ax[1, 1]):
        a.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(HERE / "dem_quick_demo.png", dpi=110)
    print(f"wrote {HERE / 'dem_quick_demo.png'} from {out}")


if __name__ == "__main__":
    main()
