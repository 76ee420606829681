"""Coarse-graining on synthetic particle sets with known fields (compare/kernels.py, profiles.py, reader.py)."""
import warnings

import numpy as np
import pandas as pd
import pytest
from granstokes.compare.kernels import Kernel
from granstokes.compare.profiles import ADDITIVE, CGSettings, DepthProfiles, Grid, coarse_grain, derive, ensemble
from granstokes.compare.reader import DriveFolder, Frame, find_drives
from granstokes.dem.layout import BASE, BED, CONTACT_COLUMNS
from scipy.integrate import quad

KERNELS = [Kernel("lucy", 0.5), Kernel("gaussian", 0.5), Kernel("lucy", 1.3), Kernel("gaussian", 0.2)]


def frame(x, v=None, radius=0.5, types=BED, lx=10.0, lz=1.0, step=0):
    x = np.asarray(x, dtype=float)
    n = len(x)
    radius = np.broadcast_to(np.asarray(radius, dtype=float), (n,)).copy()
    return Frame(step=step, t=0.0, ids=np.arange(1, n + 1), types=np.broadcast_to(types, (n,)).copy(), x=x,
                 v=np.zeros((n, 3)) if v is None else np.asarray(v, dtype=float), radius=radius,
                 mass=np.pi * radius ** 2, box=np.array([[0.0, lx], [-5.0, 30.0], [-0.5, lz - 0.5]]))


def contacts(rows):
    return pd.DataFrame(rows, columns=list(CONTACT_COLUMNS))


def lattice(layers, spacing=0.1, per_layer=20, lx=10.0, y0=0.0):
    """Grains on a rectangular lattice: ``per_layer`` across x, layers ``spacing`` apart from y0."""
    ys = y0 + spacing * np.arange(layers)
    xs = (np.arange(per_layer) + 0.5) * lx / per_layer
    X, Y = np.meshgrid(xs, ys)
    return np.c_[X.ravel(), Y.ravel(), np.zeros(X.size)]


@pytest.mark.parametrize("K", KERNELS, ids=lambda k: f"{k.name}-{k.width}")
def test_kernels_normalised_with_stated_width_and_exact_cdf(K):
    c = K.cutoff
    total, _ = quad(K, -c, c, points=[0.0], epsabs=1e-14, epsrel=1e-13)
    assert total == pytest.approx(1.0, abs=1e-12)
    var, _ = quad(lambda s: s * s * K(s), -c, c, points=[0.0], epsabs=1e-14)
    assert np.sqrt(var) == pytest.approx(K.width, rel=0.015 if K.name == "gaussian" else 1e-12)
    assert K(c) == 0 and K(-1.01 * c) == 0
    s = np.linspace(-1.2 * c, 1.2 * c, 13)
    exact = [quad(K, -c, min(max(v, -c), c), epsabs=1e-14)[0] for v in s]
    assert np.allclose(K.cdf(s), exact, atol=1e-12)
    assert K.cdf(-c) == 0.0 and K.cdf(c) == 1.0


@pytest.mark.parametrize("K", KERNELS, ids=lambda k: f"{k.name}-{k.width}")
def test_stress_line_is_the_exact_average_of_the_kernel_along_the_branch(K):
    y2, y1 = 3.0, 3.9
    for y in (2.7, 3.1, 3.45, 4.2, 4.9):
        exact = quad(lambda l: K(y - y2 - l * (y1 - y2)), 0.0, 1.0, epsabs=1e-14, limit=200)[0]
        assert K.line(y, y2, y1) == pytest.approx(exact, abs=1e-10)
    assert K.line(3.2, 3.0, 3.0) == pytest.approx(K(0.2))  # horizontal branch: K at its height


def test_settings_and_grid_reject_bad_input():
    with pytest.raises(ValueError, match="kernel"):
        CGSettings("box")
    with pytest.raises(ValueError, match="width"):
        CGSettings("lucy", -1.0)
    with pytest.raises(ValueError, match="spacing"):
        CGSettings("lucy", 0.5, spacing=1.0)
    with pytest.raises(ValueError, match="grid"):
        Grid(1.0, 0.0, 0.1)


