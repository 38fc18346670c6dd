"""The journal of control requests: each POST / PUT / DELETE under /api/ that reached the API is in the state
document's `commands` with who sent it, what, and the answer; reads are not; a stream is one counted entry."""

from __future__ import annotations

import json

import pytest

from app.console.command_journal import CommandJournal

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


def _commands(client) -> list[dict]:
    return client.get("/api/state").json()["commands"]


def test_a_script_command_appears_with_its_client_body_and_answer(client):
    sent = {"angles_deg": {"RARM_JOINT0": -10.0}, "time": 1.0}
    r = client.post("/api/sequence/joint-angles", json=sent, headers={"X-Client-Id": "script-a"})
    assert r.status_code == 200, r.text
    entry = _commands(client)[-1]
    assert entry["client"] == "script-a" and entry["request"] == "POST /api/sequence/joint-angles"
    assert json.loads(entry["body"]) == sent
    assert entry["status"] == 200 and entry["answer"] == r.json()["message"] and entry["count"] == 1


def test_reads_are_not_journaled_and_a_client_without_an_id_is_named_by_its_address(client):
    client.get("/api/params")
    assert _commands(client) == []
    client.post("/api/motion/stop")
    assert [e["client"] for e in _commands(client)] == ["anonymous@testclient"]


def test_a_refused_command_is_journaled_with_its_status_and_detail(client):
    r = client.post("/api/sequence/joint-angles", json={"angles_deg": {"RARM_JOINT0": 10}, "time": -1},
                    headers={"X-Client-Id": "script-b"})
    assert r.status_code == 422
    entry = _commands(client)[-1]
    assert entry["status"] == 422 and entry["answer"] == r.json()["detail"][:160] and entry["client"] == "script-b"


def test_a_stream_of_setpoints_is_one_entry_counted_and_another_client_starts_a_new_one(client):
    body = {"point": "rhand", "linear": [0.01, 0, 0], "angular": [0, 0, 0]}
    for _ in range(3):
        assert client.put("/api/operator/velocity", json=body, headers={"X-Client-Id": "stick"}).status_code == 200
    client.put("/api/operator/velocity", json=body, headers={"X-Client-Id": "other"})
    entries = _commands(client)
    assert [(e["client"], e["count"]) for e in entries] == [("stick", 3), ("other", 1)]
    assert [e["seq"] for e in entries] == [1, 2]


def test_the_journal_keeps_its_last_entries_and_cuts_long_bodies():
    journal = CommandJournal(length=3, coalesce_s=0.0)
    for k in range(5):
        journal.record("c", f"POST /api/x/{k}", json.dumps({"v": "y" * 500}).encode(), 200, b'{"message": "ok"}')
    entries = journal.entries()
    assert [e.seq for e in entries] == [3, 4, 5] and all(len(e.body) == 160 for e in entries)
    assert [d["seq"] for d in json.loads(journal.encoded())] == [3, 4, 5]
    assert entries[-1].answer == "ok"
