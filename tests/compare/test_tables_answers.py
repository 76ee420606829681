"""The report's tables on disk: a gzip table written again from the same data, later and elsewhere, is the same
bytes (no timestamp: a regenerated report changes only where its numbers do), and it reads back to CSV_FLOAT's six
significant digits."""
import numpy as np
import pandas as pd
from granstokes.compare.tables import write_csv


def test_a_table_written_again_is_the_same_bytes_and_keeps_six_digits(tmp_path):
    table = pd.DataFrame({"t": np.arange(6) / 3.0, "u_w": np.exp(np.arange(6) / 7.0)})
    first, second = tmp_path / "first.csv.gz", tmp_path / "again" / "first.csv.gz"
    write_csv(table, first)
    second.parent.mkdir()
    write_csv(table, second)
    header = first.read_bytes()[:8]
    assert header[:2] == b"\x1f\x8b" and header[4:8] == bytes(4)  # gzip, its MTIME field zero
    assert first.read_bytes() == second.read_bytes()
    back = pd.read_csv(first)
    assert np.allclose(back.to_numpy(), table.to_numpy(), rtol=5e-6, atol=0)
    assert not np.allclose(back.to_numpy(), table.to_numpy(), rtol=5e-8, atol=0)  # rounded to six digits, not more
