"""numba's on-disk cache of a kernel is keyed to its own source file only: a kernel module that builds in code from
other modules records their digest (BUILT_FROM), so that editing them changes its file too and its stale machine
code is recompiled (without it a caller keeps the old callee's code after the callee's file changes)."""
import granstokes.continuum.compiled as compiled
import granstokes.continuum.problems as problems
import granstokes.continuum.speed_bdf as speed_bdf
import granstokes.continuum.stress_dirk as stress_dirk
import pytest


@pytest.mark.parametrize("module, built_from", [(speed_bdf, (compiled, problems)), (stress_dirk, (compiled,))],
                         ids=["speed_bdf", "stress_dirk"])
def test_a_kernel_module_records_the_sources_it_builds_in(module, built_from):
    expected = compiled.digest(*built_from)
    assert module.BUILT_FROM == expected, (
        f"{module.__name__}.BUILT_FROM is stale: set it to {expected!r} (its kernels' cache must change with "
        f"{', '.join(m.__name__ for m in built_from)})")


def test_the_digest_follows_the_text(tmp_path, monkeypatch):
    """The digest is of the sources' text: equal for equal text, different for one changed character."""
    import importlib

    monkeypatch.syspath_prepend(str(tmp_path))
    for name, text in (("gs_a", "X = 1\n"), ("gs_b", "X = 1\n"), ("gs_c", "X = 2\n")):
        (tmp_path / f"{name}.py").write_text(text)
    a, b, c = (importlib.import_module(name) for name in ("gs_a", "gs_b", "gs_c"))
    assert compiled.digest(a) == compiled.digest(b) != compiled.digest(c)
