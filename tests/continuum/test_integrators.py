"""The integrators' contract at its edges (continuum.integrators): output times at the start return the initial
state, fixed steps that miss the outputs are refused before any step, and options a method cannot honour raise."""
import numpy as np
import pytest
from granstokes.continuum.integrators import integrate
from granstokes.continuum.mesh import Mesh
from granstokes.continuum.problems import ImposedSpeed, ImposedStress
from granstokes.continuum.rheology import Friction

FRICTION = Friction(0.3839, 0.6494)


def _stress():
    return ImposedStress(FRICTION, FRICTION.mu_w_from_tilde(0.5), Mesh.graded(16, 0.0))


@pytest.mark.parametrize("method, problem", [("sdirk4", _stress), ("bdf", lambda: ImposedSpeed(
    FRICTION, 1.334, Mesh.graded(16, 0.0)))])
def test_an_output_time_at_the_start_is_the_initial_state(method, problem):
    pb = problem()
    states, stats = integrate(pb, [0.0, 1e-3], method=method, compiled=False)
    start = pb.initial()
    assert np.allclose(states[0][pb.mass > 0], start[pb.mass > 0]) and stats.steps > 0
    assert not np.allclose(states[1], states[0])  # it moved on to the next time


@pytest.mark.parametrize("fixed", [[0.1, 0.2], [0.0, 0.5, 1.0], [0.5, 0.4, 1.0]])
def test_fixed_steps_that_miss_an_output_or_do_not_increase_are_refused(fixed):
    with pytest.raises(ValueError, match="fixed_times"):
        integrate(_stress(), [1.0], method="crank-nicolson", fixed_times=fixed)


def test_a_baseline_refuses_an_observer_it_cannot_call():
    with pytest.raises(ValueError, match="observer"):
        integrate(_stress(), [1.0], method="solve_ivp-BDF", observer=lambda t, x: None)


def test_scipy_s_solve_ivp_is_called_from_the_registry_only():
    """Every solve_ivp run is a registered baseline (continuum.integrators): no other module of the package imports
    or calls it."""
    import ast
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    users = set()
    for folder in ("continuum", "dem", "compare", "granstokes"):
        for path in (root / folder).rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text())):
                named = (isinstance(node, ast.ImportFrom) and any(a.name == "solve_ivp" for a in node.names)
                         or isinstance(node, ast.Attribute) and node.attr == "solve_ivp")
                if named:
                    users.add(str(path.relative_to(root)))
    assert users == {"continuum/integrators.py"}
