"""Rerun recordings (``dream.run(..., rerun=...)`` and :func:`dream.recording.from_log`), read back
through Rerun's own reader: the entities, the steps, and the robots where the run had them."""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

import dream
from dream import Faults
from dream.recording import from_log

rerun = pytest.importorskip("rerun", reason="Rerun recordings need rerun-sdk (the rerun extra, Python >= 3.11)")
from rerun.chunk import RrdReader  # noqa: E402


def entities(path):
    """The entity paths of the recording at ``path``, and whether each holds static data only."""
    found: dict[str, bool] = {}
    for chunk in RrdReader(path).stream().to_chunks():
        found[chunk.entity_path] = found.get(chunk.entity_path, True) and chunk.is_static
    return found


def robots(path, entity="/robots", component="Points2D:positions"):
    """``{step: (k, 2) positions}`` of ``entity`` in the recording at ``path``."""
    found = {}
    for chunk in RrdReader(path).stream().to_chunks():
        if chunk.entity_path != entity or chunk.is_static:
            continue
        batch = chunk.to_record_batch()
        steps, rows = batch.column("step").to_pylist(), batch.column(component).to_pylist()
        for step, row in zip(steps, rows):
            found[step] = np.array(row, dtype=np.float64).reshape(-1, 2)
    return found


def test_run_recording_has_the_robots_of_every_logged_step(tmp_path):
    path = tmp_path / "run.rrd"
    result = dream.run("hrvo-circle", n=7, seed=2, backend="fast", steps=12, rerun=path, log_every=4, trace=True)
    found = entities(path)
    for entity in ("/robots", "/robots/heading", "/robots/velocity", "/goals"):
        assert found[entity] is False, entity
    assert found["/arena"] is True
    assert {"/measures/messages/sent", "/measures/messages/heard", "/measures/circles_completed"} <= set(found)
    positions = robots(path)
    assert sorted(positions) == [0, 4, 8, 12]
    for step, xy in positions.items():  # float32 in the recording
        assert np.allclose(xy, result.trace[step][:2].T, atol=1e-6)
    headings = robots(path, "/robots/heading", "Arrows2D:vectors")
    theta = result.trace[12][2]
    assert np.allclose(np.arctan2(headings[12][:, 1], headings[12][:, 0]), theta, atol=1e-5)


def test_recording_marks_the_faulty_robots(tmp_path):
    path = tmp_path / "run.rrd"
    result = dream.run("hrvo-circle", n=6, backend="fast", steps=5, rerun=path, faults=Faults(crash=0.5, crash_at=1))
    crashed = sorted(e["robot"] for e in result.faults["events"] if e["kind"] == "crash")
    classes = {}
    for chunk in RrdReader(path).stream().to_chunks():
        if chunk.entity_path == "/robots" and not chunk.is_static:
            batch = chunk.to_record_batch()
            classes.update(zip(batch.column("step").to_pylist(), batch.column("Points2D:class_ids").to_pylist()))
    assert np.flatnonzero(np.array(classes[5]) == 3).tolist() == crashed  # class 3: crashed (frames.STATUSES)
    assert not any(classes[0])


def test_log_becomes_a_recording(tmp_path):
    log, path = tmp_path / "run.parquet", tmp_path / "view.rrd"
    dream.run("hrvo-circle", n=5, backend="fast", steps=9, log=log, log_every=3, faults=Faults(loss=0.3))
    assert from_log(log, path) == 4
    table = pq.read_table(log)
    positions = robots(path)
    assert sorted(positions) == [0, 3, 6, 9]
    x, y, step = (table.column(name).to_numpy() for name in ("x", "y", "step"))
    for k, xy in positions.items():
        assert np.allclose(xy, np.column_stack((x, y))[step == k], atol=1e-6)
    assert {"/measures/messages/lost", "/measures/faults/crashed", "/robots/velocity"} <= set(entities(path))


def test_recording_refuses_a_bad_target_and_a_failed_run_leaves_none(tmp_path):
    with pytest.raises(ValueError, match="ending in .rrd"):
        dream.run("hrvo-circle", n=3, backend="fast", steps=2, rerun=tmp_path / "run.mp4")
    pq.write_table(pa.table({"a": [1, 2]}), tmp_path / "other.parquet")
    with pytest.raises(ValueError, match="not a DREAM trajectory log"):
        from_log(tmp_path / "other.parquet", tmp_path / "other.rrd")
    path = tmp_path / "run.rrd"
    with pytest.raises(ValueError, match="robot_measures"):
        dream.run(Broken, n=3, backend="fast", steps=4, rerun=path)
    assert not path.exists() and not list(tmp_path.glob(".dream-*"))


class Broken(dream.Experiment):
    name = "broken"

    def build(self, n):
        pass

    def robot_measures(self):
        return {"bad": np.zeros(1)}


def test_served_recording_listens_on_localhost_only(capfd):
    import urllib.request

    import psutil

    from dream import recording

    dream.run("hrvo-circle", n=4, backend="fast", steps=3, rerun="serve")
    try:
        (server,) = recording._served
        address = capfd.readouterr().err.split("Rerun web viewer: ")[1].split()[0]
        with urllib.request.urlopen(address, timeout=30) as page:  # the web viewer's page
            assert page.status == 200 and b"<html" in page.read(2000).lower()
        listening = [c.laddr for c in psutil.Process(server.pid).net_connections() if c.status == "LISTEN"]
        assert len(listening) == 2 and {addr.ip for addr in listening} == {"127.0.0.1"}
    finally:
        recording._stop_served()
    assert not recording._served and server.poll() is not None


def test_recording_of_a_swarm_robot_shows_what_the_focus_robot_read_and_heard(tmp_path):
    import importlib.util
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    spec = importlib.util.spec_from_file_location("rendezvous_example", root / "examples" / "rendezvous.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    path = tmp_path / "run.rrd"
    dream.run(module.Rendezvous, n=12, backend="fast", steps=30, swarm=True, rerun=path)
    found: dict[str, dict[int, object]] = {}
    for chunk in RrdReader(path).stream().to_chunks():
        if chunk.entity_path.startswith("/focus/"):
            batch = chunk.to_record_batch()
            column = next(name for name in batch.schema.names if name.endswith((":strips", ":text", ":positions")))
            steps = batch.column("step").to_pylist()
            found.setdefault(chunk.entity_path, {}).update(zip(steps, batch.column(column).to_pylist()))
    assert set(found) == {"/focus/heard", "/focus/seen", "/focus/inbox"}
    last = {entity: values[30] for entity, values in found.items()}
    heard, text = len(last["/focus/heard"]), last["/focus/inbox"][0]
    assert heard > 0 and f"heard {heard} messages" in text
    assert len(text.splitlines()) == 4 + heard  # a line per message
    assert "| sender | x | y |" in text  # with the fields of each (rendezvous's robots send x and y)
    assert f"saw {len(last['/focus/seen'])} robots" in text
