"""The compiled loops' disk cache follows the code they compile in (continuum.kernels.source_key): numba keys a
cached function by its own bytecode and closure, so each loop carries in its closure a hash of the source of every
module it compiles in, taken when the module was imported, and of the numba options."""
from pathlib import Path

from granstokes.continuum import kernels, problems
from granstokes.continuum.bdf import bdf_loop
from granstokes.continuum.mesh import Mesh
from granstokes.continuum.problems import ImposedSpeed, ImposedStress
from granstokes.continuum.rheology import Friction
from granstokes.continuum.stepper import dirk_loop

FRICTION = Friction(0.3839, 0.6494)


def _closure(loop) -> dict:
    return dict(zip(loop.__code__.co_freevars, (c.cell_contents for c in loop.__closure__)))


def test_each_loop_holds_the_key_of_the_sources_it_compiles_in(monkeypatch):
    stress = ImposedStress(FRICTION, FRICTION.mu_w_from_tilde(0.5), Mesh.graded(16, 0.0))
    speed = ImposedSpeed(FRICTION, 1.334, Mesh.graded(16, 0.0))
    dirk, _ = stress.dirk_kernels()[:2]
    bdf = speed.bdf_kernels()[0]
    key_dirk = _closure(dirk_loop(dirk, compiled=False))["sources"]
    key_bdf = _closure(bdf_loop(bdf, compiled=False))["sources"]
    assert key_dirk == kernels.source_key(*dirk, dirk_loop) and key_bdf == kernels.source_key(*bdf, bdf_loop)
    assert key_dirk != key_bdf  # different loops' modules
    for module in ("granstokes.continuum.problems", "granstokes.continuum.kernels", "compiled"):
        edited = {**kernels._TEXTS, module: kernels._TEXTS[module] + "\n# an edit"}
        monkeypatch.setattr(kernels, "_TEXTS", edited)
        assert kernels.source_key(*dirk, dirk_loop) != key_dirk, module
        monkeypatch.undo()
    assert kernels.source_key(*dirk, dirk_loop) == key_dirk and len(key_dirk) == 16
    assert kernels._TEXTS["granstokes.continuum.problems"] == Path(problems.__file__).read_text()
