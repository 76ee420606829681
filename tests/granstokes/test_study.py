"""granstokes study: the config and its checks, --set, sizing from the calibration (one material), and (slow)
the smoke study through a Dask scheduler, killed mid-way and resumed."""
import json
import math
import os
import re
import signal
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import pytest
from granstokes.compare.stokes_experiment import EARLY_FRAMES_PER_TS, FRAMES_PER_TS
from granstokes.dem import config as dem_config
from granstokes.dem.calibrate import material_table
from granstokes.dem.sizing import clearance

from granstokes.cli import main as granstokes_main
from granstokes.study import config
from granstokes.study.plan import calibration_config, plan_study

ROOT = Path(__file__).resolve().parents[2]
CALIBRATION = ROOT / "results" / "quick-calibration" / "calibration.json"


def _study(**changes) -> str:
    doc = {"name": "t", "dem": "quick", "seeds": [1, 2], "pressures": [10.0, 20.0],
           "calibration": {"file": str(CALIBRATION)},
           "drive": [{"kind": "stress", "mu_w_tilde": 0.5}, {"kind": "speed", "mu_w_tilde": 0.5},
                     {"kind": "stress", "tau_w": 6.0}]}
    doc.update(changes)
    import tomli_w
    return tomli_w.dumps(doc)


@pytest.mark.parametrize("change, message", [
    ({"pressures": []}, "pressures must be"),
    ({"pressures": [10.0, 10.0]}, "pressures must be"),
    ({"dem": "nope"}, "dem must be one of the DEM presets"),
    ({"calibration": {"file": "/nonexistent/calibration.json"}}, "calibration.file must be"),
    ({"calibration": {"run": True, "wobble": 1}}, "calibration keys must be"),
    ({"drive": [{"kind": "stress", "u_w": 1.0}]}, r"drive\[stress-u1\] load must be"),
    ({"drive": [{"kind": "stress", "mu_w_tilde": 0.5, "mu_w": 0.4}]}, r"drive\[0\] load must be"),
    ({"colour": "red"}, "study keys must be"),
    ({"seeds": [True]}, "seeds must be"),
])
def test_bad_studies_are_refused_naming_the_parameter(change, message):
    with pytest.raises(ValueError, match=message) as err:
        config.parse(_study(**change))
    assert "\n" not in str(err.value)


def test_sizing_comes_from_the_calibration_with_one_material(tmp_path):
    """Every run is sized from the calibrated material: depth >= delta_s + the depth study's clearance, duration >= 10
    calibrated t_s, frames every t_s/FRAMES_PER_TS of the fastest drive; the grains' k_n is one at every pressure
    (kappa scales as 1/p), the calibration stage's too; tau_w gives mu_w = tau_w/p_w.  Each run's and calibration's
    TOML is the config it runs."""
    study = config.parse(_study())
    material, _, _ = material_table(CALIBRATION)
    sp = plan_study(study, material, "test")
    k_n = set()
    assert list(sp.runs) == ["p10", "p20", "p20-wide"]
    for label, run in sp.runs.items():
        p_w, text, p = run.p_w, run.text, run.plan
        cfg = p.config
        assert dem_config.parse(text) == cfg
        assert cfg.p_w == p_w and cfg.seeds == (1, 2) and cfg.material.mu_s == pytest.approx(material["mu_s"])
        assert cfg.material.phi == pytest.approx(material["phi"]) and cfg.material.I0 == pytest.approx(material["I0"])
        k_n.add(round(cfg.contact.k_n, 6))
        deepest = max(d.scales.delta_s for d in p.drives)
        assert p.depth >= deepest + clearance(deepest)
        for d in p.drives:
            assert d.duration == pytest.approx(10 * d.scales.t_s, rel=1e-9)
        frame = min(d.scales.t_s for d in p.drives) / FRAMES_PER_TS  # the snapshots as LAMMPS writes them
        assert abs(p.intervals["atoms"] * p.dt - frame) <= p.intervals["plate"] * p.dt
        assert p.intervals["plate"] <= p.intervals["atoms"] and p.intervals["profiles"] <= p.intervals["atoms"]
        # denser over the first t_s: EARLY_FRAMES_PER_TS per t_s, on the coarse grid too (a divisor)
        fine, early = p.intervals["atoms_early"], p.intervals["early"]
        assert p.intervals["atoms"] % fine == 0
        assert abs(early * p.dt - frame * FRAMES_PER_TS) <= p.intervals["atoms"] * p.dt
        assert abs(fine * p.dt - frame * FRAMES_PER_TS / EARLY_FRAMES_PER_TS) <= p.intervals["plate"] * p.dt
        if label.endswith("-wide"):  # the width check: the first drive alone, twice as wide
            assert [d.drive.name for d in p.drives] == ["stress-mutilde0.5"]
            assert cfg.box.width == 2 * sp.runs["p20"].plan.config.box.width and p_w == 20.0
            assert p.depth == sp.runs["p20"].plan.depth  # as deep as the run it checks
            continue
        tau = next(d for d in p.drives if d.drive.tau_w is not None)
        assert tau.scales.mu_w == pytest.approx(6.0 / p_w)
    assert len(k_n) == 1
    cal, text = calibration_config(study, 10.0)
    assert round(cal.contact.k_n, 6) in k_n and cal.p_w == 10.0 and dem_config.parse(text) == cal
    # the same sizing through dem run --calibration: the preset's nominal material replaced
    out = tmp_path / "dry"
    assert granstokes_main(["dem", "run", "--preset", "quick", "--calibration", str(CALIBRATION), "--out", str(out),
                            "--dry-run"]) == 0
    assert not out.exists()


