"""``granstokes predict``: the local mu(I), the nonlocal fluidity (NGF) or the elasto-plastic mu(I) prediction of a
DEM scene, in DEM units (d = rho_p = g = 1), I0 in the DEM convention (I = |du/dy| d/sqrt(p/rho_p)).

    granstokes predict --model local|ngf|elastic --mu-s A --mu-d B --I0 C [--A L] [--G S] --phi F --p-w P --depth H
                       (--mu-w M | --u-w U) (--steady | --times T1 T2 ...) [--plate-mass m] [--json]

The models are continuum.scene_models' (the ones compare/ scores), on the scene (continuum.scene.BedScene) under
the load (continuum.load.Load):

* ``--model local --steady``: the closed-form steady state of the scene (scene_models.local_steady); u_w_err = 0:
  exact up to rounding.
* ``--model local --times``: the velocity form (continuum.velocity.solve_velocity) from a bed at rest,
  regularised with YieldRule.for_layer (eps = EPS_FRACTION U/delta_s); errors Richardson's |x_N - x_N/2|/3
  (SceneModel.estimated, continuum.richardson, second order in space; the regularisation's own creep is not in
  it).
* ``--model elastic --G S``: continuum.elastic, the velocity form with an elastic shear stress of modulus G (rho_p g
  d), from a stress-free bed at rest; its steady state is local mu(I)'s (closed form); errors Richardson's from
  N/2 cells.
* ``--model ngf``: continuum.ngf (steady: Chebyshev, errors the change from n/2 points; transient:
  from rest on the solver's default numerics, errors Richardson from N/2 cells).  g is given at the nodes y (for
  the transient, ln g interpolated linearly from the cell centres).

Every output gives the plate's speed and friction with their errors (u_w_err, mu_w_err; the imposed one's
is 0) and the layer depth in d: the steady state's delta_s (where tau/p falls to mu_s), a transient's
delta_u at each time (where u falls to continuum.crossing.U_FRACTION of u_w, the depth compare/ measures in the
DEM).

Bad input raises ValueError naming the parameter and its range (the root parser, granstokes.cli, prints
one line and exits 2).  The solvers are imported when a prediction runs, not when the parser is built
(start-up time).
"""
from __future__ import annotations

import argparse
import json

import numpy as np

from granstokes.lib.validate import finite, require

MODELS = ("local", "ngf", "elastic")
BOUNDARIES = ("neumann", "dirichlet")
STEADY_LAYER = "delta_s [d]: the steady yield depth, where tau/p falls to mu_s"


def register(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "predict", help="local mu(I) or nonlocal-fluidity prediction of a DEM scene (DEM units)",
        description="Predict the DEM scene (plate on a bed of depth H, no-slip base) in DEM units "
                    "d = rho_p = g = 1; I0 in the DEM convention I = |du/dy| d/sqrt(p/rho_p) "
                    "(= 2 x the paper's I0).")
    p.add_argument("--model", required=True, choices=MODELS, help="local mu(I) or ngf (nonlocal granular fluidity)")
    p.add_argument("--mu-s", type=float, required=True, help="static friction mu_s > 0")
    p.add_argument("--mu-d", type=float, required=True, help="dynamic friction mu_d > mu_s")
    p.add_argument("--I0", type=float, required=True,
                   help="I0 > 0 of the Jop law, DEM convention (I = |du/dy| d/sqrt(p/rho_p))")
    p.add_argument("--A", type=float, help="nonlocal amplitude A >= 0 (ngf only; the length is A d)")
    p.add_argument("--G", type=float, help="the bed's shear modulus G > 0 (rho_p g d; elastic only)")
    p.add_argument("--phi", type=float, required=True, help="solid fraction in (0, 1)")
    p.add_argument("--p-w", type=float, required=True, help="plate pressure p_w > 0 (rho_p g d)")
    p.add_argument("--depth", type=float, required=True, help="bed depth H > 0 (d)")
    drive = p.add_mutually_exclusive_group(required=True)
    drive.add_argument("--mu-w", type=float, help="imposed plate friction tau_w/p_w, mu_s < mu_w < mu_d")
    drive.add_argument("--u-w", type=float, help="imposed plate speed u_w > 0 (sqrt(g d))")
    when = p.add_mutually_exclusive_group(required=True)
    when.add_argument("--steady", action="store_true", help="the steady state")
    when.add_argument("--times", type=float, nargs="+",
                      help="output times > 0, increasing (sqrt(d/g)), from a bed at rest")
    p.add_argument("--plate-mass", type=float, default=0.0, help="plate mass per unit area >= 0 (rho_p d), default 0")
    p.add_argument("--boundary", default="neumann", choices=BOUNDARIES,
                   help="ngf fluidity boundary condition: neumann (dg/dy = 0, default) or dirichlet (g = g_loc)")
    p.add_argument("--t0-hat", type=float, default=1.0,
                   help="ngf transient relaxation time in local inertial times d sqrt(rho_p/p), default 1")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run_predict)
    return p


