"""The preparation's settings as the config validates them and the prepare script carries them; a drive's table and
its run.json record."""
import dataclasses
import json
import re
import tomllib

import pytest
from granstokes.continuum.load import Load
from granstokes.dem import config, scene
from granstokes.dem.contact import grain_mass
from granstokes.dem.sizing import plan, sized_drives

from granstokes.cli import main


def _script(name="smoke", **prepare):
    """A preset's plan and seed 1's prepare script, with ``prepare`` entries set."""
    doc = tomllib.loads(config.preset_text(name))
    p = plan(config.from_dict({**doc, "prepare": {**doc.get("prepare", {}), **prepare}}))
    return p, scene.prepare_script(p, 1)


@pytest.mark.parametrize("name", ["smoke", "spheres"])
def test_settling_ends_on_its_own_threshold_once_the_pile_has_landed(name):
    p, text = _script(name, settle_ke_per_grain=0.02)
    settle = text.split('print "PHASE settle"')[1].split("label settled")[0]
    assert re.search(r'if "\$\{ke_grain\} < 0\.02 && \$\{ke_grain\} < \$\{ke_previous\}" then "jump SELF settled"',
                     settle)
    assert "variable ke_previous equal 0.0" in settle and "variable ke_previous equal ${ke_grain}" in settle
    relax = text.split('print "PHASE relax"')[1]
    assert f'if "${{ke_grain}} < {p.config.prepare.ke_per_grain:.10g}" then "jump SELF relaxed"' in relax


@pytest.mark.parametrize("name", ["smoke", "spheres"])
def test_relax_counts_the_plate_and_the_plate_approaches_at_its_set_speed(name):
    p, text = _script(name)
    load = text.split("# --- load:")[1].split('print "PHASE relax"')[0]
    mass = grain_mass(1.0, p.dimension)
    assert re.search(rf"variable ke_grain equal \(c_ke_bed\+c_ke_plate\)/count\(bed\)/{mass:.10g}\n", load)
    assert "compute ke_plate plate ke" in load
    # the drag on each plate grain balances its share of p_w A at the approach speed (terminal speed)
    n = scene.plate_grains(p)
    gamma = float(re.search(r"fix plate_drag plate viscous (\S+)", load).group(1))
    push = -float(re.search(r"fix load plate addforce 0\.0 (\S+) 0\.0", load).group(1))
    assert push * n == pytest.approx(p.config.p_w * p.area)
    assert push / gamma == pytest.approx(scene.PLATE_APPROACH_SPEED) and scene.PLATE_APPROACH_SPEED == 4.0
    assert f"velocity plate set 0.0 {-scene.PLATE_APPROACH_SPEED:g} 0.0 units box" in text


def test_default_settling_threshold():
    assert config.Prepare().settle_ke_per_grain == 0.03 and config.Prepare().ke_per_grain == 1e-5
    assert config.Prepare(ke_per_grain=0.1, settle_ke_per_grain=0.1).settle_ke_per_grain == 0.1


@pytest.mark.parametrize("value, valid", [("0.5", "in [ke_per_grain = 0.0001, 0.1]"),
                                          ("1e-6", "in [ke_per_grain = 0.0001, 0.1]"),
                                          ("-0.01", "a finite number > 0"), ("nan", "a finite number > 0"),
                                          ('"fast"', "a finite number > 0")])
def test_a_bad_settling_threshold_is_one_line_and_exit_2(value, valid, tmp_path, monkeypatch, capsys):
    """Outside [ke_per_grain, SETTLE_KE_MAX] (smoke: ke_per_grain = 1e-4): exit 2, one line naming it."""
    monkeypatch.chdir(tmp_path)
    code = main(["dem", "run", "--preset", "smoke", "--set", f"prepare.settle_ke_per_grain={value}", "--out", "r",
                 "--dry-run"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert f"prepare.settle_ke_per_grain must be {valid}" in err, err
    assert not (tmp_path / "r").exists()


def test_a_drive_is_its_table_and_its_record_reads_back_as_sized():
    """A drive's [[drive]] table gives it back; run.json's records of a scene's drives (DriveSizing.as_record) read
    back through sized_drives as sized: name, scales, duration, steps, and the load the record states."""
    for name in config.PRESETS:
        cfg = config.preset(name)[0]
        wave = dataclasses.replace(cfg.drives[0], name="wave", duration=None, omega_ts=2.0, cycles=3.0)
        cfg = dataclasses.replace(cfg, drives=(*cfg.drives, wave))
        assert tuple(config.Drive(**d.table()) for d in cfg.drives) == cfg.drives
        p = plan(cfg)
        meta = json.loads(json.dumps({"config": cfg.as_dict(), "sizing": p.as_dict()}))
        for record, sized, back in zip(meta["sizing"]["drives"], p.drives, sized_drives(meta), strict=True):
            assert (back.drive.name, back.scales, back.duration, back.steps) == (sized.drive.name, sized.scales,
                                                                                 sized.duration, sized.steps)
            assert back.load == Load.from_record(record, cfg.p_w) and back.load.omega == sized.load.omega
            assert back.load.amplitude == pytest.approx(sized.load.amplitude, rel=1e-15)