def test_uniform_packing_gives_its_solid_fraction_and_zero_stress():
    """A dense lattice (layers 0.1 d apart, 20 grains each over L_x = 10): phi = 20 pi r^2/(L_x 0.1) in the
    interior; at rest, with touching pairs carrying no force, every stress and the temperature vanish."""
    r = 0.05
    x = lattice(200, spacing=0.1, per_layer=20)  # y in [0, 19.9]
    fr = frame(x, radius=r)
    pairs = contacts([[i + 1, i + 21, 0.1, 0.0, -0.1, 0.0, 0.0, 0.0, 0.0, 0.0] for i in range(0, 3000, 7)])
    s = CGSettings("lucy", 0.5)
    grid = Grid(-3.0, 23.0, s.h)
    cg = coarse_grain(fr, pairs, s, grid, dimension=2)
    der = derive(cg, grid.y, 2)
    inner = (grid.y > 3) & (grid.y < 17)
    phi = 20 * np.pi * r ** 2 / (10.0 * 0.1)
    assert np.allclose(cg["phi"][inner], phi, rtol=1e-5)  # lattice-sum (Poisson) error of a 0.1 d lattice
    for k in ("sigma_xx", "sigma_yy", "sigma_xy", "sigma_yx", "p", "tau", "T"):
        assert np.nanmax(np.abs(der[k])) == 0.0, k
    assert np.abs(cg["b_y"]).max() == 0.0


@pytest.mark.parametrize("dimension,kernel", [(2, "lucy"), (3, "gaussian")])
def test_linear_shear_gives_linear_velocity_and_no_kinetic_stress(dimension, kernel):
    gamma = 0.7
    x = lattice(200, spacing=0.1, per_layer=8)
    v = np.c_[gamma * x[:, 1], np.zeros(len(x)), np.zeros(len(x))]
    fr = frame(x, v)
    s = CGSettings(kernel, 0.47, spacing=0.05)  # grid points on lattice layers and midpoints (and the cut
    grid = Grid(-3.0, 23.0, s.h)                # at 1.41 d, off the lattice): u = gamma y by symmetry
    cg = coarse_grain(fr, None, s, grid, dimension)
    der = derive(cg, grid.y, dimension)
    inner = (grid.y > 3) & (grid.y < 17)
    assert np.allclose(der["u_x"][inner], gamma * grid.y[inner], atol=1e-9)
    assert np.allclose(der["dudy"][inner], gamma, atol=1e-8)
    scale = cg["rho"][inner].max() * (gamma * s.width) ** 2  # what a velocity spread of gamma w would give
    for ab in ("xx", "yy", "zz", "xy"):
        assert np.abs(cg[f"sigma_k_{ab}"][inner]).max() < 1e-9 * scale
    assert np.isnan(cg["sigma_c_yy"]).all()  # no contact snapshot: contact fields are NaN, not zero
    assert der["I_paper"][inner] == pytest.approx(der["I_dem"][inner] / 2, nan_ok=True)


@pytest.mark.parametrize("kernel", ["lucy", "gaussian"])
def test_contact_stress_integrates_to_force_times_branch(kernel):
    """Two bed grains: int sigma_c_ab dy = f_a r_b / A (force on grain 1, r = x_1 - x_2), A = L_x L_z in 3D."""
    x1, x2 = np.array([4.0, 6.3, 1.0]), np.array([3.55, 5.45, 0.8])
    r = x1 - x2
    fn, ft = 3.0, np.array([0.4, 0.2, -0.3])
    ft -= ft @ r / (r @ r) * r
    f = fn * r / np.linalg.norm(r) + ft
    fr = frame(np.array([x1, x2]), radius=np.array([0.5, 0.5]), lx=8.0, lz=2.5)
    pair = contacts([[1, 2, np.linalg.norm(r), *r, fn, *ft]])
    s = CGSettings(kernel, 0.4, spacing=0.004)
    grid = Grid(0.0, 12.0, s.h)
    area = 8.0 * 2.5
    cg = coarse_grain(fr, pair, s, grid, dimension=3)
    integral = lambda k: cg[k].sum() * s.h  # noqa: E731
    tol = 1e-8 if kernel == "lucy" else 1e-5  # trapezoid rule on C2 (Lucy) / cut (Gaussian) profiles
    assert integral("sigma_c_yy") == pytest.approx(f[1] * r[1] / area, rel=tol)
    assert integral("sigma_c_xy") == pytest.approx(f[0] * r[1] / area, rel=tol)
    assert integral("sigma_c_yx") == pytest.approx(f[1] * r[0] / area, rel=tol)
    assert integral("sigma_c_xx") == pytest.approx(f[0] * r[0] / area, rel=tol)
    assert integral("sigma_c_zz") == pytest.approx(f[2] * r[2] / area, rel=tol)
    # sigma_c_ay is the kernel-smoothed force through horizontal planes: between 0 and f_a / A
    assert 0 <= cg["sigma_c_yy"].min() and cg["sigma_c_yy"].max() <= f[1] / area * (1 + 1e-12)


