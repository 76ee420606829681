"""scipy's own BDF (scipy.integrate.BDF) on an imposed speed, the test oracle of continuum.bdf's loop: the same system
(the interior z = x[1:], the wall unknown from ``problem.project``), its Newton systems either by scipy's LU of the
reduced Jacobian (``bordered=False``) or, patching the solver's ``lu`` and ``solve_lu``, by the bordered band of
continuum.stepper.NewtonMatrix with the wall's row and column at each iterate (``bordered``, ``wall_newton``: the
systems continuum.bdf solves).  Used by tests and benchmarks only."""
from __future__ import annotations

import time

import numpy as np
from granstokes.continuum.stepper import MAX_STEPS, NewtonFailure, NewtonMatrix, StepperFailure, StepStats
from granstokes.continuum.stepper import integrate as integrate_dirk

#: the reduced Jacobian is dense up to this many unknowns: scipy's dense LU path costs less than SuperLU with its sparse
#: bookkeeping there
DENSE_BDF_MAX = 128
#: what the bordered BDF hands scipy for its Jacobian
MARKER = -1.0


def reduced_jacobian(problem, x, t, dense_max=DENSE_BDF_MAX):
    """d/dz of the rate of the differential rows z = x[1:] with the wall x[0] = x0(z) eliminated by
    the constraint g(x0, z) = 0: J_zz - J_z0 (dg/dz)/(dg/dx0), a band plus kl dense rows; a dense
    array up to ``dense_max`` rows (scipy's BDF then factorises it by LAPACK getrf), else CSC (SuperLU)."""
    jac = problem.jacobian(x, t)
    n = len(x) - 1
    grad = problem.wall_gradient(x)
    coupling = jac.bands[jac.ku + 1:, 0][:n]  # J[1..kl, 0]
    dense = -coupling[:, None] * (grad[1:] / grad[0])[None, :]
    if n <= dense_max:
        out = np.zeros((n, n))
        for k in range(-jac.kl, jac.ku + 1):  # diagonal k = column - row, band row ku - k
            values = jac.bands[jac.ku - k, 1:]
            np.fill_diagonal(out[:, k:] if k >= 0 else out[-k:, :], values[k:] if k >= 0 else values[:n + k])
        out[:len(coupling)] += dense
        return out
    import scipy.sparse as sp

    rows = np.repeat(np.arange(len(coupling)), n)
    cols = np.tile(np.arange(n), len(coupling))
    return (jac.sparse(1) + sp.coo_matrix((dense.ravel(), (rows, cols)), shape=(n, n))).tocsc()


