"""`dream sweep` / `dream.sweep`: real Dask clusters (a LocalCluster, and a `dask scheduler` + `dask worker`
pair started here), rows streamed to a resumable CSV, a failing run as an error row, bad input refused up front."""

from __future__ import annotations

import csv
import os
import socket
import subprocess
import sys
import urllib.error
import urllib.request
from pathlib import Path

import distributed
import psutil
import pytest
from PIL import Image

import dream
from dream.cli import main
from dream.sweep import Table, plan

# A tiny experiment: three robots drive forward for a few steps; seed 2's build raises.
DRIFT = """
from dream import Experiment, param


class Drift(Experiment):
    name = "drift"
    default_n = 3
    speed: float = param(0.05, "forward speed (m/s)")

    def build(self, n):
        if self.world.seed == 2:
            raise RuntimeError("seed 2 is cursed")

    def after_step(self, step, poses):
        self.dxu[0] = self.speed

    def done(self, step, poses):
        return step >= 4

    def measures(self):
        return {"mean_x": float(self.sim.poses[0].mean()), "seed": self.world.seed, "swarm": self.swarm}

    has_swarm_mode = True

    def build_swarm(self, n):
        self.build(n)

    def swarm_step(self, step, x):
        return [[self.speed] * self.n, [0.0] * self.n]
"""


@pytest.fixture
def drift(tmp_path: Path) -> str:
    path = tmp_path / "drift.py"
    path.write_text(DRIFT)
    return str(path)


