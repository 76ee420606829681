"""The granstokes continuum command: JSON contract, table, plot, one-line errors."""
import json
import subprocess
import sys

import numpy as np
import pytest
from granstokes.continuum.steady import mu_w_for_speed

from granstokes.cli import main

BEADS = ["--mu-s", str(np.tan(np.radians(21))), "--mu-d", str(np.tan(np.radians(33)))]


def exit_code(argv):
    """main()'s status; argparse usage errors exit through SystemExit."""
    try:
        return main(argv)
    except SystemExit as stop:
        return stop.code


def run(capsys, *args):
    code = exit_code(["continuum", *BEADS, *args])
    out, err = capsys.readouterr()
    # the one-time notice that a cold numba cache compiles the kernels (continuum.compiled) is not the command's
    err = "".join(line for line in err.splitlines(keepends=True) if not line.startswith("granstokes: compiling"))
    return code, out, err


def test_json_contract_imposed_stress(capsys, paper_friction):
    code, out, err = run(capsys, "--mu-w-tilde", "0.5", "--times", "1e-4", "1e-2", "1", "--json")
    assert code == 0 and err == ""
    data = json.loads(out)
    assert set(data) == {"imposed", "mu_s", "mu_d", "mu_w_inf", "beta_w", "t", "u_w", "mu_w", "delta", "steady",
                         "u_w_err", "mu_w_err", "delta_err", "accuracy"}
    assert data["imposed"] == "stress" and data["t"] == [1e-4, 1e-2, 1.0] and data["accuracy"] == 1e-6
    assert len(data["u_w"]) == len(data["mu_w"]) == len(data["delta"]) == len(data["delta_err"]) == 3
    for q in ("u_w", "delta"):  # the default accuracy is reached: every estimate below 1e-6 of its value
        assert np.all(np.array(data[f"{q}_err"]) <= 1e-6 * np.array(data[q]))
    assert data["mu_w_err"] == [0.0, 0.0, 0.0]  # imposed
    assert data["mu_w_inf"] == pytest.approx(paper_friction.mu_w_from_tilde(0.5), rel=1e-12)
    assert data["steady"]["u_w"] == pytest.approx(1.34039, abs=2e-5)
    assert data["mu_w"] == pytest.approx([data["mu_w_inf"]] * 3)
    assert np.all(np.diff(data["u_w"]) > 0) and np.all(np.diff(data["delta"]) > 0)


def test_json_contract_imposed_speed(capsys, paper_friction):
    code, out, _ = run(capsys, "--u-w", "1.334", "--times", "1e-3", "10", "--json")
    data = json.loads(out)
    assert code == 0 and data["imposed"] == "speed"
    assert data["mu_w_inf"] == pytest.approx(mu_w_for_speed(paper_friction, 1.334), rel=1e-12)
    assert data["u_w"] == pytest.approx([1.334, 1.334], rel=1e-10)
    assert data["steady"]["u_w"] == pytest.approx(1.334, rel=1e-12)
    assert data["mu_w"][0] > data["mu_w"][1] > data["mu_w_inf"] - 1e-4
    assert data["u_w_err"] == [0.0, 0.0]  # imposed (the constraint holds to round-off)


def test_mu_w_and_mu_w_tilde_agree(capsys, paper_friction):
    mu_w = paper_friction.mu_w_from_tilde(0.3)
    a = json.loads(run(capsys, "--mu-w", str(float(mu_w)), "--times", "0.1", "--json")[1])
    b = json.loads(run(capsys, "--mu-w-tilde", "0.3", "--times", "0.1", "--json")[1])
    assert a["u_w"] == pytest.approx(b["u_w"], rel=1e-12)


def test_table_and_plot(capsys, tmp_path):
    png = tmp_path / "profiles.png"
    code, out, _ = run(capsys, "--mu-w-tilde", "0.9", "--times", "0.01", "1", "--plot", str(png))
    assert code == 0 and "delta/delta_s" in out and "steady" in out and "y~ = y/delta_s" in out
    assert png.stat().st_size > 10_000