def test_set_overrides_and_presets_print(capsys):
    study, text = config.load(None, "smoke", ["seeds=[3, 4, 5]", "pressures=[4.0]", "drive.0.mu_w_tilde=0.3"])
    assert study.seeds == (3, 4, 5) and study.pressures == (4.0,) and study.drives[0].mu_w_tilde == 0.3
    assert tomllib.loads(text)["seeds"] == [3, 4, 5] and text.startswith("# smoke with --set")
    with pytest.raises(ValueError, match="--set"):
        config.load(None, "smoke", ["seeds"])
    assert granstokes_main(["preset", "study", "smoke"]) == 0
    printed = capsys.readouterr().out
    assert config.parse(printed) == config.load(None, "smoke")[0]
    assert granstokes_main(["preset", "dem"]) == 0
    assert set(capsys.readouterr().out.split()) == set(dem_config.PRESETS)


def test_the_dry_run_adds_the_comparison_to_the_beds(tmp_path, capsys, canned_speed):
    """The smoke study's dry run prints the comparison (every snapshot of every bed coarse-grained, the width
    check's too; each scored drive's models a unit of work over the jobs, its report) and one total: the
    calibrations, the beds, the comparison and the start-up, with the disk."""
    from granstokes.compare.stokes_experiment import CG_PER_DRIVE_STEP, MODEL_DRIVE_STEPS, MODELS, REPORT_DRIVE_STEPS
    from granstokes.dem.calibrate import plan_calibration
    from granstokes.dem.estimate import STARTUP, duration_text

    assert granstokes_main(["study", "--preset", "smoke", "--out", str(tmp_path / "s"), "--jobs", "2",
                            "--dry-run"]) == 0
    printed = capsys.readouterr().err
    nominal = dem_config.preset("smoke")[0].material
    sp = plan_study(config.load(None, "smoke")[0], {k: getattr(nominal, k) for k in dem_config.MATERIAL_KEYS}, "")
    assert list(sp.runs) == ["p5", "p10", "p10-wide"] and sp.scored_drives() == 4
    # 2 seeds x (2 drives at p5 and at p10, 1 in the wide run), a snapshot every output.atoms as LAMMPS writes it,
    # every output.atoms_early over the first output.early
    frames = {label: 2 * sum(d.duration / (r.plan.intervals["atoms"] * r.plan.dt)
                             + min(d.steps, r.plan.intervals["early"]) * (1 / r.plan.intervals["atoms_early"]
                                                                         - 1 / r.plan.intervals["atoms"])
                             for d in r.plan.drives) for label, r in sp.runs.items()}
    assert sp.grain_frames() == pytest.approx(sum(sp.runs[k].plan.n_grains * n for k, n in frames.items()), rel=0.02)
    rate = canned_speed.rate(2, "drive")
    cg, model = sp.grain_frames() / (CG_PER_DRIVE_STEP * rate), MODELS * MODEL_DRIVE_STEPS / rate
    cg += 4 * REPORT_DRIVE_STEPS / rate  # each drive's report, one after the other
    assert sp.comparison_seconds(1) == pytest.approx(cg + 4 * model)  # one process: the drives in turn
    assert sp.comparison_seconds(2) == pytest.approx(cg + 2 * model * canned_speed.contention)  # two at once
    beds = sp.cost_seconds(2)
    assert f"the study's beds: about {duration_text(beds)} with 2 job(s)" in printed
    assert f"the comparison: about {duration_text(sp.comparison_seconds(2))} (" in printed
    calibration = sum(plan_calibration(calibration_config(config.load(None, "smoke")[0], p)[0]).estimate(2)
                      .seconds for p in (5.0, 10.0))
    total = calibration + beds + sp.comparison_seconds(2) + STARTUP["study"]
    assert re.search(rf"total: about {re.escape(duration_text(total))} on this machine \(calibration "
                     rf"{re.escape(duration_text(calibration))} \+ beds .* and [\d.]+ MB of disk", printed)
    assert not (tmp_path / "s").exists()


