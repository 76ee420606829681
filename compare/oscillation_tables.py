"""An oscillation report's DEM side as small tables (REPORT_DIR/tables): every drive's scene and each bed's records
(the plate's block-averaged series, the method-of-planes mu and the velocity profiles, compare.oscillation.dem_record),
so that ``granstokes compare --tables`` predicts and renders again without the run folders."""
from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

import pandas as pd
from granstokes.continuum.load import Load

from .oscillation import OscillatingDrive, Record

DRIVES_JSON = "oscillating_drives.json"
#: the tables keep nine digits: a report regenerated from them equals the report from the run folders to its digits
TABLE_FLOAT = "%.9g"


def _stem(drive: OscillatingDrive) -> str:
    return str(drive.label).replace("/", "__")


def write(dem, folder: Path) -> None:
    """``dem``: (OscillatingDrive, [Record per bed]) pairs, as compare.oscillation.dem_side gives them."""
    folder.mkdir(parents=True, exist_ok=True)
    drives = []
    for drive, records in dem:
        record = {**asdict(drive), "run": str(drive.run), "load": drive.load.as_record(), "p_w": drive.load.p_w,
                  "folders": len(records), "intervals": [r.interval for r in records]}
        drives.append(record)
        for k, r in enumerate(records):
            r.plate.to_csv(folder / f"{_stem(drive)}__bed{k}_plate.csv.gz", index=False, float_format=TABLE_FLOAT)
            r.profiles.to_csv(folder / f"{_stem(drive)}__bed{k}_profiles.csv.gz", index=False,
                              float_format=TABLE_FLOAT)
            r.velocity.to_csv(folder / f"{_stem(drive)}__bed{k}_velocity.csv.gz", index=False,
                              float_format=TABLE_FLOAT)
    (folder / DRIVES_JSON).write_text(json.dumps(drives, indent=1))


def read(folder: Path) -> list[tuple[OscillatingDrive, list[Record]]]:
    """The pairs ``write`` stored."""
    out = []
    for d in json.loads((folder / DRIVES_JSON).read_text()):
        drive = OscillatingDrive(Path(d["run"]), d["name"], Load.from_record(d["load"], d["p_w"]), d["depth"],
                                 d["plate_mass"], d["surface_offset"], d["t_s"], d["duration"], ())
        records = [Record(pd.read_csv(folder / f"{_stem(drive)}__bed{k}_plate.csv.gz"),
                          pd.read_csv(folder / f"{_stem(drive)}__bed{k}_profiles.csv.gz"),
                          pd.read_csv(folder / f"{_stem(drive)}__bed{k}_velocity.csv.gz"), d["intervals"][k])
                   for k in range(d["folders"])]
        out.append((drive, records))
    return out
