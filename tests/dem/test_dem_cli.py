"""``granstokes dem`` as users call it: help, --resume from the folder's own config with what is left,
--dry-run of a calibration, and progress as plain lines when stderr is not a terminal (no LAMMPS run)."""
import json
import sys
import textwrap

from granstokes.dem import config, layout
from granstokes.dem.calibrate import plan_calibration
from granstokes.dem.lammps_env import PLAIN_FRACTION, PLAIN_SECONDS
from granstokes.dem.runner import Lines, _Lammps
from granstokes.dem.sizing import plan

from granstokes.cli import main


def test_dem_alone_prints_its_help(capsys):
    assert main(["dem"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: granstokes dem") and "run" in out and "calibrate" in out


def _interrupted_run(folder):
    """A smoke run folder whose bed is prepared and whose drive was interrupted."""
    folder.mkdir()
    (folder / layout.CONFIG_TOML).write_text(config.preset_text("smoke"))
    stages = {"seed-1": {"status": "complete"}, "seed-1/speed": {"status": "interrupted"}}
    (folder / layout.RUN_JSON).write_text(json.dumps({"status": "interrupted", "stages": stages}))
    restart = layout.prepare_dir(folder, 1) / layout.PREPARED_RESTART
    restart.parent.mkdir(parents=True)
    restart.write_text("")
    return folder


def test_resume_reads_the_stored_config_and_says_what_is_left(tmp_path, capsys):
    run = _interrupted_run(tmp_path / "run")
    before = sorted(p.name for p in run.rglob("*"))
    assert main(["dem", "run", "--resume", "--out", str(run), "--dry-run"]) == 0
    err = capsys.readouterr().err
    assert "resume: 1 of 2 stages complete (seed-1); left: seed-1/speed" in err
    p = plan(config.preset("smoke")[0])
    left = p.cost_estimate(1, 1, ["seed-1"])
    assert f"  {left}\n" in err and "of what is left" in left
    assert sorted(p.name for p in run.rglob("*")) == before
    # the same with the preset given again (it must match the stored config)
    assert main(["dem", "run", "--preset", "smoke", "--resume", "--out", str(run), "--dry-run"]) == 0
    assert main(["dem", "run", "--preset", "quick", "--resume", "--out", str(run), "--dry-run"]) == 2
    assert "--resume must be given with the config stored in" in capsys.readouterr().err


def test_a_prepared_bed_without_its_restart_is_left_to_do(tmp_path, capsys):
    run = _interrupted_run(tmp_path / "run")
    (layout.prepare_dir(run, 1) / layout.PREPARED_RESTART).unlink()
    assert main(["dem", "run", "--resume", "--out", str(run), "--dry-run"]) == 0
    assert "resume: 0 of 2 stages complete (none); left: seed-1, seed-1/speed" in capsys.readouterr().err


def test_calibrate_dry_run_prints_the_plan_and_its_cost_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "cal"
    assert main(["dem", "calibrate", "--preset", "smoke", "--out", str(out), "--dry-run"]) == 0
    err = capsys.readouterr().err
    cp = plan_calibration(config.preset("smoke")[0])
    cfg = config.preset("smoke")[0]
    assert f"{cp.summary(out)}\n  {cfg.describe()[1]}\n  {cp.cost_estimate(2, 1)}\n" in err
    assert "'smoke' grains (2D disks), 7 inertial numbers in [0.005, 0.7]" in err and "k_n = " in err
    assert not out.exists()


def test_calibrate_resume_reads_the_stored_config_and_counts_the_points(tmp_path, capsys):
    out = tmp_path / "cal"
    out.mkdir()
    (out / layout.CONFIG_TOML).write_text(config.preset_text("smoke"))
    points = {"I-0/seed-1": {"status": "complete"}, "I-3/seed-1": {"status": "complete"},
              "I-1/seed-1": {"status": "interrupted"}}
    (out / layout.CALIBRATION_STATE).write_text(json.dumps({"points": points}))
    assert main(["dem", "calibrate", "--resume", "--out", str(out), "--dry-run"]) == 0
    err = capsys.readouterr().err
    # run order: longest (smallest I) first
    assert ("resume: 2 of 10 points complete (I-0/seed-1, I-3/seed-1); left: I-1/seed-1, I-2/seed-1, I-4/seed-1, "
            "I-5/seed-1, I-6/seed-1, modulus/seed-1, modulus/seed-2, modulus/seed-3") in err  # the shear modulus's last
    assert "of what is left" in err


class _Clock:
    def __init__(self):
        self.now = 0.0

    def __call__(self):
        return self.now


def test_plain_progress_every_tenth_and_every_half_minute(capsys):
    clock = _Clock()
    bar = Lines(1000, 0, "seed-1/speed", clock=clock)
    for _ in range(100):
        bar.update(10)
    bar.close()  # nothing new since the last line
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == round(1 / PLAIN_FRACTION) and lines[-1] == "seed-1/speed: 100% (1000/1000 steps), 0 s"
    bar = Lines(1000, 500, "seed-2", clock=clock)
    bar.set_postfix_str("t=1.5")
    clock.now += PLAIN_SECONDS
    bar.update(1)  # little progress, but half a minute passed
    bar.update(1)
    bar.close()
    assert capsys.readouterr().err.splitlines() == ["seed-2: 50% (501/1000 steps, t=1.5), 30 s",
                                                    "seed-2: 50% (502/1000 steps, t=1.5), 30 s"]


def test_lammps_progress_without_a_terminal_is_plain_lines(tmp_path, capsys, monkeypatch):
    """The screen of a (stand-in) LAMMPS process, read as a run reads it, reported as plain lines."""
    screen = textwrap.dedent("""\
        import sys
        print("PHASE settle")
        print("Step Time")
        for step in range(0, 1001, 50):
            print(f"  {step} {step / 1000}")
        print("Loop time of 0.1 on 1 procs")
        """)
    monkeypatch.setattr(_Lammps, "command", lambda self, script: [sys.executable, "-c", screen])
    info = _Lammps(1, None, True).run("in.lammps", tmp_path, None, 1000, 0, "seed-1")
    assert info["last_step"] == 1000 and info["phases"] == ["settle"] and info["returncode"] == 0
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 10 and all(line.startswith("seed-1 settle: ") for line in lines)
    assert lines[0].startswith("seed-1 settle: 10% (100/1000 steps, t=0.1)") and "100% (1000/1000" in lines[-1]


def test_the_plan_prints_every_resolved_parameter_and_the_defaults_it_used(tmp_path, capsys):
    """A config with only its required tables runs at the defaults, and its dry run says which: p_w, the dimension,
    the contact law with k_n, the seeds, each drive's duration, the depth, the output intervals, and the tables left
    out; a given table is not listed as a default."""
    path = tmp_path / "bare.toml"
    path.write_text(textwrap.dedent("""\
        name = "bare"
        [material]
        mu_s = 0.28
        mu_d = 0.58
        I0 = 0.3
        I_convention = "dem"
        phi = 0.8
        [[drive]]
        name = "push"
        kind = "stress"
        mu_w_tilde = 0.5
        """))
    assert main(["dem", "run", str(path), "--out", str(tmp_path / "run"), "--dry-run"]) == 0
    err = capsys.readouterr().err
    cfg = config.load(path)[0]
    p = plan(cfg)
    assert cfg.p_w == config.Config.p_w and cfg.grains == config.Grains()
    assert f"2D disks, p_w = {config.Config.p_w:g} rho_p g d, seeds [1]; sized from mu_s = 0.28" in err
    assert f"hooke contact (pair_style classic), k_n = {cfg.contact.k_n:.4g} (kappa = 10000 at this p_w)" in err
    assert f"duration {p.drives[0].duration:.4g} (max(10 t_s" in err and f"depth {p.depth:g} d = ceil(" in err
    assert f"outputs every (sqrt(d/g)): plate {config.Output().plate:g}, thermo" in err
    assert "defaults (no table in the config): [grains], [box], [output], [prepare], [calibration], [load]" in err
    path.write_text(path.read_text() + "[load]\np_w = 5.0\n")
    assert main(["dem", "run", str(path), "--out", str(tmp_path / "run"), "--dry-run"]) == 0
    err = capsys.readouterr().err
    assert "p_w = 5 rho_p g d" in err and "[load]" not in err.split("defaults (no table in the config): ")[1]
    assert not (tmp_path / "run").exists()


def test_an_interrupted_calibration_ends_with_the_command_that_continues_it(tmp_path, capsys, monkeypatch):
    """dem calibrate stopped by SIGTERM (the calibration itself stands in): exit 143, and the last line is the
    resume command with the options given that the folder does not store (--jobs, --launcher)."""
    import signal

    from granstokes.dem import calibrate

    out = tmp_path / "cal"
    monkeypatch.setattr(calibrate, "calibrate", lambda cfg, text, folder, **_: calibrate.CalibrateResult(
        folder, "interrupted", "interrupted by SIGTERM; continue with --resume", None, signal.SIGTERM))
    assert main(["dem", "calibrate", "--preset", "smoke", "--out", str(out), "--jobs", "3", "--launcher",
                 "srun -n {np}"]) == 143
    assert capsys.readouterr().err.splitlines()[-1] == (
        f"dem calibrate: interrupted (SIGTERM); continue with: granstokes dem calibrate --resume --out {out} "
        "--jobs 3 --launcher 'srun -n {np}'")
