"""The elasto-plastic model's cost and accuracy against local mu(I)'s velocity form, in the same run: the committed
2D disks' scene at p_w = 20 (bed 40 d, the plate's mass), an imposed stress (mu~_w = 0.45) and an imposed speed over
10 t_s, G the calibration's measured shear modulus (results/calibration-disks/p20, ``elasticity``; a stated value
where the calibration holds none).  Per drive: CPU seconds (best of REPEATS), accepted steps, and the plate's
response at the last time with Richardson's error estimate (the comparison's numerics and n_cells/2); the ratio
of the elastic model's cost to the velocity form's.

    .venv/bin/python bench/elastic_cost.py [--G 2400]
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from granstokes.continuum.elastic import solve_elastic
from granstokes.continuum.load import Load
from granstokes.continuum.scene import BedScene
from granstokes.continuum.scene_models import LOCAL, elastic_model

ROOT = Path(__file__).resolve().parents[1]
CALIBRATION = ROOT / "results" / "calibration-disks" / "p20" / "calibration.json"
REPEATS = 3
DEPTH, PLATE_MASS, P_W = 40.0, 0.47, 20.0


def _best(fn) -> tuple[float, object]:
    best, out = np.inf, None
    for _ in range(REPEATS):
        start = time.process_time()
        out = fn()
        best = min(best, time.process_time() - start)
    return best, out


def main() -> None:
    from granstokes.compare.calibrate import load

    cal = load(CALIBRATION)
    parser = argparse.ArgumentParser()
    parser.add_argument("--G", type=float, default=(getattr(cal, "elasticity", None) or {}).get("G"))
    args = parser.parse_args()
    if args.G is None:
        raise SystemExit("--G: the calibration holds no shear modulus; give one")
    material, scene = cal.material(), BedScene(DEPTH, PLATE_MASS)
    mu_w = material.mu_s + 0.45 * (material.mu_d - material.mu_s)
    loads = {"stress": Load("stress", P_W, mu_w=mu_w), "speed": Load("speed", P_W, u_w=4.0)}
    model = elastic_model(args.G)
    rows = []
    for kind, ld in loads.items():
        t_end = 10 * ld.scales(material).t_s
        times = np.geomspace(t_end / 1000, t_end, 60)
        local_s, local = _best(lambda: LOCAL.estimated(material, scene, ld, times))
        elastic_s, elastic = _best(lambda: model.estimated(material, scene, ld, times))
        steps = len(solve_elastic(material, scene, ld, times, args.G, numerics=model.numerics).step_t)
        key = "u_w" if kind == "stress" else "mu_w"
        rows.append({"drive": kind, "t_end": t_end, "local_s": local_s, "elastic_s": elastic_s,
                     "ratio": elastic_s / local_s, "elastic_steps": steps,
                     f"local_{key}": float(np.asarray(getattr(local, key))[-1]),
                     f"elastic_{key}": float(np.asarray(getattr(elastic, key))[-1]),
                     "elastic_err": float(elastic.errors[f"{key}_err"][-1])})
    print(json.dumps({"G": args.G, "rows": rows}, indent=1))
    print("| drive | t_end | local mu(I) [s] | elastic [s] | ratio | elastic steps | plate response, local / elastic "
          "(error) |\n|---|---|---|---|---|---|---|")
    for r in rows:
        key = "u_w" if r["drive"] == "stress" else "mu_w"
        print(f"| {r['drive']} | {r['t_end']:.3g} | {r['local_s']:.2f} | {r['elastic_s']:.2f} | {r['ratio']:.1f} | "
              f"{r['elastic_steps']} | {r[f'local_{key}']:.5g} / {r[f'elastic_{key}']:.5g} ({r['elastic_err']:.1g}) |")


if __name__ == "__main__":
    main()
