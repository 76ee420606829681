"""An oscillation report's DEM side as small tables (REPORT_DIR/tables): every drive's scene and each bed's records
(the plate's block-averaged series, the method-of-planes mu and the velocity profiles, compare.oscillation.dem_record),
so that ``granstokes compare --tables`` predicts and renders again without the run folders."""
from __future__ import annotations

import json
from pathlib import Path

import pandas as pd

from .oscillation import DriveSpec, Record
from .tables import write_csv

DRIVES_JSON = "oscillating_drives.json"
#: the tables keep nine digits: a report regenerated from them equals the report from the run folders to its digits
TABLE_FLOAT = "%.9g"


def _stem(drive: DriveSpec) -> str:
    return str(drive.label).replace("/", "__")


def write(dem, folder: Path) -> None:
    """``dem``: (DriveSpec, [Record per bed]) pairs, as compare.oscillation.dem_side gives them."""
    folder.mkdir(parents=True, exist_ok=True)
    drives = []
    for drive, records in dem:
        record = {**drive.as_record(), "beds": len(records), "intervals": [r.interval for r in records]}
        drives.append(record)
        for k, r in enumerate(records):
            for name, table in (("plate", r.plate), ("profiles", r.profiles), ("velocity", r.velocity)):
                write_csv(table, folder / f"{_stem(drive)}__bed{k}_{name}.csv.gz", TABLE_FLOAT)
    (folder / DRIVES_JSON).write_text(json.dumps(drives, indent=1))


def read(folder: Path) -> list[tuple[DriveSpec, list[Record]]]:
    """The pairs ``write`` stored."""
    out = []
    for d in json.loads((folder / DRIVES_JSON).read_text()):
        drive = DriveSpec.from_record(d)
        records = [Record(pd.read_csv(folder / f"{_stem(drive)}__bed{k}_plate.csv.gz"),
                          pd.read_csv(folder / f"{_stem(drive)}__bed{k}_profiles.csv.gz"),
                          pd.read_csv(folder / f"{_stem(drive)}__bed{k}_velocity.csv.gz"), d["intervals"][k])
                   for k in range(d["beds"])]
        out.append((drive, records))
    return out