def _scene(args):
    """The material and the scene (continuum.scene.BedScene) of the arguments."""
    from .scales import Material
    from .scene import BedScene

    require(args.model in MODELS, "--model", f"one of {MODELS}", args.model)
    for name in ("mu_s", "mu_d", "I0", "phi", "p_w", "depth", "plate_mass"):
        require(finite(getattr(args, name)), f"--{name.replace('_', '-')}", "a finite number", getattr(args, name))
    require(args.mu_s > 0, "--mu-s", "a finite number > 0", args.mu_s)
    require(args.mu_d > args.mu_s, "--mu-d", f"a finite number > mu_s = {args.mu_s}", args.mu_d)
    require(args.I0 > 0, "--I0", "a finite number > 0 (DEM convention)", args.I0)
    require(0 < args.phi < 1, "--phi", "in the open interval (0, 1)", args.phi)
    require(args.p_w > 0, "--p-w", "a finite number > 0", args.p_w)
    require(args.depth > 0, "--depth", "a finite number > 0", args.depth)
    require(args.plate_mass >= 0, "--plate-mass", "a finite number >= 0", args.plate_mass)
    material = Material(mu_s=args.mu_s, mu_d=args.mu_d, I0=args.I0, I_convention="dem", phi=args.phi)
    return material, BedScene(args.depth, plate_mass=args.plate_mass)


def _load(args, p_w: float, mu_top: float, top_name: str = "mu_d"):
    """The plate's load (continuum.load.Load) from --mu-w or --u-w."""
    from .load import Load

    if args.mu_w is not None:
        require(finite(args.mu_w) and args.mu_s < args.mu_w < mu_top, "--mu-w",
                f"in the open interval (mu_s, {top_name}) = ({args.mu_s:.6g}, {mu_top:.6g})", args.mu_w)
        return Load("stress", p_w, mu_w=float(args.mu_w))
    require(finite(args.u_w) and args.u_w > 0, "--u-w", "a finite number > 0", args.u_w)
    return Load("speed", p_w, u_w=float(args.u_w))


def _model(args, material):
    """The scene model (continuum.scene_models), its load, and the numerics of its transient here."""
    from .ngf import NonlocalFluidity, mu_max
    from .scene import SceneNumerics
    from .scene_models import LOCAL, elastic_model, ngf_model

    if args.model != "elastic":
        require(args.G is None, "--G", "given only with --model elastic", args.G)
    if args.model in ("local", "elastic"):
        require(args.A is None, "--A", "given only with --model ngf", args.A)
    if args.model == "local":
        return LOCAL, _load(args, args.p_w, material.mu_d), LOCAL.numerics
    if args.model == "elastic":
        require(args.G is not None and finite(args.G) and args.G > 0, "--G",
                "a finite shear modulus > 0 (rho_p g d), required with --model elastic", args.G)
        model = elastic_model(args.G)
        return model, _load(args, args.p_w, material.mu_d), model.numerics
    require(args.A is not None, "--A", "a finite number >= 0, required with --model ngf", args.A)
    require(finite(args.A) and args.A >= 0, "--A", "a finite number >= 0", args.A)
    require(args.boundary in BOUNDARIES, "--boundary", f"one of {BOUNDARIES}", args.boundary)
    require(finite(args.t0_hat) and args.t0_hat > 0, "--t0-hat", "a finite number > 0", args.t0_hat)
    top = mu_max(material, NonlocalFluidity(A=args.A, boundary=args.boundary, t0_hat=args.t0_hat))
    # the transient on the solver's default numerics (160 cells, rtol 1e-6), finer than the comparison's
    load = _load(args, args.p_w, top, "mu(I_max = 10), just below mu_d")
    return ngf_model(args.A, args.boundary, args.t0_hat), load, SceneNumerics()