@pytest.mark.slow
def test_a_scheduler_address_is_checked_and_a_dry_run_needs_no_scheduler(tmp_path, capsys):
    """--scheduler: a malformed address is one line naming the option (exit 2), an address where nothing answers
    too, within seconds; a dry run checks the form only, prints the plan and says the workers set the
    concurrency."""
    import socket

    out = tmp_path / "s"
    with socket.socket() as closed:
        closed.bind(("127.0.0.1", 0))
        nobody = f"tcp://127.0.0.1:{closed.getsockname()[1]}"
    for address in ("127.0.0.1", "tcp://127.0.0.1", nobody):
        start = time.monotonic()
        assert granstokes_main(["study", "--preset", "smoke", "--out", str(out), "--scheduler", address]) == 2
        err = capsys.readouterr().err
        assert err.startswith("granstokes: error: --scheduler must be ") and err.count("\n") == 1, err
        assert time.monotonic() - start < 15 and not out.exists()
    assert granstokes_main(["study", "--preset", "smoke", "--out", str(out), "--scheduler", nobody, "--dry-run"]) == 0
    err = capsys.readouterr().err
    assert f"study: on the scheduler {nobody}, its workers set the concurrency" in err
    assert "the study's beds" in err and not out.exists()


#: the smoke study cut to what the test needs: one pressure, one drive of 4 t_s, one seed, a 6-point calibration
#: without the shear modulus (tests/dem/test_modulus.py measures it; here it would be half the calibration's cost)
SMALL = ["pressures=[10.0]", "seeds=[1]", 'drive=[{kind = "speed", mu_w_tilde = 0.5}]', "min_duration=0.0",
         "duration_ts=4.0",
         "calibration.I=[0.01, 0.03, 0.08, 0.2, 0.4, 0.6]", "calibration.modulus=false"]