@pytest.mark.parametrize("args, name", [
    (["--mu-w", "0.3", "--times", "1"], "mu_w"),
    (["--mu-w", "0.7", "--times", "1"], "mu_w"),
    (["--mu-w-tilde", "0", "--times", "1"], "mu_w_tilde"),
    (["--mu-w-tilde", "1.5", "--times", "1"], "mu_w_tilde"),
    (["--mu-w-tilde", "nan", "--times", "1"], "mu_w_tilde"),
    (["--u-w", "0", "--times", "1"], "u_w"),
    (["--u-w", "-2", "--times", "1"], "u_w"),
    (["--u-w", "inf", "--times", "1"], "u_w"),
    (["--mu-w-tilde", "0.5", "--times", "1", "0.5"], "times"),
    (["--mu-w-tilde", "0.5", "--times", "0", "1"], "times"),
    (["--mu-w-tilde", "0.5", "--times", "-1"], "times"),
    (["--mu-w-tilde", "0.5", "--times", "nan"], "times"),
    (["--mu-w-tilde", "0.5", "--times", "1", "--n-cells", "3"], "n_cells"),
    (["--mu-w-tilde", "0.5", "--times", "1", "--plot", "out.pdf"], "--plot"),
])
def test_bad_input_is_one_line_naming_the_parameter(capsys, tmp_path, monkeypatch, args, name):
    monkeypatch.chdir(tmp_path)
    code, out, err = run(capsys, *args)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and err.startswith(f"granstokes: error: {name} must be")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("argv, needle", [
    (["continuum", "--mu-s", "-0.1", "--mu-d", "0.6", "--mu-w", "0.3", "--times", "1"], "mu_s must be"),
    (["continuum", "--mu-s", "0.6", "--mu-d", "0.5", "--mu-w", "0.55", "--times", "1"], "mu_d must be"),
    (["continuum", *BEADS, "--times", "1"], "one of the arguments"),
    (["continuum", *BEADS, "--mu-w", "0.5", "--u-w", "1", "--times", "1"], "not allowed with"),
])
def test_bad_friction_and_usage_errors(capsys, argv, needle):
    assert exit_code(argv) == 2
    err = capsys.readouterr().err
    assert needle in err and err.count("\n") == 1


def test_console_script_exit_status(tmp_path):
    """The installed entry point: non-zero status and one stderr line on bad input."""
    proc = subprocess.run([sys.executable, "-m", "granstokes.cli", "continuum", *BEADS, "--u-w", "-1",
                           "--times", "1"], capture_output=True, text=True, cwd=tmp_path)
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.strip() == "granstokes: error: u_w must be a finite number > 0, got -1.0"


def test_a_failed_solve_is_one_line_and_writes_nothing(capsys, tmp_path, monkeypatch):
    """The time stepper's failure (here its own step limit, cut to 5) is one stderr line naming the failure,
    exit status 1, no table and no --save folder."""
    import functools

    import granstokes.continuum.solver
    from granstokes.continuum.integrators import integrate

    monkeypatch.setattr(granstokes.continuum.solver, "integrate", functools.partial(integrate, max_steps=5))
    code, out, err = run(capsys, "--u-w", "1.334", "--times", "1", "--save", str(tmp_path / "out"))
    assert code == 1 and out == "" and len(err.strip().splitlines()) == 1
    assert err.startswith("granstokes: error: the time integration failed (max_steps = 5 reached")
    assert not (tmp_path / "out").exists()


def test_a_failed_linear_solve_is_exit_1_not_bad_input(capsys, tmp_path, monkeypatch):
    """numpy's LinAlgError is a ValueError, the bad-input signal; it is reported as a failure (exit 1)."""
    import granstokes.continuum.solver

    def singular(*args, **kwargs):
        raise np.linalg.LinAlgError("Singular matrix")

    monkeypatch.setattr(granstokes.continuum.solver, "integrate", singular)
    code, out, err = run(capsys, "--u-w", "1.334", "--times", "1", "--save", str(tmp_path / "out"))
    assert code == 1 and out == "" and len(err.strip().splitlines()) == 1
    assert err.startswith("granstokes: error: a linear solve failed (Singular matrix)")
    assert not (tmp_path / "out").exists()


def test_save_writes_pandas_readable_tables_and_metadata(capsys, tmp_path):
    import pandas as pd

    code, _, _ = run(capsys, "--u-w", "1.334", "--times", "0.01", "1", "--save", str(tmp_path / "out"))
    assert code == 0
    (stem,) = [p.name[:-len("_profiles.csv")] for p in (tmp_path / "out").glob("*_profiles.csv")]
    assert stem.startswith("continuum_speed_u_w1.334_")
    prof = pd.read_csv(tmp_path / "out" / f"{stem}_profiles.csv")
    series = pd.read_csv(tmp_path / "out" / f"{stem}_series.csv")
    meta = json.loads((tmp_path / "out" / f"{stem}.json").read_text())
    assert sorted(prof.t.unique()) == [0.01, 1.0]
    wall = prof[prof.y == 0.0].sort_values("t")
    assert wall.u.to_numpy() == pytest.approx([1.334, 1.334], rel=1e-9)  # the imposed speed, at the wall
    assert series.u_w.iloc[1:].to_numpy() == pytest.approx(1.334, rel=1e-8)
    assert meta["units"]["inertial_number"].startswith("paper:")
    # t~ = 0.01 is before 0.04 t~_mud/u~_w (continuum.solver.early_until): its solve on the deeper map counts in the
    # steps, while the series keeps its rows only up to 0.01, the later solve's after
    assert meta["early_map"]["times_below"] > 0.01 and meta["stats"]["steps"] > len(series) - 1
    assert np.all(np.diff(series.t) > 0) and series.t.iloc[-1] == 1.0
    assert meta["provenance"]["granstokes"] and {"numpy", "scipy", "python"} <= set(meta["provenance"])