def test_wall_contact_goes_to_the_contact_point_and_deposits_the_force():
    """A bed grain resting on a base grain: the stress line runs from the contact point to the bed grain's
    centre (int sigma = f (x) a / A) and the force is deposited at the contact point (int b = f / A)."""
    xb, xw = np.array([2.0, 3.0, 0.0]), np.array([2.3, 2.1, 0.0])
    rb, rw = 0.5, 0.45
    r = xb - xw
    dist = np.linalg.norm(r)  # 0.9487 < rb + rw: overlap 1.3e-3
    fn = 2.0
    fr = frame(np.array([xb, xw]), radius=np.array([rb, rw]), types=np.array([BED, BASE]))
    pair = contacts([[2, 1, dist, *(-r), fn, 0.0, 0.0, 0.0]])  # grain 1 of the pair is the wall grain
    s = CGSettings("lucy", 0.3, spacing=0.003)
    grid = Grid(-1.0, 6.0, s.h)
    cg = coarse_grain(fr, pair, s, grid, dimension=2)
    f_bed = fn * r / np.linalg.norm(r)  # on the bed grain
    a = (rb - (rb + rw - dist) / 2) * r / np.linalg.norm(r)
    c_y = xb[1] - a[1]
    assert cg["sigma_c_yy"].sum() * s.h == pytest.approx(f_bed[1] * a[1] / 10.0, rel=1e-8)
    assert cg["b_y"].sum() * s.h == pytest.approx(f_bed[1] / 10.0, rel=1e-8)
    assert grid.y[np.argmax(cg["b_y"])] == pytest.approx(c_y, abs=s.h)
    assert cg["rho"].sum() * s.h * 10.0 == pytest.approx(np.pi * rb ** 2, rel=1e-8)  # the wall grain is no material


def test_density_integrates_to_the_grain_mass():
    rng = np.random.default_rng(4)
    n = 300
    x = np.c_[rng.uniform(0, 10, n), rng.uniform(1, 15, n), np.zeros(n)]
    radius = rng.uniform(0.4, 0.6, n)
    fr = frame(x, rng.normal(size=(n, 3)), radius=radius)
    for kernel, tol in (("lucy", 1e-10), ("gaussian", 1e-12)):
        s = CGSettings(kernel, 0.5, spacing=0.005)
        grid = Grid(-2.0, 18.0, s.h)
        cg = coarse_grain(fr, None, s, grid, dimension=2)
        # trapezoid rule; its error on these C2 (Lucy) profiles is far below tol, the cut Gaussian's jump is
        # exactly compensated by the renormalisation only in the limit: the exact integral is sum m (F(c) - F(-c))
        assert cg["rho"].sum() * s.h * 10.0 == pytest.approx(fr.mass.sum(), rel=tol if kernel == "lucy" else 1e-3)
        assert s.K.cdf(s.K.cutoff) - s.K.cdf(-s.K.cutoff) == 1.0
        j = cg["j_x"].sum() * s.h * 10.0
        assert j == pytest.approx((fr.mass * fr.v[:, 0]).sum(), rel=1e-3)


# --- folders with LAMMPS-format dumps ---------------------------------------------------------------------

def write_dump(path, frames, header, box=((0, 10), (0, 20), (-0.5, 0.5))):
    """LAMMPS text dump: frames = [(step, rows)], rows a 2D array; header = ATOMS/ENTRIES line."""
    kind = "ATOMS" if header.startswith("id type") else "ENTRIES"
    with open(path, "w") as fh:
        for step, rows in frames:
            fh.write(f"ITEM: TIMESTEP\n{step}\nITEM: NUMBER OF {kind}\n{len(rows)}\nITEM: BOX BOUNDS pp mm pp\n")
            fh.write("".join(f"{lo:.16e} {hi:.16e}\n" for lo, hi in box))
            fh.write(f"ITEM: {kind} {header}\n")
            fh.write("".join(" ".join(f"{v:.10g}" for v in row) + "\n" for row in rows))


