"""Fourth-order space, accuracy on request with error estimates that bound the true
error, any time t~ > 0 (the small-time similarity limit), refusal of what cannot be met."""
import json
import subprocess
import sys

import numpy as np
import pytest
from granstokes.continuum.closed_forms import SmallTimeLimit
from granstokes.continuum.solver import Numerics, solve_stress

from tests.continuum import reference

TIMES = list(reference.TIMES)
#: the paper's three cases and a second friction law (mu_p ~ 0.5 disks: mu_s 0.28, mu_d 0.77)
CASES = [("paper", 0.9), ("paper", 0.5), ("paper", 0.1), ("disks", 0.3)]
#: the reference's relative accuracy (tests/continuum/test_reference.py), the floor of the comparisons
REF_FLOOR = reference.CONVERGED


def friction(name, paper_friction):
    return paper_friction if name == "paper" else reference.DISKS


@pytest.fixture(scope="module")
def references():
    """The independent reference (Chebyshev collocation, converged to 1e-9: tests/continuum/reference.py)."""
    return {(name, mt): reference.cached(f"{name}-{mt}") for name, mt in CASES}


def test_space_convergence_is_fourth_order(paper_friction):
    """Mesh halving with a fixed map, time error negligible: u~_w and delta converge at order 4."""
    mu_w = paper_friction.mu_w_from_tilde(0.5)
    sols = [solve_stress(paper_friction, mu_w, [1e-3, 0.1], Numerics(n_cells=n, stretch=6.0, rtol=1e-12, atol=1e-14))
            for n in (32, 64, 128)]
    for q in ("u_w", "delta"):
        v = np.array([getattr(s, q) for s in sols])
        d = np.abs(np.diff(v, axis=0)).max(axis=1)
        assert np.log2(d[0] / d[1]) == pytest.approx(4.0, abs=0.6), q


@pytest.mark.slow
@pytest.mark.parametrize("case", CASES)
def test_cli_default_is_accurate_to_1e6(references, paper_friction, case):
    """The default of ``granstokes continuum`` (imposed stress: accuracy 1e-6) gives u~_w, mu_w and
    delta within 1e-6 relative of the converged reference at every t~ in [1e-4, 10], and its
    estimates bound the true errors."""
    name, mt = case
    fr = friction(name, paper_friction)
    out = subprocess.run([sys.executable, "-m", "granstokes.cli", "continuum", "--mu-s", str(fr.mu_s),
                          "--mu-d", str(fr.mu_d), "--mu-w-tilde", str(mt), "--times", *map(str, TIMES), "--json"],
                         capture_output=True, text=True, check=True)
    got, ref = json.loads(out.stdout), references[case]
    for q in ("u_w", "mu_w", "delta"):
        true = np.abs(np.array(got[q]) - ref[q])
        assert np.all(true <= 1e-6 * np.abs(ref[q])), q
        assert np.all(true <= np.array(got[f"{q}_err"]) + REF_FLOOR * np.abs(ref[q])), q


@pytest.mark.parametrize("case", CASES)
def test_estimates_bound_the_true_error_and_are_not_too_pessimistic(references, paper_friction, case):
    """At accuracy 1e-4 (errors 1e-7..1e-5, far above the reference's): every estimate bounds the
    true error, and the largest estimate is within 10x of the largest true error (per quantity)."""
    name, mt = case
    fr = friction(name, paper_friction)
    sol = solve_stress(fr, fr.mu_w_from_tilde(mt), TIMES, accuracy=1e-4)
    ref = references[case]
    for q in ("u_w", "delta"):
        true = np.abs(getattr(sol, q) - ref[q])
        floor = REF_FLOOR * np.abs(ref[q])
        assert np.all(true <= sol.errors[q] + floor), q
        assert sol.errors[q].max() <= 10 * true.max(), q


@pytest.mark.slow
@pytest.mark.parametrize("mt", (0.9, 0.5))
def test_small_time_limit_is_the_similarity_solution(paper_friction, mt):
    """At t~ = 1e-8 (mesh and first step follow the smallest time) u~_w/sqrt(t~) and delta/sqrt(t~)
    equal the beta -> 0 similarity solution (SmallTimeLimit) up to its O(beta sqrt(t~)) correction;
    from t~ = 1e-6 to 1e-8 the gap in u~_w shrinks ten-fold, as that correction does."""
    fr = paper_friction
    mu_w = fr.mu_w_from_tilde(mt)
    lim = SmallTimeLimit(fr, mu_w)
    sol = solve_stress(fr, mu_w, [1e-8, 1e-6], accuracy=1e-7)
    gap_u = sol.u_w / np.sqrt(sol.t) / lim.wall_speed_coefficient - 1
    gap_d = sol.delta / np.sqrt(sol.t) / lim.delta_coefficient - 1
    beta_sqrt_t = fr.beta(mu_w) * np.sqrt(sol.t)
    assert np.all(np.abs(gap_u) < 0.2 * beta_sqrt_t)
    assert np.all(np.abs(gap_d) < 0.2 * beta_sqrt_t + 1e-6)
    assert gap_u[1] / gap_u[0] == pytest.approx(10.0, rel=0.2)


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "granstokes.cli", "continuum", "--mu-s", "0.38", "--mu-d", "0.64",
                           *args], capture_output=True, text=True)


@pytest.mark.parametrize("args, parameter", [
    (("--mu-w-tilde", "0.5", "--times", "1", "--accuracy", "1e-12"), "--accuracy"),
    (("--mu-w-tilde", "0.5", "--times", "1", "--accuracy", "0.5"), "--accuracy"),
    (("--mu-w-tilde", "0.5", "--times", "0", "1"), "times"),
])
def test_bad_requests_are_refused_with_the_range(args, parameter):
    r = run_cli(*args)
    assert r.returncode == 2 and r.stdout == ""
    assert len(r.stderr.strip().splitlines()) == 1 and parameter in r.stderr
    assert "in [" in r.stderr or "finite numbers > 0" in r.stderr  # the valid range is named


def test_an_unreachable_accuracy_is_refused_with_what_can_be_reached(paper_friction):
    """1e-10 at t~ = 1e-4 to 10 would need far more than the largest mesh: refused after the first
    estimate (no long refinement), naming the accuracy that can be reached."""
    with pytest.raises(ValueError, match=r"accuracy must be >= \d"):
        solve_stress(paper_friction, paper_friction.mu_w_from_tilde(0.5), TIMES, accuracy=1e-10)
