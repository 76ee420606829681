"""The oscillating plate's model side (compare.oscillation): what the comparison's numerics cost and how far their
observables are from a converged reference, against the verification numerics (continuum.oscillation's defaults)
in the same run.  Prints the table for bench/RESULTS.md.

    .venv/bin/python bench/oscillation.py

Drives: an imposed speed and an imposed stress at mu~_w = 0.6 and omega t_s = 1 on the oscillating-disks study's
scene (p_w = 20, bed 28 d, the plate's mass of the quick preset's plate), 4 periods, material from
results/calibration-disks/p20/calibration.json; NGF with the committed disks study's A.  Reference: 320 cells at
rtol 1e-8.  Errors: |observable - reference| of compare.oscillation.observables on the model's own record.
"""
from __future__ import annotations

import json
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from granstokes.compare import calibrate
from granstokes.compare import oscillation as osc
from granstokes.compare.drive import DriveSpec
from granstokes.continuum.load import Load
from granstokes.continuum.oscillation import OSCILLATION_NUMERICS
from granstokes.continuum.scene import SceneNumerics

ROOT = Path(__file__).parent.parent
P_W, DEPTH, PLATE_MASS, CYCLES, OMEGA_TS, MU_TILDE = 20.0, 28.0, 0.471, 4, 1.0, 0.6
REFERENCE = SceneNumerics(n_cells=320, rtol=1e-8, atol=1e-11)
CANDIDATES = {"verification (200 cells, rtol 1e-6; baseline)": OSCILLATION_NUMERICS,
              "comparison (80 cells, rtol 1e-4)": osc.NUMERICS}
OBSERVED = ("response_amplitude", "phase_lag", "yielded_depth", "dissipation")


def drive(kind: str, material) -> DriveSpec:
    fr = material.friction
    mu_w = fr.mu_w_from_tilde(MU_TILDE)
    held = Load("stress", P_W, mu_w=mu_w)
    if kind == "speed":
        from granstokes.continuum.steady import steady_wall_speed
        sc = held.scales(material)
        held = Load("speed", P_W, u_w=sc.U * steady_wall_speed(fr, mu_w))
    t_s = held.scales(material).t_s
    load = replace(held, omega=OMEGA_TS / t_s)
    return DriveSpec(Path("bench"), f"{kind}-w{OMEGA_TS:g}", load, DEPTH, plate_mass=PLATE_MASS, surface_offset=0.0,
                     steps=0, transit_time=np.nan, seeds=1, grains=0, dimension=2, t_s=t_s,
                     duration=CYCLES * load.period)


def measure(d, material, model, A, numerics):
    depths = np.arange(0.5, DEPTH, 1.0)
    start = time.process_time()
    rec = osc.model_record(d, material, model, A, depths, numerics)
    cpu = time.process_time() - start
    values = osc.observables(rec, d, material.mu_s)["values"]
    return cpu, {o: values[o][0] for o in OBSERVED}


def main():
    material = calibrate.load(ROOT / "results/calibration-disks/p20/calibration.json").material()
    A = json.loads((ROOT / "results/study-disks/metrics.json").read_text())["ngf"]["A"]
    print("| drive | model | numerics | CPU s | CPU / baseline | " + " | ".join(f"err {o}" for o in OBSERVED) + " |")
    print("|---|---|---|---|---|" + "---|" * len(OBSERVED))
    for kind in ("speed", "stress"):
        d = drive(kind, material)
        for model in ("local", "ngf"):
            a = A if model == "ngf" else None
            _, ref = measure(d, material, model, a, REFERENCE)
            base = None
            for name, numerics in CANDIDATES.items():
                cpu, got = measure(d, material, model, a, numerics)
                base = base or cpu
                errs = " | ".join(f"{abs(osc._difference(o, got[o], ref[o])):.2g}" for o in OBSERVED)
                print(f"| {kind} | {model} | {name} | {cpu:.2f} | {cpu / base:.2f} | {errs} |")


if __name__ == "__main__":
    main()
