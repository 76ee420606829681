"""Which bed grains slip against the plate, and why: the per-grain diagnosis of docs/dem.md "Slip against p_w".

    .venv/bin/python bench/plate_slip.py RUN [RUN ...]

For every drive of each run folder (``granstokes dem run``, with its dumps): the slip of compare.plate.slip per seed,
then over the second half of the drive (compare.plate.SLIP_FROM), from the atom and contact snapshots:

* the bed grains touching the plate, split by how many plate grains each touches: one (it can roll under that
  grain) or two and more (wedged in a gap of the plate: it cannot roll without sliding at one contact); their share,
  their lag 1 - <u_x>/<u_plate> and the lag's absolute value in sqrt(g d);
* the bed-plate contacts at the Coulomb limit (|f_t| >= 0.99 mu |f_n|, mu the plate's friction from run.json);
* 2D only: the gaps of the plate's row, each by the highest bed grain in it: wedged (touching both neighbours),
  against one side, or free (more than GAP_TOUCH from both).

Prints one block per drive.  Cost: a few seconds per drive and seed.
"""
from __future__ import annotations

import argparse
import json
from collections import Counter
from pathlib import Path

import numpy as np
import pandas as pd
from granstokes.compare.drive import drive_specs
from granstokes.compare.plate import SLIP_FROM, PlateRecord, pooled, slip
from granstokes.dem.layout import ATOMS, BED, CONTACTS, PLATE, RUN_JSON, dump_snapshots, snapshot_table

#: a bed grain this close to a plate grain (surface to surface, in d) counts as touching it in the gap census
GAP_TOUCH = 0.02
#: the Coulomb limit: a contact slides when |f_t| reaches this fraction of mu |f_n|
SLIDING = 0.99


def _frames(folder: Path):
    """(atoms, contacts) tables of the snapshots in the second half of the drive, indexed by atom id."""
    atoms = list(dump_snapshots(folder / ATOMS))
    contacts = dict(dump_snapshots(folder / CONTACTS))
    for step, text in atoms[int(len(atoms) * SLIP_FROM):]:
        if step in contacts:
            yield snapshot_table(text).set_index("id"), snapshot_table(contacts[step])


def _touching(folder: Path, mu: float) -> tuple[pd.DataFrame, np.ndarray]:
    """Per touching bed grain and frame: diameter, u_x / plate u_x, plate grains touched; and |f_t|/(mu |f_n|) of
    every bed-plate contact."""
    rows, ratios = [], []
    for a, c in _frames(folder):
        plate = a.index[a.type == PLATE]
        u_plate = a.loc[plate, "vx"].mean()
        p1, p2 = c.id1.isin(plate), c.id2.isin(plate)
        bp = c[p1 ^ p2]
        bed_ids = np.where(p1[p1 ^ p2], bp.id2, bp.id1)
        bed_ids = [i for i in bed_ids if a.loc[i, "type"] == BED]
        for i, k in Counter(bed_ids).items():
            rows.append((2 * a.loc[i, "radius"], a.loc[i, "vx"], u_plate, k))
        ratios.append(np.hypot(np.hypot(bp.ft_x, bp.ft_y), bp.ft_z) / (mu * bp.fn.abs()))
    grains = pd.DataFrame(rows, columns=["diameter", "u_x", "u_plate", "plate_grains"])
    return grains, np.concatenate(ratios) if ratios else np.array([])


def _gaps(folder: Path, width: float) -> Counter:
    """2D: each gap of the plate's row in each frame, by the highest bed grain between its two plate grains."""
    census = Counter()
    for a, _ in _frames(folder):
        p = a[a.type == PLATE]
        row = p[p.y > p.y.max() - 0.1].sort_values("x")  # the row (toothless plates: every grain)
        xs, ys, rp = row.x.to_numpy() % width, row.y.to_numpy(), row.radius.to_numpy()
        order = np.argsort(xs)
        xs, ys, rp = xs[order], ys[order], rp[order]
        near = a[(a.type == BED) & (a.y > ys.mean() - 3.0)]
        for k in range(len(xs)):
            right = (k + 1) % len(xs)
            xl, xr = xs[k], xs[right] + (width if right == 0 else 0.0)
            mid = 0.5 * (xl + xr)
            dx = (near.x.to_numpy() - mid + width / 2) % width - width / 2
            inside = near[np.abs(dx) < 0.5 * (xr - xl)]
            if not len(inside):
                census["free"] += 1
                continue
            g = inside.loc[inside.y.idxmax()]
            x = mid + ((g.x - mid + width / 2) % width - width / 2)
            clear = [np.hypot(x - xp, g.y - yp) - (g.radius + r) for xp, yp, r in ((xl, ys[k], rp[k]),
                                                                                 (xr, ys[right], rp[right]))]
            touching = sum(c < GAP_TOUCH for c in clear)
            census[("free", "one side", "wedged")[touching]] += 1
    return census


def diagnose(run: Path) -> None:
    meta = json.loads((run / RUN_JSON).read_text())
    mu, dim, width = float(meta["plate"]["friction"]), int(meta["config"]["grains"]["dimension"]), \
        float(meta["config"]["box"]["width"])
    for spec in drive_specs(run):
        per_seed = [slip(PlateRecord.read(f)) for f in spec.folders]
        s = pooled(per_seed)
        seeds = ", ".join(f"{100 * e['value']:.1f}" for e in per_seed)
        print(f"{run}/{spec.name} (p_w = {spec.p_w:g}, {spec.kind}): slip {100 * s['value']:.1f} +- "
              f"{100 * s['stderr']:.1f} % (per seed {seeds})")
        parts = [_touching(f, mu) for f in spec.folders]
        g = pd.concat([p[0] for p in parts], ignore_index=True)
        ratio = np.concatenate([p[1] for p in parts])
        g["wedged"] = g.plate_grains >= 2
        for wedged, h in g.groupby("wedged"):
            lag = 1 - h.u_x.mean() / h.u_plate.mean()
            print(f"  {'wedged (2+ plate grains)' if wedged else 'one plate grain'}: {100 * len(h) / len(g):.0f} % of "
                  f"the touching grains, lag {100 * lag:.1f} % ({lag * h.u_plate.mean():.3f} sqrt(g d)), "
                  f"mean diameter {h.diameter.mean():.3f}")
        frames = len(g) and sum(1 for f in spec.folders for _ in _frames(f))
        print(f"  touching grains per frame {len(g) / max(frames, 1):.1f}; bed-plate contacts at the Coulomb limit "
              f"{100 * np.mean(ratio >= SLIDING):.1f} % (mean |f_t|/(mu |f_n|) {ratio.mean():.2f})")
        if dim == 2:
            census = sum((_gaps(f, width) for f in spec.folders), Counter())
            total = sum(census.values())
            print("  gaps: " + ", ".join(f"{k} {100 * census[k] / total:.0f} %" for k in ("wedged", "one side",
                                                                                           "free")))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs", nargs="+", type=Path)
    for run in ap.parse_args().runs:
        diagnose(run)


if __name__ == "__main__":
    main()
