"""DataLogger: ring buffer of snapshots and CSV export."""

import csv
import io

import numpy as np

from app.service.data_logger import DataLogger, csv_header
from tests.controller.test_chain_and_loop import make_loop


def test_logger_keeps_only_the_newest_snapshots_and_exports_csv(tmp_path):
    logger = DataLogger(max_length=50)
    loop, _, _ = make_loop(on_snapshot=logger.record)
    loop.run_for(0.5)  # 100 ticks
    assert len(logger) == 50
    text = logger.to_csv(tmp_path / "log.csv")
    rows = list(csv.reader(io.StringIO(text)))
    assert rows[0] == csv_header()
    assert len(rows) == 51
    times = np.array([float(r[0]) for r in rows[1:]])
    assert np.all(np.diff(times) > 0)
    assert times[-1] == np.float64(0.5)
    assert (tmp_path / "log.csv").read_text() == text