def read(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as file:
        return list(csv.DictReader(file))


def no_cluster(*args, **kwargs):
    raise AssertionError("a cluster was started")


def test_sweep_on_local_cluster_writes_rows_error_rows_resumes_and_plots(drift, tmp_path, monkeypatch, capsys):
    out, png = tmp_path / "runs.csv", tmp_path / "runs.png"
    argv = ["sweep", drift, "-n", "2,3", "--param", "speed=0.05,0.1", "--backend", "fast", "--workers", "2"]
    argv += ["--out", str(out), "--no-progress"]
    assert main([*argv, "--seeds", "0:3", "--plot", str(png)]) == 0
    rows = read(out)
    assert len(rows) == 2 * 2 * 3
    assert {(r["n"], r["params.speed"], r["seed"]) for r in rows} == {
        (n, speed, seed) for n in ("2", "3") for speed in ("0.05", "0.1") for seed in ("0", "1", "2")
    }
    for row in rows:
        assert row["experiment"] == "drift" and row["backend"] == "fast" and row["worker"].startswith("tcp://")
        if row["seed"] == "2":
            assert row["error"] == "RuntimeError: seed 2 is cursed" and row["success"] == ""
        else:
            assert row["error"] == "" and row["success"] == "True" and row["completed_step"] == "4"
            assert row["collisions"] == "0" and row["simulator"] == "fast"
            assert row["measures.seed"] == row["seed"]  # the row's metrics are its own run's
            assert float(row["measures.mean_x"]) != 0.0
    summary = capsys.readouterr().out
    assert "12 runs of drift: 8 succeeded, 4 raised" in summary
    with Image.open(png) as image:
        assert image.format == "PNG" and image.width > 300

    # Again with one more seed: only seed 3 and the failed seed 2 run; done rows stay as they were.
    done_before = {(r["n"], r["params.speed"], r["seed"]): r for r in rows if r["error"] == ""}
    assert main([*argv, "--seeds", "0:4"]) == 0
    rows = read(out)
    assert len(rows) == 2 * 2 * 4
    for row in rows:
        key = (row["n"], row["params.speed"], row["seed"])
        if key in done_before:
            assert row == done_before[key]
    assert sum(1 for r in rows if r["error"]) == 4  # seed 2 failed again, once per combination

    # Nothing left to do but the failed runs: with seeds 0 and 1 no cluster starts at all.
    monkeypatch.setattr(distributed, "LocalCluster", no_cluster)
    assert main([*argv, "--seeds", "0,1"]) == 0
    assert read(out) == rows


def listening() -> set[str]:
    """The addresses on which this process and its children (the cluster's) accept connections."""
    processes = [psutil.Process(), *psutil.Process().children(recursive=True)]
    return {c.laddr.ip for p in processes for c in p.net_connections("tcp") if c.status == psutil.CONN_LISTEN}


@pytest.mark.parametrize("dashboard", [False, True])
def test_local_cluster_listens_on_loopback_with_the_dashboard_off_unless_asked(
    drift, tmp_path, monkeypatch, capsys, dashboard
):
    seen = {}

    class Watched(distributed.LocalCluster):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            port = self.scheduler_info["services"]["dashboard"]  # Dask's HTTP server, with or without a dashboard
            try:
                status = urllib.request.urlopen(f"http://127.0.0.1:{port}/status", timeout=10).status
            except urllib.error.HTTPError as err:
                status = err.code
            seen.update(scheduler=self.scheduler_address, status=status, listening=listening())

    monkeypatch.setattr(distributed, "LocalCluster", Watched)
    argv = ["sweep", drift, "--seeds", "0", "--workers", "1", "--out", str(tmp_path / "x.csv"), "--no-progress"]
    assert main([*argv, *(["--dashboard"] if dashboard else [])]) == 0
    assert seen["scheduler"].startswith("tcp://127.0.0.1:")
    assert seen["listening"] == {"127.0.0.1"}  # scheduler, worker, nanny and their HTTP servers
    assert seen["status"] == (200 if dashboard else 404)
    assert ("dashboard: http://127.0.0.1:" in capsys.readouterr().err) is dashboard


def test_dashboard_with_a_scheduler_is_refused(drift, tmp_path, capsys):
    argv = ["sweep", drift, "--scheduler", "tcp://127.0.0.1:1", "--dashboard", "--out", str(tmp_path / "x.csv")]
    assert main(argv) == 2
    assert "dashboard: serves the local cluster's" in capsys.readouterr().err


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def test_sweep_on_a_dask_scheduler_and_worker(drift, tmp_path):
    address = f"tcp://127.0.0.1:{free_port()}"
    dask = [sys.executable, "-m", "dask"]
    # The workers import this checkout's dream, as the test process does.
    env = {**os.environ, "PYTHONPATH": str(Path(dream.__file__).parents[1])}
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "env": env}
    started = []
    try:
        started.append(subprocess.Popen([*dask, "scheduler", "--host", "127.0.0.1", "--port", address.rsplit(":", 1)[1],
                                         "--no-dashboard"], **quiet))  # fmt: skip
        # Two threads: the runs of one worker process must not share its current world.
        started.append(subprocess.Popen([*dask, "worker", address, "--nthreads", "2", "--nworkers", "1",
                                         "--no-dashboard", "--host", "127.0.0.1"], **quiet))  # fmt: skip
        with distributed.Client(address, timeout="60s") as client:
            client.wait_for_workers(1, timeout=60)
            (worker,) = client.scheduler_info()["workers"]
        out = tmp_path / "remote.csv"
        rows = dream.sweep(drift, seeds=[0, 1, 2], n=2, params={"speed": [0.1]}, scheduler=address, out=out,
                           backend="fast", steps=10, progress=False)  # fmt: skip
        assert [(r["seed"], r["success"], r["worker"]) for r in rows] == [
            (0, True, worker),
            (1, True, worker),
            (2, None, worker),
        ]
        assert rows[2]["error"] == "RuntimeError: seed 2 is cursed"
        assert rows[0]["params.speed"] == 0.1 and rows[0]["step_cap"] == 10 and rows[0]["steps"] == 4
        assert len(read(out)) == 3
        # Read back from the CSV, done rows come as Python values.
        again = dream.sweep(drift, seeds=[0, 1], n=2, params={"speed": [0.1]}, scheduler=address, out=out,
                            backend="fast", steps=10, progress=False)  # fmt: skip
        assert again == rows[:2]
    finally:
        for process in reversed(started):
            process.terminate()
        for process in started:
            try:
                process.wait(timeout=20)
            except subprocess.TimeoutExpired:
                process.kill()