def predict(args) -> dict:
    """The prediction as a JSON-ready dict (lists and floats)."""
    from .crossing import U_FRACTION
    from .ngf import STEADY_INTERVALS
    from .rules import EPS_FRACTION
    from .scales import UNITS
    from .solver import check_times

    material, scene = _scene(args)
    model, load, numerics = _model(args, material)
    m = material
    out = {"model": args.model, "imposed": load.kind, "units": UNITS["dem_units"],
           "I_convention": "dem: I = |du/dy| d/sqrt(p/rho_p)",
           "parameters": {"mu_s": m.mu_s, "mu_d": m.mu_d, "I0": m.I0, "phi": m.phi, "p_w": load.p_w,
                          "depth": scene.depth, "plate_mass": scene.plate_mass, **load.imposed}}
    if args.model != "local":
        out["parameters"].update(model.parameters)
    if args.steady:
        st = model.steady(material, scene, load, estimate=True)
        out.update({"u_w": st.u_w, "mu_w": st.mu_w, "u_w_err": st.u_w_err, "mu_w_err": st.mu_w_err,
                    "delta_s": st.delta_s, "layer": STEADY_LAYER, "y": st.y.tolist(), "u": st.u.tolist()})
        if st.g is not None:
            out["g"] = st.g.tolist()
        out["method"] = ("closed form (continuum.steady) scaled with continuum.scales" if args.model != "ngf" else
                         f"Chebyshev collocation, {STEADY_INTERVALS} intervals per piece; errors: change from n/2")
        return out
    t = check_times(args.times, "--times")
    tr = model.estimated(material, scene, load, t, numerics)
    if args.model == "local":
        out["method"] = (f"velocity form (continuum.velocity), eps = {EPS_FRACTION:g} U/delta_s; "
                         "errors: Richardson from N/2")
    elif args.model == "elastic":
        out["method"] = "elasto-plastic velocity form (continuum.elastic), TR-BDF2; errors: Richardson from N/2"
    else:
        out["g"] = [gk.tolist() for gk in tr.g]
        out["method"] = "finite volumes (u, ln g), scipy Radau; errors: Richardson from N/2"
    out.update({"t": t.tolist(), "u_w": tr.u_w.tolist(), "mu_w": np.asarray(tr.mu_w).tolist(),
                "delta_u": tr.delta_u.tolist(), **{k: v.tolist() for k, v in tr.errors.items()},
                "layer": f"delta_u [d]: the depth below the plate where u falls to {U_FRACTION:g} u_w",
                "y": np.asarray(tr.y).tolist(), "u": np.asarray(tr.u).tolist()})
    return out


def run_predict(args) -> int:
    out = predict(args)
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"{out['model']} model, imposed {out['imposed']} ({out['units']}; I0 {out['I_convention']})")
    if args.steady:
        print(f"steady: u_w = {out['u_w']:.8g} (+- {out['u_w_err']:.2g}), mu_w = {out['mu_w']:.8g} "
              f"(+- {out['mu_w_err']:.2g}), delta_s = {out['delta_s']:.6g} d")
    else:
        print(f"{'t':>12} {'u_w':>14} {'u_w_err':>10} {'mu_w':>12} {'mu_w_err':>10} {'delta_u [d]':>12} "
              f"{'delta_u_err':>11}")
        for row in zip(*(out[k] for k in ("t", "u_w", "u_w_err", "mu_w", "mu_w_err", "delta_u", "delta_u_err"))):
            print(f"{row[0]:12.5g} {row[1]:14.8g} {row[2]:10.2g} {row[3]:12.8g} {row[4]:10.2g} {row[5]:12.6g} "
                  f"{row[6]:11.2g}")
    return 0