def test_version_names_the_package_and_the_commit(capsys):
    from granstokes import __version__
    from granstokes.lib.provenance import git_hash

    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0
    out = capsys.readouterr().out.strip()
    assert out == f"granstokes {__version__} (git {git_hash() or 'unknown'})" and __version__ != "0+unknown"


def test_layering_no_package_imports_the_one_above():
    """continuum/ imports neither dem nor compare; dem/ does not import compare."""
    import re
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    rules = {"continuum": r"^\s*(from|import) (dem|compare)\b", "dem": r"^\s*(from|import) compare\b"}
    for package, pattern in rules.items():
        offenders = [str(p) for p in (root / package).rglob("*.py") if re.search(pattern, p.read_text(), re.M)]
        assert offenders == []


def test_table_and_plot_of_a_speed(capsys, tmp_path):
    """An imposed speed at the default accuracy: the table names the wall-clustered map (solver.map_for), its
    u~_w column is the imposed speed and its mu_w, delta carry estimates below 1e-6 relative; the plot is drawn."""
    from granstokes.continuum.solver import map_for

    from tests.continuum.reference import PAPER

    code, out, _ = run(capsys, "--u-w", "1.334", "--times", "1e-3", "3", "--plot", str(tmp_path / "p.png"))
    assert code == 0
    numerics = next(line for line in out.splitlines() if line.startswith("numerics:"))
    stretch, folds = map_for(PAPER, 0.5, "speed", 1e-3)
    assert f"stretch {stretch:.3g} + wall cluster {folds:.3g}," in numerics and "accuracy 1e-06 reached" in numerics
    rows = [line.split() for line in out.splitlines() if line.strip()[:1].isdigit()]
    assert [float(r[1]) for r in rows] == [1.334, 1.334]
    for r in rows:
        for value, err in ((r[4], r[6]), (r[7], r[9])):  # t, u~_w +- err, mu_w +- err, delta +- err
            assert float(err) <= 1e-6 * float(value)
    assert (tmp_path / "p.png").stat().st_size > 20_000


PREDICT_SCENE = ["--mu-s", "0.28", "--mu-d", "0.58", "--I0", "0.3", "--phi", "0.8", "--p-w", "20", "--depth", "30"]


def test_predict_at_an_imposed_speed_reports_the_friction_error_and_the_layer_depth(capsys):
    """A transient at imposed speed: mu_w with its error, and delta_u (depth where u falls to 5 % of u_w) in the
    JSON and the table; delta_u is the crossing of the returned profiles, and grows as the layer deepens."""
    argv = ["predict", "--model", "local", *PREDICT_SCENE, "--u-w", "5", "--times", "1", "5"]
    assert main([*argv, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["u_w_err"] == [0.0, 0.0] and 0 < max(data["mu_w_err"]) < 1e-4
    assert data["layer"].startswith("delta_u [d]")
    y, u = np.array(data["y"]), np.array(data["u"])
    for k, delta in enumerate(data["delta_u"]):
        ratio = u[k] / u[k, 0]
        j = int(np.argmax(ratio < 0.05))  # first node below 5 % of u_w, interpolated linearly
        assert delta == pytest.approx(np.interp(0.05, ratio[j:j - 2:-1], y[j:j - 2:-1]), rel=1e-12)
        assert data["delta_u_err"][k] < 1e-3 * delta
    assert 3 < data["delta_u"][0] < data["delta_u"][1] < 30
    assert main(argv) == 0
    table = capsys.readouterr().out.splitlines()
    assert table[1].split() == ["t", "u_w", "u_w_err", "mu_w", "mu_w_err", "delta_u", "[d]", "delta_u_err"]
    rows = [line.split() for line in table[2:]]
    assert [float(r[3]) for r in rows] == pytest.approx(data["mu_w"], rel=1e-7)
    assert [float(r[5]) for r in rows] == pytest.approx(data["delta_u"], rel=1e-5)


def test_predict_steady_gives_delta_s_with_its_unit(capsys):
    """delta_s = (tau_w/mu_s - p_w)/(phi rho_p g): (0.43 x 20/0.28 - 20)/0.8 = 13.393 d."""
    assert main(["predict", "--model", "local", *PREDICT_SCENE, "--mu-w", "0.43", "--steady"]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[1].endswith("delta_s = 13.3929 d")


def test_the_command_alone_prints_its_help(capsys):
    assert exit_code([]) == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: granstokes") and all(c in out for c in ("continuum", "dem", "compare", "demo"))