def drive_folder(root, steps=(0, 100, 200), n=40, with_contacts=True):
    d = root / "seed-1" / "stress"
    d.mkdir(parents=True)
    rng = np.random.default_rng(0)
    radius = rng.uniform(0.4, 0.6, n)
    pd.DataFrame({"id": np.arange(1, n + 1), "type": BED, "radius": radius, "mass": np.pi * radius ** 2}).to_csv(
        d / "grains.csv", index=False)
    atoms, cons = [], []
    for step in steps:
        x = np.c_[rng.uniform(0, 10, n), rng.uniform(1, 15, n), np.zeros(n)]
        v = rng.normal(size=(n, 3)) * [1, 1, 0]
        atoms.append((step, np.c_[np.arange(1, n + 1), np.ones(n), x, v, radius]))
        i, j = 3, 7
        r = x[i] - x[j]
        cons.append((step, [[i + 1, j + 1, np.linalg.norm(r), *r, 1.5, 0.1, -0.2, 0.0]]))
    write_dump(d / "atoms.dump", atoms, "id type x y z vx vy vz radius")
    if with_contacts:
        write_dump(d / "contacts.dump", cons, " ".join(CONTACT_COLUMNS))
    return d


def test_drive_folder_streams_frames_with_matching_contacts(tmp_path):
    d = drive_folder(tmp_path)
    drive = DriveFolder(d, dimension=2, dt=0.01)
    assert list(drive.atoms.steps) == [0, 100, 200] and list(drive.contacts.steps) == [0, 100, 200]
    prof = DepthProfiles(drive, CGSettings("lucy", 0.5)).run()
    r = prof.results
    assert r.frames.groupby("step").size().size == 3 and r.has_contacts.all()
    assert set(ADDITIVE) <= set(r.frames.columns) and {"I_dem", "I_paper", "mu", "p", "tau"} <= set(r.frames.columns)
    # positions: box corner restored, float64, equal to the dump's text to float32 precision
    fr = next(drive.frames([1]))
    text = drive.atoms.table(1)
    assert fr.x.dtype == np.float64 and np.allclose(fr.x[:, 1], text["y"], atol=2e-6)
    assert fr.mass.sum() == pytest.approx(pd.read_csv(d / "grains.csv")["mass"].sum(), rel=1e-15)
    w = prof.window(0.0, 2.0)
    assert (w["n"] == 3).all() and (w["band_over"] == "frames").all()
    assert (w["rho_lo"] <= w["rho"] + 1e-12).all() and (w["rho"] <= w["rho_hi"] + 1e-12).all()
    assert r.meta["kernel"] == "lucy" and "inertial_number" in r.meta and "stress" in r.meta
    # an ensemble of two "seeds" (the same folder twice here) bands over seeds
    e = ensemble([prof, prof], 0.0, 2.0)
    assert (e["band_over"] == "seeds").all() and np.allclose(e["rho"], w["rho"])
    inst = ensemble([prof, prof])
    assert sorted(inst["step"].unique()) == [0, 100, 200]
    raw = d / "segments" / "000"  # an unfinished run's raw segment output is no drive folder
    raw.mkdir(parents=True)
    (raw / "atoms.dump").write_text((d / "atoms.dump").read_text())
    assert [p.name for p in find_drives(tmp_path, dimension=2, dt=0.01)] == ["seed-1/stress"]


@pytest.mark.parametrize("which", ["atoms.dump", "contacts.dump"])
@pytest.mark.parametrize("cut", [25, 300])  # bytes cut off the end: mid-line, and mid-frame
def test_truncated_dump_is_read_to_the_last_whole_frame(tmp_path, which, cut):
    d = drive_folder(tmp_path)
    text = (d / which).read_bytes()
    (d / which).write_bytes(text[:-cut])
    with pytest.warns(UserWarning, match=rf"{which}.*truncated.*step 100"):
        drive = DriveFolder(d, dimension=2, dt=0.01)
    index = drive.atoms if which == "atoms.dump" else drive.contacts
    assert list(index.steps) == [0, 100]
    prof = DepthProfiles(drive).run()
    assert len(prof.results.steps) == (2 if which == "atoms.dump" else 3)
    assert prof.results.has_contacts.tolist() == ([True, True] if which == "atoms.dump" else [True, True, False])


def test_partly_written_header_is_dropped(tmp_path):
    d = drive_folder(tmp_path)
    with open(d / "atoms.dump", "a") as fh:
        fh.write("ITEM: TIMESTEP\n300\nITEM: NUMB")
    with pytest.warns(UserWarning, match="step 200"):
        drive = DriveFolder(d, dimension=2, dt=0.01)
    assert len(drive.atoms) == 3


def test_missing_contacts_file_is_a_clear_error(tmp_path):
    d = drive_folder(tmp_path, with_contacts=False)
    with pytest.raises(FileNotFoundError, match=r"stress.*no contacts\.dump"):
        DriveFolder(d, dimension=2, dt=0.01)


