"""DataLogger: a ring buffer of the ticks' rows (the snapshot and the simulator's truth beside it), read
by another process through shared storage, and the CSV export."""

import csv
import io

import numpy as np
import pytest

from app.service.data_logger import DataLogger, csv_header
from app.service.host import RobotHost

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


def test_logger_keeps_only_the_newest_rows_and_exports_csv(tmp_path):
    logger = DataLogger(max_length=50)
    host = RobotHost(speed=None, logger=logger)
    host.loop.run_for(0.5)  # 100 ticks
    assert len(logger) == 50
    text = logger.to_csv(tmp_path / "log.csv")
    rows = list(csv.reader(io.StringIO(text)))
    assert rows[0] == csv_header()
    assert len(rows) == 51
    times = np.array([float(r[0]) for r in rows[1:]])
    assert np.all(np.diff(times) > 0)
    assert times[-1] == np.float64(0.5)
    assert (tmp_path / "log.csv").read_text() == text
    base_z = float(rows[-1][csv_header().index("base/pos_sim_m/z")])
    assert 0.6 < base_z < 0.7  # the simulator's BODY height, logged beside the controller's data


def test_a_reader_of_the_shared_storage_sees_what_the_writer_logged():
    storage = np.zeros(DataLogger.storage_shape(20))
    writer = DataLogger(20, storage)
    host = RobotHost(speed=None, logger=writer)
    host.loop.run_for(0.15)  # 30 ticks: the ring wrapped
    reader = DataLogger.reader(storage)
    np.testing.assert_array_equal(reader.rows(), writer.rows())
    assert len(reader) == 20 and np.all(np.diff(reader.rows()[:, 0]) > 0)