def test_interrupted_sweep_keeps_the_rows_done(drift, tmp_path, monkeypatch):
    """Ctrl-C (KeyboardInterrupt) after the first row: exit 130, that row in the CSV, nothing else."""
    added = Table.add

    def add_then_interrupt(self, row):
        added(self, row)
        raise KeyboardInterrupt

    monkeypatch.setattr(Table, "add", add_then_interrupt)
    out = tmp_path / "cut.csv"
    argv = ["sweep", drift, "--seeds", "0:6", "--backend", "fast", "--workers", "1", "--out", str(out), "--no-progress"]
    assert main(argv) == 130
    assert len(read(out)) == 1


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--param", "gain=1"], "drift has no parameter 'gain' (its parameters: speed)"),
        (["--param", "speed=0.1,fast"], "parameter 'speed' of drift expects a number, got 'fast'"),
        (["--param", "speed"], "--param takes NAME=V1,V2,..., got 'speed'"),
        (["--param", "speed=1", "--param", "speed=2"], "--param speed given twice"),
        (["--workers", "2", "--scheduler", "tcp://127.0.0.1:1"], "workers: sizes the local cluster"),
        (["--backend", "robotarium", "-n", "51"], "n: the Robotarium backend runs at most 50 robots, got 51"),
        (["--fault", "loss=0,2"], "--fault 'loss=2': loss is a probability in [0, 1], got 2.0"),
        (["--fault", "teleport=1"], "unknown fault 'teleport'"),
    ],
)
def test_bad_input_is_one_line_before_any_cluster(drift, tmp_path, monkeypatch, capsys, extra, message):
    monkeypatch.setattr(distributed, "LocalCluster", no_cluster)
    assert main(["sweep", drift, "--out", str(tmp_path / "x.csv"), *extra]) == 2
    err = capsys.readouterr().err
    assert message in err and err.startswith("dream: error:") and err.count("\n") == 1
    assert not (tmp_path / "x.csv").exists()


@pytest.mark.parametrize("seeds", ["5:2", "-1:3", "a:b", "1,x"])
def test_bad_seeds_are_refused_by_the_parser(drift, tmp_path, capsys, seeds):
    with pytest.raises(SystemExit) as exit_:
        main(["sweep", drift, "--seeds", seeds, "--out", str(tmp_path / "x.csv")])
    assert exit_.value.code == 2 and "--seeds" in capsys.readouterr().err