def test_missing_metadata_is_a_clear_error(tmp_path):
    d = drive_folder(tmp_path)
    with pytest.raises(ValueError, match="dimension.*dt"):
        DriveFolder(d)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        DriveFolder(d, dimension=2, dt=0.01)  # a whole dump reads without a warning


# --- the derived fields and the bands, against hand formulas --------------------------------------------------

def _additive(y):
    """Additive fields with distinct, y-dependent values (every component different), one point without material
    and one without pressure."""
    k = np.arange(len(y), dtype=float)
    f = {name: 0.1 * (i + 1) * (1 + 0.05 * k) for i, name in enumerate(ADDITIVE)}
    f["rho"][0] = 0.0
    f["sigma_k_yy"][1], f["sigma_c_yy"][1] = 0.0, -0.05  # p < 0 at y[1]
    return f


@pytest.mark.parametrize("dimension", [2, 3])
def test_every_derived_field_is_its_formula(dimension):
    """u = j/rho (NaN without material), T = tr sigma_k/(D rho), sigma = sigma_k + sigma_c (sigma_yx with the contact
    part's yx), p = sigma_yy, p_mean = tr sigma / D (sigma_zz only in 3D), tau = -sigma_xy, mu = tau/p (NaN where
    p <= 0), dudy by centred differences, gamma_dot_paper = |dudy|/2, I = gamma_dot d/sqrt(p/rho_p) in each
    convention; no warning where rho or p vanish."""
    from granstokes.compare.profiles import derive
    y = np.array([0.0, 0.3, 0.7, 1.0, 1.6])
    f = _additive(y)
    d, rho_p = 1.3, 2.5
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out = derive(f, y, dimension, d=d, rho_p=rho_p)
    rho = f["rho"]
    ok = slice(1, None)
    for a in "xyz":
        assert np.isnan(out[f"u_{a}"][0]) and out[f"u_{a}"][ok] == pytest.approx(f[f"j_{a}"][ok] / rho[ok], rel=1e-14)
    trace = f["sigma_k_xx"] + f["sigma_k_yy"] + f["sigma_k_zz"]
    assert out["T"][ok] == pytest.approx(trace[ok] / (dimension * rho[ok]), rel=1e-14)
    s = {ab: f[f"sigma_k_{ab}"] + f[f"sigma_c_{ab}"] for ab in ("xx", "yy", "zz", "xy")}
    assert out["sigma_yx"] == pytest.approx(f["sigma_k_xy"] + f["sigma_c_yx"], rel=1e-14)
    assert out["p"] == pytest.approx(s["yy"], rel=1e-14)
    zz = s["zz"] if dimension == 3 else 0.0
    assert out["p_mean"] == pytest.approx((s["xx"] + s["yy"] + zz) / dimension, rel=1e-14)
    assert out["tau"] == pytest.approx(-s["xy"], rel=1e-14)
    assert np.isnan(out["mu"][1]) and np.isnan(out["I_dem"][1])
    good = np.arange(len(y)) != 1
    assert out["mu"][good] == pytest.approx(-s["xy"][good] / s["yy"][good], rel=1e-14)
    u = out["u_x"]
    h1, h2 = y[2] - y[1], y[3] - y[2]  # the second-order difference on an uneven grid, by hand at y[2]
    centred = (h1 ** 2 * u[3] + (h2 ** 2 - h1 ** 2) * u[2] - h2 ** 2 * u[1]) / (h1 * h2 * (h1 + h2))
    assert out["dudy"][2] == pytest.approx(centred, rel=1e-12)
    assert out["gamma_dot_paper"] == pytest.approx(np.abs(out["dudy"]) / 2, rel=1e-14, nan_ok=True)
    p = s["yy"][2]
    assert out["I_dem"][2] == pytest.approx(abs(centred) * d / np.sqrt(p / rho_p), rel=1e-12)
    assert out["I_paper"][2] == pytest.approx(abs(centred) * d / np.sqrt(p / rho_p) / 2, rel=1e-12)