def integrate(problem, t_out, *, rtol, atol, h0, observer=None, max_steps=MAX_STEPS, resume=None, bordered=True,
              wall_newton=True, stall=(1e-3, 50), handover="sdirk4", dense_max=DENSE_BDF_MAX):
    """``integrate`` with scipy's BDF on z = x[1:] (``problem.interior_rate``), x[0] from ``problem.project``
    (unit mass rows).

    BDF steps onto every output time (its bound moved on to the next one, no restart: scipy cuts the
    last step to the bound): its dense output is ~1e4 rtol off through an imposed speed's lift-off, where
    the landed steps are within ~1-20 rtol (bench/RESULTS.md "Remeshing the speed in time").
    Near a steady state at tight tolerances the round-off of the rate (|tau~|/h^2 eps) stops scipy's
    Newton from converging and the steps shrink without end: once the step has stayed below stall[0] t
    for stall[1] steps, after the problem's ``lift_off_end`` (the DAE's stiff transient, where BDF is
    needed), the rest goes to ``handover`` (whose Newton accepts an update at round-off).

    ``bordered``: Newton's systems I - c J are solved by the bordered band of NewtonMatrix (the unreduced M - c J)
    instead of scipy's own LU of the reduced J, whose fill-in from the wall's dense rows dominates (1.1-2.8x less
    CPU at 64-512 cells; False: the baseline of bench/speed_solver.py).  ``wall_newton``: Newton takes the imposed
    speed's wall row and column at each iterate and the band at the step's Jacobian: the wall unknown as a function
    of the interior curves with a sensitivity ~1/h_0 once the first cell's share of u~_w is small, and with all of
    it frozen Newton contracts too slowly and holds BDF at order 1 through the lift-off (bench/bdf_wall_newton.py)."""
    if not np.all(problem.mass[1:] == 1.0) or problem.mass[0] != 0.0:
        raise ValueError("method 'bdf' needs an algebraic row 0 and unit mass elsewhere")
    from scipy.integrate import BDF

    t_out = np.asarray(t_out, dtype=float)
    stats = StepStats(rejected=None)
    start = time.process_time()

    def state(z):
        return problem.project(np.concatenate(([0.0], z)))

    lift_off_end = getattr(problem, "lift_off_end", 0.0)
    iterate = [None]  # (t, x) of the last rate evaluation: in scipy's Newton, the iterate the next solve is at

    def rate(t, z):
        x = state(z)
        iterate[0] = t, x
        return problem.interior_rate(x, t) if np.isfinite(x[0]) else np.full(len(z), np.nan)

    t0, x0 = resume if resume is not None else (0.0, problem.initial())
    admissible = [state(x0[1:])]

    unreduced = []  # the last Jacobian of the unreduced problem (``bordered``)

    def jacobian(t, z):
        x = state(z)
        if np.isfinite(x[0]):
            admissible[0] = x
        if not bordered:
            return reduced_jacobian(problem, admissible[0], t, dense_max)
        unreduced[:] = [problem.jacobian(admissible[0], t)]
        return MARKER

    x = admissible[0]
    if bordered:
        # scipy's BDF uses its Jacobian J only to hand I - c J to lu. Handed J = MARKER = -1 and I = 0 (after
        # its set-up has seen an empty sparse n x n), it hands over c itself, and lu factorises the unreduced M - c J
        # by the bordered band (NewtonMatrix): I - c J is never formed (sparse, with its CSC bookkeeping, it would
        # cost ~0.3 ms a factorisation, a quarter of a 64-cell solve)
        import scipy.sparse as sp

        solver = BDF(rate, t0, x[1:], t_out[0], rtol=rtol, atol=atol, first_step=h0,
                     jac=lambda t, z: sp.csc_matrix((len(z), len(z))))
        solver.jac, solver.I, solver.J = jacobian, 0.0, jacobian(t0, x[1:])

        def lu(c):
            solver.nlu += 1
            return NewtonMatrix(problem, unreduced[0], float(c))

        def solve_lu(factors, b):
            """Newton's correction; the wall's row and column (of an imposed speed) at the current iterate if
            ``wall_newton``."""
            t, x = iterate[0]
            if wall_newton and factors.dense and np.isfinite(x[0]):
                factors.refresh_wall(problem.mass[0], *problem.wall_jacobian(x, t))
            return factors.solve(np.concatenate(([0.0], b)))[1:]

        solver.lu, solver.solve_lu = lu, solve_lu
    else:
        solver = BDF(rate, t0, x[1:], t_out[0], rtol=rtol, atol=atol, jac=jacobian, first_step=h0)
    states = np.empty((len(t_out), len(x)))
    if observer is not None and resume is None:
        observer(t0, x)
    k = small = 0  # the output times reached, the small steps in a row
    while k < len(t_out):
        if stats.steps >= max_steps:
            raise StepperFailure(f"max_steps = {max_steps} reached at t = {solver.t:.3e}")
        message = solver.step()
        if solver.status == "failed":
            raise NewtonFailure(f"BDF failed at t = {solver.t:.3e}: {message}")
        stats.steps += 1
        x = state(solver.y)
        if observer is not None:
            observer(solver.t, x)
        if solver.status == "finished":  # the step was cut to land on t_out[k]: the next bound, no restart
            states[k] = x
            k += 1
            if k < len(t_out):
                solver.t_bound, solver.status = t_out[k], "running"
            small = 0  # the landing's cut steps are no stall
            continue
        after = solver.t > lift_off_end
        small = small + 1 if after and solver.step_size < stall[0] * solver.t else 0
        if small >= stall[1]:
            states[k:], rest = integrate_dirk(problem, t_out[k:], method=handover, compiled=False, rtol=rtol, atol=atol,
                                         h0=solver.step_size, observer=observer, max_steps=max_steps - stats.steps,
                                         resume=(solver.t, x))
            stats.steps += rest.steps
            stats.newton_iterations += rest.newton_iterations
            break
    stats.newton_iterations += solver.nfev
    stats.cpu_seconds = time.process_time() - start
    return states, stats