def test_out_that_is_not_a_sweep_table_is_refused(drift, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(distributed, "LocalCluster", no_cluster)
    other = tmp_path / "other.csv"
    other.write_text("a,b\n1,2\n")
    assert main(["sweep", drift, "--out", str(other)]) == 2
    assert "is not a sweep table (no column 'experiment')" in capsys.readouterr().err
    assert other.read_text() == "a,b\n1,2\n"


def written(drift: str, out: Path, seeds: list[int]):
    """A table of drift's runs for ``seeds`` as a sweep writes it (each row added as it comes), no cluster."""
    sweep_plan = plan(drift, seeds=seeds, backend="fast")
    metrics = {"simulator": "fast", "steps": 4, "completed_step": 4, "collisions": 0, "boundary": 0, "actuator": 0}
    with Table(out, sweep_plan) as table:
        for task in sweep_plan.tasks:
            table.add({**task.inputs(), **metrics, "success": True, "wall_time": 0.25, "worker": "tcp://x:1"})
    return sweep_plan


def test_a_second_sweep_on_the_same_out_refuses_in_one_line(drift, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(distributed, "LocalCluster", no_cluster)
    out = tmp_path / "runs.csv"
    sweep_plan = written(drift, out, [0])
    before = out.read_bytes()
    with Table(out, sweep_plan):  # a sweep at work on the file
        assert main(["sweep", drift, "--seeds", "0:3", "--backend", "fast", "--out", str(out), "--no-progress"]) == 2
        err = capsys.readouterr().err
        assert err == f"dream: error: out: {out} is in use by another sweep (it holds runs.csv.lock); let it finish\n"
        with pytest.raises(ValueError, match="in use by another sweep"):
            Table(out, sweep_plan).__enter__()
    assert out.read_bytes() == before
    with Table(out, sweep_plan) as table:  # the first sweep has ended: the lock is free again
        assert len(table.done) == 1


@pytest.mark.parametrize("cut", [2, 5], ids=["line end", "into the last cells"])
def test_a_last_row_cut_short_is_dropped_with_a_warning_and_run_again(drift, tmp_path, cut):
    out = tmp_path / "runs.csv"
    sweep_plan = written(drift, out, [0, 1])
    out.write_bytes(out.read_bytes()[:-cut])  # killed while writing seed 1's row
    with (
        pytest.warns(RuntimeWarning, match=f"out: {out}:3: the last row is cut short"),
        Table(out, sweep_plan) as table,
    ):
        assert list(table.done) == [sweep_plan.tasks[0].key()]
    if cut == 2:  # the sweep runs seed 1 again and writes its row whole
        with pytest.warns(RuntimeWarning, match="cut short"):
            rows = dream.sweep(drift, seeds=[0, 1], backend="fast", workers=1, out=out, progress=False)
        assert [(r["seed"], r["success"], r["worker"] == "tcp://x:1") for r in rows] == [
            (0, True, True),
            (1, True, False),
        ]
        assert len(read(out)) == 2 and out.read_bytes().endswith(b"\r\n")


def bad_line(change: str, header: list[str], fields: list[str]) -> str:
    """Seed 1's row of a drift table made bad by ``change``, as a line of the CSV."""
    row = dict(zip(header, fields))
    if change == "garbage":
        return "garbage\r\n"
    if change == "quote":
        return '"drift"x,' + ",".join(fields[1:]) + "\r\n"
    if change == "extra field":
        return ",".join([*fields, "surprise"]) + "\r\n"
    column, value = change.split("=")
    row[column] = value
    if column == "success":
        row["error"] = ""
    return ",".join(row[c] for c in header) + "\r\n"


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ("garbage", "1 fields, the header has"),
        ("extra field", "fields, the header has"),
        ("quote", "not a CSV row"),
        ("n=ten", "n 'ten' is not a whole number"),
        ("success=maybe", "success 'maybe' is not True or False"),
        ("success=", "neither a result (success) nor an error"),
        ("wall_time=fast", "wall_time 'fast' is not a number"),
        ("seed=", "no seed"),
    ],
)
def test_a_bad_row_stops_the_sweep_before_any_run_naming_file_and_line(
    drift, tmp_path, monkeypatch, capsys, change, message
):
    monkeypatch.setattr(distributed, "LocalCluster", no_cluster)
    out = tmp_path / "runs.csv"
    written(drift, out, [0, 1])
    header, first, second = out.read_text().splitlines()
    out.write_text(f"{header}\r\n{first}\r\n" + bad_line(change, header.split(","), second.split(",")), newline="")
    before = out.read_bytes()
    assert main(["sweep", drift, "--seeds", "0:3", "--backend", "fast", "--out", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"dream: error: out: {out}:3: ") and message in err and err.count("\n") == 1
    assert out.read_bytes() == before  # the researcher's to mend


def test_a_table_that_is_not_utf8_is_refused_naming_the_line(drift, tmp_path):
    out = tmp_path / "runs.csv"
    sweep_plan = written(drift, out, [0, 1])
    out.write_bytes(out.read_bytes().replace(b",3,1,", b",\xff,1,"))
    with pytest.raises(ValueError, match=f"out: {out}:3: not UTF-8 text"):
        Table(out, sweep_plan).__enter__()


def test_plan_is_the_cartesian_product_with_converted_values(drift):
    sweep_plan = plan(drift, seeds=range(3), n=[2, 4], params={"speed": ["0.1", 0.2, 0.1]}, steps=7)
    keys = [(t.n, dict(t.params)["speed"], t.seed) for t in sweep_plan.tasks]
    # "0.1" and 0.1 are the same run once converted: 2 speeds x 2 sizes x 3 seeds, seeds innermost.
    assert keys == [(n, s, seed) for s in (0.1, 0.2) for n in (2, 4) for seed in range(3)]
    assert sweep_plan.swept == ["n", "params.speed"]
    assert sweep_plan.source == str(Path(drift).resolve())
    assert all(t.step_cap == 7 and t.backend == "auto" and t.experiment == "drift" for t in sweep_plan.tasks)


def test_plan_sweeps_faults_as_input_columns(drift):
    sweep_plan = plan(drift, seeds=[0], faults={"loss": [0, 0.3], "crash": ["0.5@3"]})
    assert [t.inputs()["faults.loss"] for t in sweep_plan.tasks] == ["0", "0.3"]
    assert sweep_plan.swept == ["faults.loss"]
    assert sweep_plan.tasks[1].fault_model() == dream.Faults(loss=0.3, crash=0.5, crash_at=3)


def test_sweep_runs_the_swarm_mode_and_refuses_it_where_there_is_none(drift, tmp_path, capsys):
    out = tmp_path / "swarm.csv"
    argv = ["sweep", drift, "--seeds", "0,1", "--backend", "fast", "--workers", "1", "--swarm"]
    assert main([*argv, "--out", str(out), "--no-progress"]) == 0
    rows = read(out)
    assert [(r["seed"], r["swarm"], r["measures.swarm"], r["success"]) for r in rows] == [
        ("0", "True", "True", "True"),
        ("1", "True", "True", "True"),
    ]
    assert float(rows[0]["measures.mean_x"]) != 0.0  # the swarm step drove them
    assert not plan(drift, seeds=[0]).tasks[0].swarm
    starter = tmp_path / "spread.py"
    assert main(["new", "spread", "-o", str(starter)]) == 0
    with pytest.raises(ValueError, match="swarm: spread has no swarm mode"):
        plan(str(starter), seeds=[0], swarm=True)


def test_table_from_before_the_swarm_column_resumes_as_robot_by_robot_runs(drift, tmp_path):
    out = tmp_path / "old.csv"
    task = plan(drift, seeds=[0]).tasks[0]
    out.write_text(
        "experiment,source_digest,n,seed,backend,step_cap,params.speed,success,error\n"
        f"drift,{task.source_digest},3,0,auto,,0.05,True,\n"
    )
    with Table(out, plan(drift, seeds=[0])) as table:
        assert task.key() in table.done
    swarm = plan(drift, seeds=[0], swarm=True)
    with Table(out, swarm) as table:
        assert swarm.tasks[0].key() not in table.done  # a swarm run is another run


def test_plan_of_a_builtin_sends_its_name_and_refuses_bad_values():
    assert plan("line-consensus", seeds=[0]).source == "line-consensus"
    assert dict(plan(dream.experiments.LineConsensus(radio_gap=5), seeds=[1]).tasks[0].params)["radio_gap"] == 5
    with pytest.raises(ValueError, match="seeds must be an integer >= 0"):
        plan("line-consensus", seeds=[-1])
    with pytest.raises(ValueError, match=r"params\['spacing'\] has no values"):
        plan("line-consensus", seeds=[0], params={"spacing": []})
    with pytest.raises(ValueError, match="unknown experiment 'nope'"):
        plan("nope", seeds=[0])


def test_unreachable_scheduler_is_one_line_and_leaves_no_file(drift, tmp_path, capsys):
    out = tmp_path / "none.csv"
    argv = ["sweep", drift, "--scheduler", f"tcp://127.0.0.1:{free_port()}", "--out", str(out), "--no-progress"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("dream: error: scheduler: cannot reach tcp://127.0.0.1:") and err.count("\n") == 1
    assert not out.exists()


def test_a_changed_experiment_file_reruns_its_rows_and_the_summary_counts_new_and_kept(
    drift, tmp_path, monkeypatch, capsys
):
    out = tmp_path / "runs.csv"
    written(drift, out, [0, 1])  # rows of the file as it is now
    Path(drift).write_text(DRIFT.replace("step >= 4", "step >= 5"))  # then the researcher edits it
    argv = ["sweep", drift, "--seeds", "0:2", "--backend", "fast", "--workers", "1", "--out", str(out), "--no-progress"]
    assert main(argv) == 0
    captured = capsys.readouterr()
    assert "2 runs of drift: 2 succeeded, 0 raised; 2 new, 0 kept;" in captured.out
    assert captured.err == f"dream: warning: out: {out}: 2 rows of this sweep come from other code of drift " \
        "(another source_digest): run again\n"  # fmt: skip
    rows = read(out)
    assert len(rows) == 2 and all(r["worker"] != "tcp://x:1" and r["completed_step"] == "5" for r in rows)
    assert {r["source_digest"] for r in rows} == {plan(drift, seeds=[0]).tasks[0].source_digest}

    monkeypatch.setattr(distributed, "LocalCluster", no_cluster)  # unchanged: nothing runs
    assert main(argv) == 0
    captured = capsys.readouterr()
    assert "2 runs of drift: 2 succeeded, 0 raised; 0 new, 2 kept;" in captured.out and captured.err == ""
    assert read(out) == rows


def test_a_table_without_source_digests_reruns_this_sweeps_rows_saying_so_once(drift, tmp_path):
    out = tmp_path / "old.csv"
    out.write_text(
        "experiment,n,seed,backend,step_cap,params.speed,success,error\n"
        "drift,3,0,auto,,0.05,True,\ndrift,3,1,auto,,0.05,True,\ndrift,3,0,auto,,0.5,True,\n"
    )
    sweep_plan = plan(drift, seeds=[0, 1])
    with pytest.warns(RuntimeWarning) as caught, Table(out, sweep_plan) as table:
        assert not any(task.key() in table.done for task in sweep_plan.tasks)
        assert len(table.rows) == 1  # another sweep's row (speed 0.5) stays
    assert [str(w.message) for w in caught] == [
        f"out: {out}: 2 rows of this sweep come from a table written before sweeps recorded the experiment's "
        "code (no source_digest column): run again"
    ]


def test_the_source_digest_is_of_the_experiments_file_builtin_or_not(drift):
    import hashlib

    from dream.experiments import LineConsensus

    def digest(path) -> str:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()[:16]

    assert plan(drift, seeds=[0]).tasks[0].source_digest == digest(drift)
    builtin = plan("line-consensus", seeds=[0]).tasks[0].source_digest
    assert builtin == digest(sys.modules[LineConsensus.__module__].__file__)


def test_sweep_writes_each_runs_log_beside_its_csv(drift, tmp_path):
    import pyarrow.parquet as pq

    from dream.sweep import log_name, logs_folder
    from dream.trajectory_log import read_metadata

    out = tmp_path / "s.csv"
    rows = dream.sweep(drift, seeds=[0, 1, 2], params={"speed": [0.05, 0.1]}, workers=1, out=out, log=True, log_every=2)
    folder = logs_folder(out)
    assert folder == tmp_path / "s-logs"
    done = [row for row in rows if not row["error"]]
    assert len(done) == 4 and all(row["log"] is None for row in rows if row["error"])  # seed 2 raised: no log
    assert sorted(Path(row["log"]).name for row in done) == sorted(p.name for p in folder.iterdir())
    for row in done:
        meta = read_metadata(row["log"])
        assert (meta["seed"], meta["params"], meta["log_every"]) == (row["seed"], {"speed": row["params.speed"]}, 2)
        assert pq.read_table(row["log"]).column("step").to_pylist() == [0] * 3 + [2] * 3 + [4] * 3  # done at step 4
    assert len({log_name(task) for task in plan(drift, [0, 1], params={"speed": [0.05, 0.1]}).tasks}) == 4
    with pytest.raises(ValueError, match="give out too"):
        dream.sweep(drift, seeds=[0], workers=1, log=True)


def test_sweep_command_logs_each_run(drift, tmp_path, capsys):
    out = tmp_path / "s.csv"
    assert (
        main(["sweep", drift, "--seeds", "0:2", "--workers", "1", "--out", str(out), "--log", "--log-every", "3"]) == 0
    )
    assert f"logs in {tmp_path / 's-logs'}" in capsys.readouterr().out
    assert len(list((tmp_path / "s-logs").glob("drift-n3-seed*.parquet"))) == 2
    assert main(["sweep", drift, "--seeds", "0", "--out", str(tmp_path / "t.csv"), "--log-every", "3"]) == 2
    assert "give --log too" in capsys.readouterr().err
