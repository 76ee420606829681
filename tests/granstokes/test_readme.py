"""README's commands run as written: every ``granstokes`` line of its shell blocks, in a fresh folder, with the
environment's command on the PATH as README's set-up says (DEM work as ``--dry-run``: the plan, its estimate)."""
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
#: subcommands that do DEM work: README's lines of them run here as their dry run
DRY = (("dem", "run"), ("dem", "calibrate"), ("study",))
#: subcommands whose README lines need a finished DEM run folder: their options are checked by --help only
NEEDS_A_RUN = (("compare",),)


def blocks() -> list[tuple[str, str]]:
    """README's fenced blocks as (language, text)."""
    found, language, body = [], None, []
    for line in (ROOT / "README.md").read_text().splitlines():
        if line.startswith("```"):
            if language is None:
                language, body = line[3:].strip(), []
            else:
                found.append((language, "\n".join(body)))
                language = None
        elif language is not None:
            body.append(line)
    return found


def shell_lines() -> list[str]:
    """The command lines of README's shell blocks (fences without a language, or sh), comments cut."""
    lines = [line.split(" #")[0].strip() for language, block in blocks() if language in ("", "sh", "bash")
             for line in block.splitlines()]
    return [line for line in lines if line and not line.startswith("#")]


def subcommand(line: str) -> tuple[str, ...]:
    words = shlex.split(line)
    return tuple(words[1:3]) if words[1] == "dem" else (words[1],)


def test_readme_says_how_the_command_is_reached():
    lines = shell_lines()
    first = next(k for k, line in enumerate(lines) if line.startswith("granstokes "))
    assert any(line == "source .venv/bin/activate" for line in lines[:first]), lines[:first]
    assert {subcommand(line) for line in lines if line.startswith("granstokes ")} >= {("dem", "calibrate"),
                                                                                     ("dem", "run"), ("study",)}


@pytest.mark.slow
def test_every_readme_command_runs_as_written(tmp_path):
    """In a fresh folder with README's activation (the command from the environment's bin on the PATH), each
    line exits 0; DEM lines as their dry run print the plan's total; the step-by-step's calibration is the
    committed one of the quick grains (its dry run writes none)."""
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    ran = []
    for line in shell_lines():
        if line.startswith(("make ", "source ")):
            continue
        assert line.startswith("granstokes "), line
        calibration = tmp_path / "cal" / "calibration.json"
        if "cal/calibration.json" in line and not calibration.exists():  # what the calibration's line writes
            calibration.parent.mkdir(exist_ok=True)
            calibration.write_bytes((ROOT / "results/quick-calibration/calibration.json").read_bytes())
        command = line
        if subcommand(line) in DRY and "--dry-run" not in line:
            command = f"{line} --dry-run"
        elif subcommand(line) in NEEDS_A_RUN:
            command = f"granstokes {' '.join(subcommand(line))} --help"
        done = subprocess.run(["bash", "-c", command], cwd=tmp_path, env=env, capture_output=True, text=True,
                              timeout=300)
        assert done.returncode == 0, (command, done.stderr[-2000:])
        if subcommand(line) in DRY:
            assert re.search(r"total: about [\d.]+ (s|min|h) on this machine .* of disk", done.stderr), done.stderr
        ran.append(command)
    assert len(ran) >= 5
    assert {p.name for p in tmp_path.iterdir()} <= {"cal", "my.toml"}  # dry runs write nothing


def test_readme_python_runs_as_written():
    """README's Python example (the paper's glass beads under an imposed stress) prints u~_w at its three times
    and their error estimates, rising with time."""
    code = next(block for language, block in blocks() if language == "python" and "solve_stress" in block)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    u_w, err = (re.findall(r"[-+]?\d*\.\d+(?:e[-+]?\d+)?", part) for part in done.stdout.split("] ["))
    u_w, err = [float(x) for x in u_w], [float(x) for x in err]
    assert len(u_w) == len(err) == 3 and 0 < u_w[0] < u_w[1] < u_w[2] and max(err) < 1e-4
