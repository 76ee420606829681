"""Grain inertia, physically: a single grain rolling without slipping down an inclined rough wall
accelerates at g sin(theta) / (1 + I/(m r^2)): (2/3) g sin(theta) for a disk (I = m r^2/2, the scene's
2D integrator ``nve/sphere disc``), (5/7) g sin(theta) for a sphere (I = 2 m r^2/5).  With sphere
inertia a disk would give 5/7, 7 % off: the tolerance (1e-4) is the fit's and the time step's error
(Verlet, dt = t_c/20; the tangential spring's stick-slip transient is over before the fit)."""
import math
import subprocess

import numpy as np
import pytest
from granstokes.dem import lammps_env, scene
from granstokes.dem.contact import Contact

pytestmark = pytest.mark.slow
THETA = math.radians(20.0)  # below the no-slip bound: rolling needs mu_p >= tan(theta)/3 (disk), 2/7 tan (sphere)
SETTLE, MEASURE, EVERY = 20000, 40000, 1000  # steps: sticking transient, then the fit window


def _rolling_script(dim: int) -> str:
    c = Contact("hooke", dim, 10.0, 1e4, 0.5, 0.5, 2 / 7, 0.0, "granular")
    z = "-0.5 0.5" if dim == 2 else "-5 5"
    density = "density/disc" if dim == 2 else "density"
    return f"""
units lj
dimension {dim}
boundary p m p
atom_style sphere
region box block 0 200 0 10 {z} units box
create_box 1 box
create_atoms 1 single 5 0.5 0 units box
set type 1 diameter 1.0
set type 1 {density} 1.0
pair_style granular
pair_coeff * * {c.pair_coeff()}
comm_modify vel yes
timestep {c.dt_max:.10g}
fix wall all wall/gran granular {c.pair_coeff()} yplane 0.0 NULL
fix gravity all gravity 1.0 vector {math.sin(THETA):.12g} {-math.cos(THETA):.12g} 0
{scene.integrator("all", dim)}
{"fix two_d all enforce2d" if dim == 2 else ""}
run {SETTLE}
variable t equal step*dt
compute vx all reduce sum vx
fix out all print {EVERY} "$(v_t:%.12g) $(c_vx:%.12g)" file rolling.txt screen no
run {MEASURE}
"""


@pytest.mark.parametrize("dim, factor", [(2, 2 / 3), (3, 5 / 7)])
def test_grain_rolls_down_an_incline_at_the_rolling_acceleration(tmp_path, dim, factor):
    (tmp_path / "in.rolling").write_text(_rolling_script(dim))
    subprocess.run([str(lammps_env.lmp_binary()), "-in", "in.rolling", "-log", "none", "-nocite"], cwd=tmp_path,
                   env=lammps_env.child_env(), check=True, capture_output=True)
    t, vx = np.loadtxt(tmp_path / "rolling.txt", comments="#").T
    acceleration = np.polyfit(t, vx, 1)[0]
    assert acceleration / math.sin(THETA) == pytest.approx(factor, rel=1e-4)
