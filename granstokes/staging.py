"""Writing an output folder all at once: the work goes into a hidden sibling folder that replaces the
target only when it is complete, so a failed or interrupted command leaves nothing behind (and an
earlier report in the target stays as it was)."""
from __future__ import annotations

import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def staged(target):
    """Yield a fresh folder beside ``target``; on success it becomes ``target`` (replacing it)."""
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix=f".{target.name}.", dir=target.parent))
    try:
        yield work
    except BaseException:
        shutil.rmtree(work, ignore_errors=True)
        raise
    if target.exists():
        shutil.rmtree(target)
    work.rename(target)