@pytest.mark.slow
def test_the_smoke_study_through_a_scheduler_killed_and_resumed(tmp_path, capsys):
    """The study runs its beds on a dask-jobqueue cluster whose 2 jobs are local worker processes offering
    ranks=1 (--scheduler; SLURMCluster's machinery without a queue); SIGTERM once the calibration is complete
    stops it (status interrupted, exit 143, a last line with the command that continues it, no traceback);
    --resume finishes it without redoing the calibration; metrics.json has the drives table, study.json every
    run with its status, the last line points at the report."""
    from dask_jobqueue.local import LocalCluster

    out = tmp_path / "study"
    with LocalCluster(cores=1, processes=1, memory="2GB", worker_extra_args=["--resources", "ranks=1"],
                      scheduler_options={"dashboard_address": "127.0.0.1:0"}) as cluster:
        cluster.scale(jobs=2)
        cluster.wait_for_workers(2, timeout=60)
        args = [sys.executable, "-m", "granstokes.cli", "study", "--preset", "smoke", "--out", str(out), "--quiet",
                "--scheduler", cluster.scheduler_address, *[x for s in SMALL for x in ("--set", s)]]
        proc = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        state = out / "calibration-p10" / "state.json"
        deadline = time.monotonic() + 240
        while time.monotonic() < deadline and proc.poll() is None:
            if state.exists() and json.loads(state.read_text() or "{}").get("status") == "complete":
                break
            time.sleep(0.2)
        os.kill(proc.pid, signal.SIGTERM)
        _, err = proc.communicate(timeout=120)
    assert proc.returncode == 143, err
    assert "Traceback" not in err and "CancelledError" not in err, err
    assert err.splitlines()[-1] == ("study: interrupted (SIGTERM); continue with: granstokes study --resume --out "
                                    f"{out} --scheduler {cluster.scheduler_address}"), err
    record = json.loads((out / "study.json").read_text())
    assert record["status"] == "interrupted" and "--resume" in record["message"]
    calibrated = json.loads(state.read_text())
    capsys.readouterr()
    assert granstokes_main(["study", "--resume", "--out", str(out), "--quiet"]) == 0
    last = capsys.readouterr().err.splitlines()[-1]
    assert last.startswith("study: complete: ") and last.endswith(f"(report: {out / 'index.html'}; record: "
                                                                  f"{out / 'study.json'})")
    assert json.loads(state.read_text())["points"] == calibrated["points"]  # not redone
    record = json.loads((out / "study.json").read_text())
    assert record["status"] == "complete" and record["runs"]["p10"]["status"] == "complete"
    assert record["runs"]["p10"]["beds"] == {"seed-1": "complete"} and len(record["resumes"]) == 1
    assert record["runs"]["p10-wide"]["status"] == "complete"
    (check,) = record["width_check"]  # the wide drive is analysed against the normal one, never scored
    assert check["drive"] == "speed-mutilde0.5" and check["observable"] == "mu_w_inf" and check["wide_err"] > 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert list(metrics["drives"]) == ["runs/p10/speed-mutilde0.5"] and metrics["runs"] == ["runs/p10"]
    (drive,) = metrics["drives"].values()
    for key in ("p_w", "kind", "imposed", "seeds", "depth", "duration", "delta_s", "t_s", "base_confined"):
        assert key in drive
    assert drive["p_w"] == 10.0 and drive["kind"] == "speed" and drive["seeds"] == 1
    assert drive["t_s"] > 0 and drive["duration"] == pytest.approx(4 * drive["t_s"], rel=0.05)
    assert (out / "index.html").exists() and (out / "runs" / "p10" / "run.json").exists()


