"""Coarse-graining of spheres (3D) through the run-folder reader, against a lattice whose fields are known.

A simple lattice of spheres (6 x 4 across x and z per layer, layers 0.1 d apart, radius r): in the interior the
solid fraction is n_layer (4/3) pi r^3 / (L_x L_z 0.1) and the density rho_p times it. Every grain moves at U0 along
x plus a fluctuation (s c, s' e, 0) with s = (-1)^ix, s' = (-1)^iz: each layer's mean velocity is U0 exactly and the
products s s' sum to zero, so the kinetic stress is sigma_k_xx = rho c^2, sigma_k_yy = rho e^2, sigma_k_xy = 0
(compressive positive: kinetic stress is positive) and the temperature T = (c^2 + e^2)/3 (tr sigma_k / (D rho) with
D = 3). One contact between two bed grains one above the other, normal force N pushing the upper grain (grain 1) up
and tangential force -F along x on it (what a plate dragging the top along +x does): the contact stress integrates
to int sigma_c_yy dy = N r_y / A and int tau dy = F r_y / A > 0 (tau = -sigma_xy, the x force of the material above
a plane on the material below), A = L_x L_z.
"""
import numpy as np
import pandas as pd
import pytest
from granstokes.compare.profiles import CGSettings, DepthProfiles
from granstokes.compare.reader import DriveFolder
from granstokes.dem.layout import BED, CONTACT_COLUMNS

from .test_cg import write_dump

LX, LZ, NX, NZ, SPACING, LAYERS, R, RHO_P = 6.0, 4.0, 6, 4, 0.1, 90, 0.05, 2.5
U0, C, E = 0.8, 0.3, 0.2
N, F = 2.0, 0.7


def _lattice_run(folder):
    ix, iz, iy = np.meshgrid(np.arange(NX), np.arange(NZ), np.arange(LAYERS), indexing="ij")
    ix, iz, iy = ix.ravel(), iz.ravel(), iy.ravel()
    x = np.c_[(ix + 0.5) * LX / NX, 1.0 + SPACING * iy, (iz + 0.5) * LZ / NZ - LZ / 2]
    s, s2 = (-1.0) ** ix, (-1.0) ** iz
    v = np.c_[U0 + s * C, s2 * E, np.zeros(len(x))]
    n = len(x)
    ids = np.arange(1, n + 1)
    mass = RHO_P * 4.0 / 3.0 * np.pi * R ** 3
    pd.DataFrame({"id": ids, "type": BED, "radius": R, "mass": mass}).to_csv(folder / "grains.csv", index=False)
    box = ((0.0, LX), (0.0, 12.0), (-LZ / 2, LZ / 2))
    write_dump(folder / "atoms.dump", [(0, np.c_[ids, np.full(n, BED), x, v, np.full(n, R)])],
               "id type x y z vx vy vz radius", box=box)
    upper, lower = 46, 45  # the grains of layers 45 and 44 at ix = iz = 0 (ids run fastest along y)
    r = x[upper - 1] - x[lower - 1]
    write_dump(folder / "contacts.dump", [(0, [[upper, lower, np.linalg.norm(r), *r, N, -F, 0.0, 0.0]])],
               " ".join(CONTACT_COLUMNS), box=box)
    return r


def test_a_sphere_lattice_gives_its_solid_fraction_temperature_kinetic_stress_and_signed_shear(tmp_path):
    folder = tmp_path / "seed-1" / "stress"
    folder.mkdir(parents=True)
    r = _lattice_run(folder)
    assert r[1] == pytest.approx(SPACING) and r[0] == r[2] == 0.0
    settings = CGSettings("lucy", 0.5, spacing=0.02)
    profiles = DepthProfiles(DriveFolder(folder, dimension=3, dt=0.01), settings).run().results.frames
    y = profiles.y.to_numpy()
    inner = (y > 3.5) & (y < 7.5)
    phi = NX * NZ * 4.0 / 3.0 * np.pi * R ** 3 / (LX * LZ * SPACING)
    rho = RHO_P * phi
    at = profiles[inner]
    assert at.phi.to_numpy() == pytest.approx(phi, rel=1e-5)
    assert at.rho.to_numpy() == pytest.approx(rho, rel=1e-5)
    assert at.u_x.to_numpy() == pytest.approx(U0, rel=1e-6)  # the dump is read in float32
    assert at.sigma_k_xx.to_numpy() == pytest.approx(rho * C ** 2, rel=1e-5)
    assert at.sigma_k_yy.to_numpy() == pytest.approx(rho * E ** 2, rel=1e-5)
    assert np.abs(at.sigma_k_xy.to_numpy()).max() < 1e-9 * rho * C * E
    assert at["T"].to_numpy() == pytest.approx((C ** 2 + E ** 2) / 3, rel=1e-5)
    area, h = LX * LZ, settings.spacing
    assert (profiles.sigma_c_yy.sum() * h) == pytest.approx(N * r[1] / area, rel=1e-6)
    contact_tau = -(profiles.sigma_c_xy.sum() * h)
    assert contact_tau == pytest.approx(F * r[1] / area, rel=1e-6) and contact_tau > 0
    assert ((profiles.tau + profiles.sigma_k_xy).sum() * h) == pytest.approx(F * r[1] / area, rel=1e-6)
