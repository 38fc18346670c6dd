"""A tiny study (shortened wall pushes) on the local process pool and on a Ray instance started here gives the
same results, run for run; a second invocation finds every run stored and runs none. A cluster address nothing
answers at fails at once, naming it."""

import re
import shutil
import socket
import tempfile

import pytest
import ray

from app.lab.study.pool import PoolBackend
from app.lab.study.ray_backend import RayBackend, RayUnavailable
from app.lab.study.space import Case, EstopParams
from app.lab.study.store import RunStore
from app.lab.study.study import StudyConfig, run_study, tuning_specs, validation_specs
from tests.app.study.fakes import Counting

#: Two parameter sets, one disturbed forward push (wall 2 cm nearer, pushed at 0.1 m/s), one held-out push, each
#: ended after 5 s: 6 runs of 7.5 simulated seconds.
TINY = StudyConfig(
    params=[EstopParams(0.04, 1.0, 0.5), EstopParams(0.06, 0.5, 0.25)],
    cases=[Case.make("wall-push-forward", None, {"wall_gap_m": -0.02, "push_speed_m_s": 0.1})],
    validation_cases=[Case.make("wall-push-forward", None, {"wall_gap_m": 0.0, "push_speed_m_s": 0.12})],
    duration_s=5.0, bootstrap_resamples=20)


def results(store: RunStore) -> dict:
    return {key: record["result"] for key, record in store.records.items()}


def test_the_pool_and_ray_give_the_same_study_and_a_rerun_skips_every_stored_run(tmp_path):
    pool_store = RunStore(tmp_path / "pool" / "runs.jsonl")
    on_pool = run_study(TINY, PoolBackend(2), pool_store)
    recommended = on_pool.recommendation.summary.params
    expected_keys = {s.key() for s in tuning_specs(TINY) + validation_specs(TINY, recommended)}
    assert set(pool_store.records) == expected_keys and len(expected_keys) == 6
    assert all(r["verdict"] != "error" for r in results(pool_store).values())
    flags = {r["flag_time_s"] for r in results(pool_store).values()}
    assert None not in flags and len(flags) >= 2  # every push raised the flag; the disturbances made a difference

    temp_dir = tempfile.mkdtemp(prefix="ray", dir="/tmp")  # short: Ray's socket paths must stay under 108 bytes
    try:
        ray.init(address="local", num_cpus=2, include_dashboard=False, _node_ip_address="127.0.0.1",
                 _temp_dir=temp_dir, object_store_memory=100 * 1024**2, log_to_driver=False)
        ray_store = RunStore(tmp_path / "ray" / "runs.jsonl")
        on_ray = run_study(TINY, RayBackend(), ray_store)
    finally:
        ray.shutdown()
        shutil.rmtree(temp_dir, ignore_errors=True)
    assert results(ray_store) == results(pool_store)  # bit for bit: every float of every run
    assert on_ray.recommendation.summary == on_pool.recommendation.summary
    assert on_ray.validation == on_pool.validation
    assert [p.runs for p in on_ray.phases] == [4, 2]

    counting = Counting()
    again = run_study(TINY, counting, RunStore(tmp_path / "pool" / "runs.jsonl"))  # a restart: all stored
    assert counting.asked == 0 and [p.runs for p in again.phases] == [0, 0]
    assert [p.skipped for p in again.phases] == [4, 2]
    assert again.recommendation.summary == on_pool.recommendation.summary


def _closed_port() -> int:
    """A loopback port nothing listens on (bound, then closed)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize("address", ["127.0.0.1:{port}", "ray://127.0.0.1:{port}"])
def test_ray_at_an_address_nothing_answers_fails_naming_it(address):
    address = address.format(port=_closed_port())
    with pytest.raises(RayUnavailable, match=re.escape(repr(address)) + ".*nothing answers"):
        list(RayBackend(address).run([{"anything": 1}]))
    assert not ray.is_initialized()


@pytest.mark.parametrize("address", ["nohost", "host:", ":6379", "host:port", "host:0", "host:65536"])
def test_a_malformed_ray_address_is_refused_naming_the_forms_allowed(address):
    with pytest.raises(RayUnavailable, match="expected HOST:PORT, ray://HOST:PORT, 'auto' or 'local'"):
        list(RayBackend(address).run([{"anything": 1}]))


def test_a_host_name_no_resolver_can_encode_fails_as_unreachable_not_with_a_traceback():
    address = "a" * 70 + ":6379"  # a DNS label over 63 characters: IDNA refuses to encode it
    with pytest.raises(RayUnavailable, match="nothing answers"):
        list(RayBackend(address).run([{"anything": 1}]))


def test_the_study_command_line_exits_2_when_the_cluster_does_not_answer(tmp_path, capsys):
    from app.lab.study.estop_walking_cli import main

    address = f"127.0.0.1:{_closed_port()}"
    code = main(["--ray", address, "--walks", "side", "--phases", "1", "--holds", "0.3", "--out", str(tmp_path)])
    assert code == 2
    assert f"error: --ray {address!r}: nothing answers" in capsys.readouterr().err