def test_the_band_is_student_t_over_the_samples_each_point_has():
    """Band half-width t_0.975(m - 1) std(ddof=1)/sqrt(m), m the samples that are not NaN at that point; one sample
    at a point (or one in all): no band, and no warning."""
    from granstokes.compare.profiles import FIELDS, _band
    from scipy import stats
    rng = np.random.default_rng(5)
    samples = {k: rng.normal(size=(4, 3)) for k in FIELDS}
    samples["phi"][3, 1] = np.nan               # 3 samples at y[1]
    samples["phi"][1:, 2] = np.nan              # 1 sample at y[2]
    central = {k: np.nanmean(samples[k], axis=0) for k in FIELDS}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out = _band(central, samples, 4, "seeds")
        alone = _band(central, {k: v[:1] for k, v in samples.items()}, 1, "frames")
    for j, m in ((0, 4), (1, 3)):
        column = samples["phi"][:, j][~np.isnan(samples["phi"][:, j])]
        half = stats.t.ppf(0.975, m - 1) * column.std(ddof=1) / np.sqrt(m)
        assert out["phi_hi"][j] - central["phi"][j] == pytest.approx(half, rel=1e-12)
        assert central["phi"][j] - out["phi_lo"][j] == pytest.approx(half, rel=1e-12)
    assert np.isnan(out["phi_lo"][2]) and np.isnan(out["phi_hi"][2])
    assert np.isnan(alone["rho_lo"]).all() and (out["n"], out["band_over"], alone["n"]) == (4, "seeds", 1)


def test_a_2d_frame_ignores_its_z_extent_and_a_box_need_not_start_at_zero():
    """2D: A = L_x (per unit thickness) whatever the box's z bounds; the area is the box's width, not its upper bound;
    j_y is the grains' y momentum."""
    x = lattice(200, spacing=0.1, per_layer=20, lx=10.0)
    v = np.c_[np.zeros(len(x)), np.full(len(x), 0.25), np.full(len(x), -0.6)]
    s = CGSettings("lucy", 0.5)
    grid = Grid(-3.0, 23.0, s.h)
    base = coarse_grain(frame(x, v, radius=0.05), None, s, grid, dimension=2)
    shifted = frame(x + [5.0, 0.0, 0.0], v, radius=0.05, lz=3.5)
    shifted.box[0] += 5.0
    moved = coarse_grain(shifted, None, s, grid, dimension=2)
    inner = (grid.y > 3) & (grid.y < 17)
    phi = 20 * np.pi * 0.05 ** 2 / (10.0 * 0.1)
    assert moved["phi"][inner] == pytest.approx(phi, rel=1e-5) and base["phi"][inner] == pytest.approx(phi, rel=1e-5)
    assert moved["j_y"][inner] == pytest.approx(0.25 * moved["rho"][inner], rel=1e-12)
    assert moved["j_z"][inner] == pytest.approx(-0.6 * moved["rho"][inner], rel=1e-12)


def test_the_grid_covers_every_bed_and_the_plate_s_rise():
    """A drive's grid covers the tallest bed's first frame and the plate's largest rise after it (a deep sheared
    bed dilates by more than the margin: a 66 d bed rose 2 d), nothing more."""
    s = CGSettings("lucy", 0.5)
    low, tall = frame(np.array([[1.0, 30.0, 0.0], [2.0, 1.0, 0.0]])), frame(np.array([[1.0, 31.0, 0.0]]))
    c = s.K.cutoff
    assert s.grid_for(low).hi == pytest.approx(np.ceil((30.0 + c + 2.0) / s.h) * s.h)
    grid = s.grid_for([low, tall], rise=2.5)
    assert grid.hi == pytest.approx(np.ceil((31.0 + 2.5 + c + 2.0) / s.h) * s.h)
    assert grid.lo == pytest.approx(np.floor((1.0 - c - 2.0) / s.h) * s.h)
    risen = frame(np.array([[1.0, 33.4, 0.0]]))
    coarse_grain(risen, None, s, grid, dimension=2)  # covered
    with pytest.raises(ValueError, match="does not cover"):
        coarse_grain(risen, None, s, s.grid_for([low, tall]), dimension=2)


def test_a_grid_that_does_not_cover_the_grains_height_is_refused_and_the_dimension_named():
    x = np.array([[1.0, 9.8, 0.0], [2.0, 1.0, 0.0]])  # the highest grain at y = 9.8, both at z = 0
    s = CGSettings("lucy", 0.5)
    with pytest.raises(ValueError, match=r"does not cover the grains' y range \[1, 9\.8\]"):
        coarse_grain(frame(x), None, s, Grid(-2.0, 10.0, s.h), dimension=2)
    with pytest.raises(ValueError) as err:
        coarse_grain(frame(x), None, s, Grid(-2.0, 12.0, s.h), dimension=4)
    assert str(err.value) == "dimension must be 2 or 3, got 4"
