"""TOML configs as text: entries overridden by dotted keys (``--set load.p_w=20``, as LAMMPS's ``-var``),
written back with tomli-w so that a run folder's config file is the config that ran."""
from __future__ import annotations

import tomllib

import tomli_w

from .validate import require


def parse_assignment(text: str) -> tuple[str, object]:
    """``key=value`` with a dotted key and a TOML value (a bare word is a string): ("load.p_w", 20.0)."""
    key, sep, value = text.partition("=")
    key = key.strip()
    require(sep == "=" and key != "" and all(part.strip() for part in key.split(".")), "--set",
            "KEY=VALUE with a dotted key, e.g. load.p_w=20 or seeds=[1,2,3]", text)
    try:
        parsed = tomllib.loads(f"v = {value.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        parsed = value.strip()
    return key, parsed


def assign(doc: dict, key: str, value) -> None:
    """Set the dotted ``key`` of ``doc`` in place; a numeric part indexes an array of tables (drive.0.u_w)."""
    *path, last = key.split(".")
    node = doc
    for part in path:
        if isinstance(node, list):
            require(part.isdigit() and int(part) < len(node), f"--set {key}",
                    f"an index below {len(node)} at '{part}'", part)
            node = node[int(part)]
        else:
            node = node.setdefault(part, {})
        require(isinstance(node, (dict, list)), f"--set {key}", f"a table at '{part}'", node)
    if isinstance(node, list):
        require(last.isdigit() and int(last) < len(node), f"--set {key}", f"an index below {len(node)}", last)
        node[int(last)] = value
    else:
        node[last] = value


def with_entries(text: str, entries, header: str = "") -> str:
    """``text`` with each (dotted key, value) of ``entries`` set (``None`` removes the key), as TOML, led by
    ``header`` comment lines; the text itself when there is nothing to set."""
    entries = list(entries)
    if not entries:
        return text
    doc = tomllib.loads(text)
    for key, value in entries:
        if value is None:
            *path, last = key.split(".")
            node = doc
            for part in path:
                node = node.get(part, {})
            node.pop(last, None)
        else:
            assign(doc, key, value)
    lead = "".join(f"# {line}\n" for line in header.splitlines() if line)
    return lead + tomli_w.dumps(doc)
