"""An MCAP file of the log's channels (app.session.channels): rows in, JSON messages with their schemas out,
in zstd chunks; `flush()` ends the chunk in progress and hands everything to the OS, so a crash of the writing
process loses only what came after the last flush."""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import BinaryIO

import numpy as np
from mcap.writer import CompressionType, Writer

from app.session.channels import (
    JSON_SCHEMA,
    ROW_TOPICS,
    SESSION_SCHEMAS,
    TF_TOPIC,
    dumps,
    row_payloads,
    row_topic_schemas,
    schema_name,
    tf_payload,
)

PROFILE = ""  # no ROS profile: JSON messages with JSON schemas
LIBRARY = "hrp2-console"


def time_ns(seconds: float) -> int:
    return int(round(float(seconds) * 1e9))


class McapLog:
    """Writes one MCAP file. `session` adds the session's own channels (inputs, parameter changes, behaviour
    runs, the simulator digest) to the row's."""

    def __init__(self, out: str | Path | BinaryIO, metadata_name: str, metadata: Mapping[str, object],
                 session: bool = False) -> None:
        self._file = open(out, "wb") if isinstance(out, (str, Path)) else None  # noqa: SIM115 - closed in finish
        self._writer = Writer(self._file if self._file is not None else out, compression=CompressionType.ZSTD,
                              chunk_size=1 << 20)
        self._writer.start(profile=PROFILE, library=LIBRARY)
        self._writer.add_metadata(metadata_name, {k: json.dumps(v) for k, v in metadata.items()})
        schemas = {**row_topic_schemas(), **(SESSION_SCHEMAS if session else {})}
        self._channels: dict[str, int] = {}
        for topic, schema in schemas.items():
            sid = self._writer.register_schema(schema_name(topic), JSON_SCHEMA, json.dumps(schema).encode())
            self._channels[topic] = self._writer.register_channel(topic, "json", sid)
        self._previous: np.ndarray | None = None
        self._sequence = 0
        self.rows = 0

    @property
    def topics(self) -> tuple[str, ...]:
        return tuple(self._channels)

    def write(self, topic: str, log_time_ns: int, message: Mapping) -> None:
        self.write_json(topic, log_time_ns, dumps(message))

    def write_json(self, topic: str, log_time_ns: int, data: bytes) -> None:
        self._sequence += 1
        self._writer.add_message(self._channels[topic], log_time=log_time_ns, publish_time=log_time_ns,
                                 data=data, sequence=self._sequence)

    def write_row(self, tick: int, log_time_ns: int, row: np.ndarray) -> None:
        """One tick: every tick topic, the on-change ones when they changed, and BODY's transform."""
        for topic, data in row_payloads(tick, row, self._previous):
            self.write_json(topic, log_time_ns, data)
        self.write_json(TF_TOPIC, log_time_ns, tf_payload(row, log_time_ns))
        self._previous = row.copy()
        self.rows += 1

    def flush(self) -> None:
        """End the chunk in progress and write everything to the OS (not fsync: a process crash loses
        nothing flushed; a power cut may)."""
        self._writer.flush()

    def finish(self) -> None:
        """The summary (indexes, statistics) and the footer; closes a file this object opened."""
        self._writer.finish()
        if self._file is not None:
            self._file.close()


assert set(ROW_TOPICS) <= set(row_topic_schemas())


def rows_to_mcap(rows: np.ndarray, out: str | Path | BinaryIO, ticks, metadata: Mapping[str, object]) -> int:
    """A log export: `rows` (n, ROW_LENGTH) with their tick numbers, stamped with their control time."""
    from app.service.log_row import COLUMNS
    from app.session.channels import LOG_METADATA

    log = McapLog(out, LOG_METADATA, {"columns": list(COLUMNS), **metadata})
    for tick, row in zip(ticks, rows, strict=True):
        log.write_row(int(tick), time_ns(row[0]), row)
    log.finish()
    return len(rows)