@pytest.mark.slow
def test_ctrl_c_stops_a_study_quietly_and_says_how_to_continue(tmp_path):
    """Ctrl-C (SIGINT to the study's process group, LAMMPS included) while its beds run on the local cluster:
    exit 130, study.json interrupted, no traceback or Dask warning on stderr, and the last line is the command
    that continues it."""
    out = tmp_path / "study"
    given = ["pressures=[20.0]", "seeds=[1, 2, 3]", "width_check=false",  # the committed calibration's grains
             f'calibration={{file = "{CALIBRATION}"}}']
    proc = subprocess.Popen([sys.executable, "-m", "granstokes.cli", "study", "--preset", "smoke", "--out", str(out),
                             "--quiet", *[x for s in given for x in ("--set", s)]],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, start_new_session=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None and not list(out.glob("runs/p20/seed-*/prepare")):
        time.sleep(0.05)
    time.sleep(0.5)
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert json.loads((out / "study.json").read_text())["status"] == "interrupted"
    for noise in ("Traceback", "CancelledError", "WARNING", "KeyboardInterrupt"):
        assert noise not in err, err
    assert err.splitlines()[-1] == f"study: interrupted (SIGINT); continue with: granstokes study --resume --out {out}"


def test_the_last_line_points_at_the_report_as_given():
    """Complete: the report and the record under --out as the user wrote it; failed: why and the record."""
    from argparse import Namespace

    from granstokes.study.cli import final_line

    args = Namespace(out="my-study", scheduler=None, jobs=2)
    assert final_line({"status": "complete", "message": "verdict"}, args) == \
        "study: complete: verdict (report: my-study/index.html; record: my-study/study.json)"
    assert final_line({"status": "failed", "message": "why"}, args) == "study: failed: why (see my-study/study.json)"
    assert final_line({"status": "interrupted", "signal": 15}, Namespace(out="a b", scheduler="tcp://h:1", jobs=2)) \
        == "study: interrupted (SIGTERM); continue with: granstokes study --resume --out 'a b' --scheduler tcp://h:1"


def _cluster_recipe(page: str = "docs/cluster.md") -> str:
    """The Python block of ``page`` that builds the SLURMCluster (docs/cluster.md's: the driver)."""
    import re

    return next(b for b in re.findall(r"```python\n(.*?)```", (ROOT / page).read_text(), re.S) if "SLURMCluster(" in b)


@pytest.mark.parametrize("page, lines", [
    ("docs/cluster.md", ["#SBATCH -A my-account", "#SBATCH -p compute", "#SBATCH --cpus-per-task=32",
                         "#SBATCH --mem=60G", "#SBATCH -t 04:00:00", "source /shared/granstokes/.venv/bin/activate"])])
def test_the_cluster_recipe_builds_its_slurm_job(tmp_path, page, lines):
    """The SLURMCluster of docs/cluster.md (README points there), up to the submission: the installed dask-jobqueue
    accepts its arguments and writes a job of the account, partition, cores, memory and walltime given (and the shared
    environment), whose workers run one thread each, offer the ``ranks`` resource the beds hold and leave before
    the walltime."""
    setup = _cluster_recipe(page).split("cluster.adapt")[0].replace("/shared/dask-logs", str(tmp_path / "logs"))
    scope = {}
    exec(setup, scope)
    cluster = scope["cluster"]
    try:
        script = cluster.job_script()
    finally:
        cluster.close()
    for line in lines:
        assert f"\n{line}\n" in script, script
    for arg in ("--nthreads 1", "--nworkers 32", "--resources ranks=1", "--lifetime 230m", "--lifetime-stagger 5m"):
        assert arg in script, script
    assert 230 + 5 < 4 * 60  # the latest departure, in minutes, before the walltime


@pytest.mark.slow
def test_the_cluster_driver_runs_the_study_on_its_scheduler(tmp_path, monkeypatch, capfd):
    """docs/cluster.md's driver with dask-jobqueue's local jobs in place of Slurm's (its Slurm entries and
    prologue dropped, one worker per job): it starts the cluster, waits for a worker, runs granstokes study with
    the scheduler's address added (a dry run, then a refused study) and exits with the study's status."""
    import types

    from dask_jobqueue.local import LocalCluster

    class Local(LocalCluster):
        def __init__(self, **given):
            given = {k: v for k, v in given.items() if k in ("worker_extra_args",)}
            super().__init__(cores=1, processes=1, memory="1GB", scheduler_options={"dashboard_address": ":0"},
                             **given)

    monkeypatch.setitem(sys.modules, "dask_jobqueue", types.SimpleNamespace(SLURMCluster=Local))
    monkeypatch.setenv("PATH", f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}")
    handlers = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    out = tmp_path / "s"
    try:
        for args, code in ((["--dry-run"], 0), (["--set", "colour=1"], 2)):
            monkeypatch.setattr(sys, "argv", ["slurm_study.py", "--preset", "smoke", "--out", str(out), *args])
            with pytest.raises(SystemExit) as stop:
                exec(compile(_cluster_recipe(), "slurm_study.py", "exec"), {"__name__": "__main__"})
            assert stop.value.code == code
            err = capfd.readouterr().err
            if code == 0:
                assert "study: on the scheduler tcp://" in err and "the study's beds" in err
            else:
                assert "granstokes: error: study keys must be" in err
    finally:
        for s, handler in handlers.items():
            signal.signal(s, handler)
    assert not out.exists()


def test_the_demo_runs_its_study_once_then_renders_again(tmp_path, monkeypatch):
    """make demo twice: the study runs once (its folder is the study's own, not refused), the front page is
    written both times; a study that stops leaves a one-line error and exit 1."""
    from granstokes import demo
    from granstokes.lib.staging import start

    calls = []

    def fake_study(study, text, folder, resume=False, **_):
        calls.append(resume)
        start(folder, "study")
        status = "failed" if len(calls) == 3 else "complete"
        (folder / "metrics.json").write_text(json.dumps({"verdict": "v", "units": "u"}))
        (folder / "study.toml").write_text(text)
        (folder / "study.json").write_text(json.dumps({"status": status, "message": "m"}))
        return {"status": status, "message": "m"}

    monkeypatch.setattr(demo, "run_study", fake_study)
    monkeypatch.setattr(demo, "write_continuum_report", lambda work: (work / "index.html").write_text("c"))
    out = tmp_path / "demo"
    assert demo.run_demo(out).exists() and demo.run_demo(out).exists()
    assert calls == [False]
    other = tmp_path / "other"
    demo.run_demo(other)
    (other / "study" / "study.json").write_text(json.dumps({"status": "running"}))
    assert granstokes_main(["demo", "--out", str(other)]) == 1 and calls == [False, False, True]


def test_the_runs_are_one_per_pressure_and_frequency():
    """An oscillating study runs each frequency of its drives at each pressure in a run of its own (a held study: one
    run per pressure), every run's TOML the config it runs."""
    study = config.load(None, "oscillating-smoke", ["pressures=[10.0, 20.0]", "omega_ts=[5.0, 0.5]"])[0]
    nominal = dem_config.preset(study.dem)[0].material
    sp = plan_study(study, {k: getattr(nominal, k) for k in dem_config.MATERIAL_KEYS}, "")
    assert list(sp.runs) == ["p10-w0.5", "p10-w5", "p20-w0.5", "p20-w5"]
    for label, r in sp.runs.items():
        wave = label.partition("-")[2]
        assert [d.drive.name for d in r.plan.drives] == [f"stress-mutilde0.5-{wave}", f"speed-mutilde0.5-{wave}"]
        assert dem_config.parse(r.text) == r.plan.config


def test_a_resume_plans_a_begun_run_as_its_stored_config(tmp_path):
    """A run folder begun under an older sizing goes on as stored; runs not begun are planned anew; the cost
    counts only the stages left."""
    study = config.parse(_study(width_check=False))
    material, _, _ = material_table(CALIBRATION)
    sp = plan_study(study, material, "test")
    folder = sp.folder(tmp_path, "p10")
    folder.mkdir(parents=True)
    stored = sp.runs["p10"].text.replace("duration_ts = 10.0", "duration_ts = 3.0")
    (folder / "config.toml").write_text(stored)
    stages = {k: {"status": "complete"} for k in sp.runs["p10"].plan.stage_keys(1)}
    (folder / "run.json").write_text(json.dumps({"stages": stages}))
    begun = sp.as_begun(tmp_path)
    assert begun.runs["p10"].text == stored and begun.runs["p20"] is sp.runs["p20"]
    first = begun.runs["p10"].plan.drives[0]
    assert first.duration == pytest.approx(3 * first.scales.t_s)
    assert begun.done(tmp_path) == {f"p10/{k}" for k in stages}
    assert begun.cost_seconds(1, tmp_path) < begun.cost_seconds(1)


def test_a_resume_past_the_calibration_sizes_from_it_and_does_not_cost_it_again(tmp_path, capsys):
    """A smoke study whose calibrations completed: its resumed dry run sizes the runs from the reference
    pressure's calibration.json (not the preset's nominal material), prints no calibration cost, and its total
    has no calibration stage; a study not yet calibrated still prints both."""
    from granstokes.dem.layout import CALIBRATION_JSON, CALIBRATION_STATE

    from granstokes.study.plan import calibration_folder

    out = tmp_path / "s"
    out.mkdir()
    (out / "study.toml").write_text(config.preset_text("smoke"))
    study = config.load(None, "smoke")[0]
    for p_w in study.calibration_pressures:
        folder = calibration_folder(out, p_w)
        folder.mkdir()
        (folder / CALIBRATION_JSON).write_bytes(CALIBRATION.read_bytes())
        (folder / CALIBRATION_STATE).write_text(json.dumps({"status": "complete", "points": {}}))
    assert granstokes_main(["study", "--resume", "--out", str(out), "--dry-run"]) == 0
    err = capsys.readouterr().err
    reference = calibration_folder(out, study.reference_pressure) / CALIBRATION_JSON
    assert f"sized from {reference.parent.relative_to(out)} ->" in err and "nominal material" not in err
    assert "study: calibration at p" not in err and "(calibration " not in err and "total: about" in err
    material = material_table(CALIBRATION)[0]
    sp = plan_study(study, material, "")
    assert f"depth {sp.runs['p10'].plan.depth:g} d" in err  # sized from the calibration
    (calibration_folder(out, study.reference_pressure) / CALIBRATION_STATE).write_text('{"status": "running"}')
    assert granstokes_main(["study", "--resume", "--out", str(out), "--dry-run"]) == 0
    err = capsys.readouterr().err
    assert "nominal material" in err and "study: calibration at p = 10" in err and "(calibration " in err
    assert "study: calibration at p = 5" not in err  # complete: not run again, not costed


def test_a_preset_runs_from_any_working_directory_and_a_missing_file_is_named(tmp_path, monkeypatch, capsys):
    """The oscillating-disks preset names committed results relative to the repository: its dry run works from
    any folder; the same text saved elsewhere (its paths now relative to that file) is refused with the file
    named as missing, before any work."""
    monkeypatch.chdir(tmp_path)
    assert granstokes_main(["study", "--preset", "oscillating-disks", "--out", "s", "--dry-run"]) == 0
    assert "total: about" in capsys.readouterr().err and not (tmp_path / "s").exists()
    saved = tmp_path / "mine.toml"
    saved.write_text(config.preset_text("oscillating-disks"))
    assert granstokes_main(["study", str(saved), "--out", "s", "--dry-run"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "calibration.file must be" in err[0] and "(this file is missing)" in err[0]
    assert str(tmp_path / "results" / "calibration-disks" / "p20" / "calibration.json") in err[0]


def test_the_plan_prints_each_stokes_drives_growth_window_at_the_measured_shear_wave_speed(capsys):
    """The disks preset sized from the committed p = 20 calibration (c_s = 118 measured): each drive's window runs
    from 3 transits of its bed at that speed (not at the contacts' 270) to min(t_s/2, half the record); the shortest
    layers have none (their elastic start reaches past t_s/2)."""
    cal = ROOT / "results" / "calibration-disks" / "p20" / "calibration.json"
    c_s = json.loads(cal.read_text())["elasticity"]["c_s"]
    assert granstokes_main(["study", "--preset", "disks", "--out", "unused", "--dry-run", "--set",
                            f"calibration={{file = '{cal}'}}"]) == 0
    err = capsys.readouterr().err
    assert f"transits at the calibration's measured c_s = {c_s:.4g}" in err
    found = 0
    for m in re.finditer(r"t_s = ([\d.e+-]+), depth ([\d.]+) d, .*?, growth window ([\d.e+-]+) decade\(s\) "
                         r"\[([\d.e+-]+), ([\d.e+-]+)\]", err):
        t_s, depth, decades, start, end = map(float, m.groups())
        assert start == pytest.approx(3 * depth / c_s, rel=6e-3)  # printed to 3 digits: 0.5 % at worst
        assert end == pytest.approx(0.5 * t_s, rel=6e-3)
        assert decades == pytest.approx(math.log10(end / start), abs=0.01)
        found += 1
    nothing = re.findall(r"t_s = ([\d.e+-]+), depth ([\d.]+) d, .*?, no growth window \(the elastic start, "
                         r"([\d.e+-]+), reaches past ([\d.e+-]+)\)", err)
    assert found >= 8 and nothing  # every disks drive has one or the other
    for t_s, depth, start, end in nothing:
        assert float(start) == pytest.approx(3 * float(depth) / c_s, rel=6e-3) and float(start) > float(end)
        assert float(end) == pytest.approx(0.5 * float(t_s), rel=6e-3)


def test_a_resume_may_add_beds_to_a_study_and_nothing_else():
    """granstokes.study.runner.adds_beds: seeds that continue the stored ones, or another error target, add beds;
    reordered seeds, fewer seeds or another grid do not."""
    from granstokes.study.runner import adds_beds

    stored = config.parse(_study(seeds=[1, 2]))
    assert adds_beds(stored, config.parse(_study(seeds=[1, 2, 3])))
    assert adds_beds(stored, config.parse(_study(seeds=[1, 2], target={"creep_length": 0.5})))
    for other in (_study(seeds=[2, 1, 3]), _study(seeds=[1]), _study(seeds=[1, 2]),
                  _study(seeds=[1, 2, 3], pressures=[10.0, 40.0])):
        assert not adds_beds(stored, config.parse(other))


def test_a_second_round_plans_its_beds_from_the_first_rounds_measured_errors():
    """compare.noise.measured_errors: a report's DEM error over n beds times sqrt(n) is one bed's; with it the target
    asks each drive for t(n - 1)/sqrt(n) x that error <= the difference (creep one-bed error 1 d, target 1 d: 7 beds,
    t(5)/sqrt(6) = 1.05, t(6)/sqrt(7) = 0.925), the law where nothing was measured, never fewer than the run had."""
    from granstokes.compare import noise

    study = config.parse(_study(seeds=[1, 2], target={"creep_length": 1.0, "beds_max": 9}))
    material, _, _ = material_table(CALIBRATION)
    metrics = {"drives": {"runs/p10/stress-mutilde0.5": {"seeds": 4}, "runs/p20/stress-mutilde0.5": {"seeds": 4}},
               "scorecard": [{"drive": "runs/p10/stress-mutilde0.5", "observable": "creep_length", "dem_err": 0.5},
                             {"drive": "runs/p20/stress-mutilde0.5", "observable": "creep_length", "dem_err": 0.1},
                             {"drive": "runs/p20/stress-mutilde0.5", "observable": "t90", "dem_err": None}]}
    measured = noise.measured_errors(metrics)
    assert measured == {"runs/p10/stress-mutilde0.5": {"creep_length": pytest.approx(1.0)},
                        "runs/p20/stress-mutilde0.5": {"creep_length": pytest.approx(0.2)}}
    law = {key: noise.NoiseLaw(key[0], key[1], 1e-3, 1e-3, 0.0, 0.0, 0.0) for key in
           [(o, k) for k, obs in noise.SCORED.items() for o in obs]}  # the law: everything decided by 2 beds
    sp = plan_study(study, material, "test", law, measured)
    assert sp.runs["p10"].plan.config.seeds == (1, 2, 3, 4, 5, 6, 7)  # the measured p10 error asks 7
    assert sp.runs["p20"].plan.config.seeds == (1, 2, 3)  # 0.2 d: t(2)/sqrt(3) x 0.2 = 0.50 <= 1 at 3 beds
    assert plan_study(study, material, "test", law).runs["p10"].plan.config.seeds == (1, 2)


def test_a_part_of_a_study_keeps_the_whole_studys_grains():
    """``stiffness_at``: a study's part at p_w = 10 alone, with the preset's kappa held at the whole study's 20,
    has the whole's k_n (one material); without it, kappa would hold at 10 and k_n halve (Hooke: k_n = kappa p d)."""
    material, _, _ = material_table(CALIBRATION)
    whole = plan_study(config.parse(_study()), material, "test").runs["p10"].plan.config.contact.k_n
    part = plan_study(config.parse(_study(pressures=[10.0], stiffness_at=20.0)), material, "test")
    alone = plan_study(config.parse(_study(pressures=[10.0])), material, "test")
    assert part.runs["p10"].plan.config.contact.k_n == pytest.approx(whole, rel=1e-12)
    assert alone.runs["p10"].plan.config.contact.k_n == pytest.approx(whole / 2, rel=1e-12)
    with pytest.raises(ValueError, match="stiffness_at must be a pressure > 0"):
        config.parse(_study(stiffness_at=-1.0))
