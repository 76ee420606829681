"""The contact law as LAMMPS applies it (dem.contact): a head-on collision of two disks, without gravity, gives the
set normal restitution for every pair with ``pair_style granular`` and, with the classic style, for the mean pair
only (its damping scales with the pair's mass: lighter pairs bounce more)."""
import json
import math
import re
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from granstokes.dem import config, lammps_env
from granstokes.dem.contact import Contact, grain_volume, mean_grain_volume
from scipy import stats

SPEED = 0.5  # each disk's approach speed, sqrt(g d): overlaps stay ~1e-3 d at k_n = 2e5
GAP = 0.1  # d between the surfaces at the start
#: the relative integration error of a restitution at dt = t_c/20 (the lightest pair: 20 steps a contact)
INTEGRATION = 0.05


def restitution(contact: Contact, d1: float, d2: float, tmp_path) -> float:
    """Relative speed after over before for disks of diameters d1, d2 meeting head on (LAMMPS, one rank)."""
    script = f"""units lj
dimension 2
atom_style sphere
atom_modify map array
boundary f f p
region box block -5 5 -5 5 -0.5 0.5
create_box 3 box
create_atoms 1 single {-(d1 + d2) / 4 - GAP / 2} 0 0
create_atoms 1 single {(d1 + d2) / 4 + GAP / 2} 0 0
set atom 1 diameter {d1}
set atom 2 diameter {d2}
set group all density/disc 1.0
velocity all set 0 0 0
set atom 1 vx {SPEED}
set atom 2 vx {-SPEED}
{contact.pair_lines()}
comm_modify vel yes
fix nve all nve/sphere disc
fix plane all enforce2d
timestep {contact.dt_max}
run {math.ceil((GAP / (2 * SPEED) + 20 * contact.t_c) / contact.dt_max)}
variable dv equal vx[2]-vx[1]
print "DV ${{dv}}"
"""
    (tmp_path / "in.lammps").write_text(script)
    out = subprocess.run([str(lammps_env.lmp_binary()), "-in", "in.lammps", "-log", "none", "-nocite"],
                         cwd=tmp_path, env=lammps_env.child_env(), check=True, capture_output=True, text=True).stdout
    return float(re.findall(r"^DV (\S+)", out, re.MULTILINE)[-1]) / (2 * SPEED)


def _contact(pair_style: str) -> Contact:
    text = config.preset_text("smoke").replace("[grains]\n", f'[grains]\npair_style = "{pair_style}"\n')
    return config.parse(text).contact


@pytest.mark.slow
def test_the_restitution_is_the_set_one_where_the_style_promises_it(tmp_path):
    """granular: e for every pair within the time step's integration error (the lightest pair's contact lasts the
    20 steps of dt = t_c/20: 4 %); classic: the same collision as granular for the mean pair, and the documented
    spread over the masses (dem.contact: 0.43-0.58 at w = 0.2)."""
    granular, classic = _contact("granular"), _contact("classic")
    w, e = classic.polydispersity, classic.restitution
    mean = math.sqrt(mean_grain_volume(w, 2) / grain_volume(1.0, 2))  # the disk of the mean mass
    pairs = ((1 - w, 1 - w), (1 + w, 1 + w), (1 - w, 1 + w))
    measured = [restitution(granular, d1, d2, tmp_path) for d1, d2 in pairs]
    assert all(abs(m - e) <= INTEGRATION * e for m in measured), measured
    assert restitution(classic, mean, mean, tmp_path) == pytest.approx(restitution(granular, mean, mean, tmp_path),
                                                                       abs=1e-3)
    light, heavy = restitution(classic, *pairs[0], tmp_path), restitution(classic, *pairs[1], tmp_path)
    assert 0.54 < light < 0.59 and 0.41 < heavy < 0.45, (light, heavy)
    assert light - heavy > 5 * (max(measured) - min(measured))  # the classic spread is the masses', not the step's


def test_the_3d_pair_style_check_is_its_results_and_finds_no_difference_beyond_its_family_level():
    """bench/pair_style_check.csv: the spheres grains in both styles from the same seeds. Its calibration rows are
    the committed cells' seed means (recomputed here from both points.csv, each cell within 10 % of its row's I), its
    drive rows the two reports' DEM values; each p is Welch's (recomputed by scipy from the means, errors and
    counts), each interval holds its difference; and no row differs at 95 % for the family: the smallest p exceeds
    0.05 over the number of rows (Holm's first step, which rejects none then). With 2-4 seeds that is no detectable
    difference, not an agreement (the intervals bound it)."""
    root = Path(__file__).resolve().parents[2]
    table = pd.read_csv(root / "bench" / "pair_style_check.csv")
    calibration, drives = table[table.part == "calibration"], table[table.part == "drives"]
    assert len(calibration) >= 14 and {"mu", "phi"} == set(calibration.quantity)
    assert {"u_w_inf", "mu_w_inf", "delta_u", "t90"} <= set(drives.quantity)
    points = {"classic": pd.read_csv(root / "results" / "calibration-spheres" / "p20" / "points.csv"),
              "granular": pd.read_csv(root / "results" / "pair-style-spheres" / "calibration" / "points.csv")}
    for r in calibration.itertuples():
        target = float(r.where.split("=")[1])
        for name, cells in points.items():
            near = cells[np.abs(np.log(cells.I / target)) < 0.1][r.quantity]
            assert getattr(r, name) == pytest.approx(near.mean(), rel=1e-5) and getattr(r, f"{name}_n") == len(near)
    metrics = json.loads((root / "results" / "pair-style-spheres" / "drives" / "metrics.json").read_text())
    dem = {(d.rsplit("/", 1)[-1].split("-")[0], o): v for d, o, v in
           ((x["drive"], x["observable"], x["dem"]) for x in metrics["scorecard"])}
    for r in drives.itertuples():
        assert r.granular == pytest.approx(dem[(r.where.split()[-1], r.quantity)], rel=1e-5)
    side = lambda name: (table[name].to_numpy(), (table[f"{name}_err"] * np.sqrt(table[f"{name}_n"])).to_numpy(),  # noqa: E731
                         table[f"{name}_n"].to_numpy())
    recomputed = stats.ttest_ind_from_stats(*side("granular"), *side("classic"), equal_var=False).pvalue
    assert np.allclose(recomputed, table.p, rtol=0, atol=2e-3)  # the CSV keeps six digits of the means
    relative = (table.granular - table.classic) / table.classic.abs()
    assert ((table.ci95_low <= relative) & (relative <= table.ci95_high)).all()
    assert ((table.p < 0.05) == ((table.ci95_low > 0) | (table.ci95_high < 0))).all()
    assert table.p.min() > 0.05 / len(table) and not table.holm_rejects.any()
