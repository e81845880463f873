"""The fitting batch: local processes, a real Dask cluster with a worker killed mid-batch, --resume after a crash.

The cluster is real: a ``dask scheduler`` and two ``dask worker`` processes on 127.0.0.1
(free ports, ``--nthreads 1``), started as subprocesses and killed at the end even when
a test fails. The batch runs through the ``brdfkit`` command line in a subprocess.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from brdfkit.measured.batch import make_jobs, run_batch

SRC = str(Path(__file__).resolve().parents[1] / "src")
SOURCES = ["nielsen/bindercover", "nielsen/bluebook", "nielsen/cardboard", "nielsen/glossyredpaper"]
MODELS = ["lambert", "blinn-phong", "ward"]
SETTINGS = dict(samples=600, starts=3, seed=0)
CLI_ARGS = ["--set", "nielsen", "--limit", "4", "--samples", "600", "--starts", "3"]


def _fits(folder):
    """The finished fit files: an atomic write in flight is a hidden ``.NAME.*.tmp.json`` beside them."""
    return sorted(f for f in folder.glob("*.json") if not f.name.startswith("."))


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = SRC + os.pathsep + env.get("PYTHONPATH", "")
    env["OMP_NUM_THREADS"] = "1"
    return env


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _kill_group(p: subprocess.Popen, sig=signal.SIGKILL) -> None:
    if p.poll() is None:
        try:
            os.killpg(p.pid, sig)
        except ProcessLookupError:
            pass
    try:
        p.wait(timeout=10)
    except subprocess.TimeoutExpired:  # pragma: no cover
        os.killpg(p.pid, signal.SIGKILL)
        p.wait(timeout=10)


def _cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "brdfkit", "fit", "--all-measured", *args]


def _records(out: Path) -> dict[tuple[str, str], dict]:
    """The stored fits, without the timing (the only field that may differ between runs)."""
    recs = json.loads((out / "fit_params.json").read_text())
    return {(r["source"], r["column"]): {k: v for k, v in r.items() if k != "seconds"} for r in recs}


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The batch on local processes (2 workers), the reference table."""
    out = tmp_path_factory.mktemp("local")
    res = run_batch(MODELS, SOURCES, out, workers=2, **SETTINGS)
    assert res.complete and res.fitted == len(SOURCES) * len(MODELS) and res.skipped == 0
    return out


def test_local_batch_tables(reference):
    rows = (reference / "fit_errors.csv").read_text().strip().splitlines()
    assert rows[0] == "material," + ",".join(MODELS)
    assert [r.split(",")[0] for r in rows[1:]] == SOURCES
    assert all(float(x) > 0 for r in rows[1:] for x in r.split(",")[1:])
    recs = _records(reference)
    assert len(recs) == 12 and all(r["samples"] == 600 and "at_bound" in r for r in recs.values())
    # one file per fit, each a complete JSON object
    assert len(list(_fits(reference / "fits"))) == 12
    md = (reference / "fit_errors.md").read_text()
    assert "| **mean rank** |" in md and ("fitting bound" in md)
    for png in ("fit_errors_sorted.png", "fit_errors_by_material.png"):
        assert (reference / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # in-process (one worker) gives the identical table: a fit is a pure function of its job
    same = run_batch(MODELS, SOURCES[:1], reference.parent / "one", workers=1, **SETTINGS)
    assert same.records[0]["error"] == recs[(SOURCES[0], MODELS[0])]["error"]


@pytest.fixture
def cluster(tmp_path):
    """A Dask scheduler and two workers on 127.0.0.1; yields (address, [worker processes])."""
    port = _free_port()
    procs = []
    logs = []
    try:
        log = open(tmp_path / "scheduler.log", "wb")
        logs.append(log)
        procs.append(subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", str(port),
             "--no-dashboard"], stdout=log, stderr=subprocess.STDOUT, env=_env(), start_new_session=True))
        addr = f"tcp://127.0.0.1:{port}"
        workers = []
        for i in range(2):
            log = open(tmp_path / f"worker{i}.log", "wb")
            logs.append(log)
            w = subprocess.Popen(
                [sys.executable, "-m", "distributed.cli.dask_worker", addr, "--nthreads", "1", "--nworkers", "1",
                 "--no-dashboard", "--host", "127.0.0.1", "--memory-limit", "0", "--name", f"w{i}"],
                stdout=log, stderr=subprocess.STDOUT, env=_env(), start_new_session=True)
            procs.append(w)
            workers.append(w)
        from distributed import Client

        with Client(addr, timeout=30) as c:
            c.wait_for_workers(2, timeout=60)
        yield addr, workers, tmp_path / "scheduler.log"
    finally:
        for p in reversed(procs):
            _kill_group(p)
        for log in logs:
            log.close()


def test_dask_cluster_with_a_worker_killed_mid_batch_equals_local(cluster, reference, tmp_path):
    addr, workers, sched_log = cluster
    out = tmp_path / "dask"
    p = subprocess.Popen(_cli("-m", "lambert", "-m", "blinn-phong", "-m", "ward", *CLI_ARGS, "--out", str(out),
                              "--scheduler", addr), stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=_env(),
                         start_new_session=True)
    try:
        t0 = time.time()
        fits = out / "fits"
        while time.time() - t0 < 300 and p.poll() is None:
            if fits.is_dir() and len(list(_fits(fits))) >= 1:
                break
            time.sleep(0.02)
        n_at_kill = len(list(_fits(fits)))
        assert p.poll() is None, p.communicate()[1].decode()[-2000:]
        _kill_group(workers[0])  # the worker and its nanny: its tasks in flight are lost
        assert 1 <= n_at_kill < 12, f"the kill came too late to test anything ({n_at_kill} of 12 done)"
        stdout, stderr = p.communicate(timeout=300)
    finally:
        _kill_group(p)
    assert p.returncode == 0, stderr.decode()[-2000:]
    assert "fitted 12 and kept 0 of 12 fits" in stdout.decode()
    assert "Remove worker" in sched_log.read_text() and "name: w0" in sched_log.read_text()
    assert (out / "fit_errors.csv").read_text() == (reference / "fit_errors.csv").read_text()
    assert _records(out) == _records(reference)


def test_resume_after_a_crash_completes_the_identical_table(reference, tmp_path):
    out = tmp_path / "crash"
    args = _cli("-m", "lambert", "-m", "blinn-phong", "-m", "ward", *CLI_ARGS, "--out", str(out), "--workers", "1")
    p = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=_env(), start_new_session=True)
    try:
        t0 = time.time()
        fits = out / "fits"
        while time.time() - t0 < 300 and p.poll() is None:
            if fits.is_dir() and len(list(_fits(fits))) >= 3:
                break
            time.sleep(0.02)
        _kill_group(p)  # SIGKILL: a crash, nothing gets to clean up
    finally:
        _kill_group(p)
    kept = sorted(_fits(fits))
    assert 3 <= len(kept) < 12, f"{len(kept)} fits at the crash"
    for f in kept:  # every file that exists is complete (atomic writes); no temp files are left as fits
        assert json.loads(f.read_text())["error"] > 0
    r = subprocess.run(args + ["--resume", "--json"], capture_output=True, env=_env(), timeout=300)
    assert r.returncode == 0, r.stderr.decode()[-2000:]
    summary = json.loads(r.stdout)
    assert summary["skipped"] == len(kept) and summary["fitted"] == 12 - len(kept)
    assert (out / "fit_errors.csv").read_text() == (reference / "fit_errors.csv").read_text()
    assert _records(out) == _records(reference)
    # resume with other settings refits instead of mixing results
    jobs = make_jobs(MODELS, SOURCES, samples=700, starts=3, seed=0)
    assert all(j.settings()["samples"] == 700 for j in jobs)


def test_interrupt_keeps_finished_fits_and_says_so(tmp_path):
    out = tmp_path / "int"
    # fits of 3000 samples (each ~0.1-0.2 s, not ~20 ms as at CLI_ARGS' 600), 8 materials × 3 models: after
    # the second fit the other 22 take several seconds, so a test process descheduled for a moment on a
    # loaded machine (the full suite on two cores) still interrupts a running batch, not one that has just
    # finished (with 4 materials, 10 fits left, a fresh-clone CI run once saw the batch end first: exit 0)
    slow = ["--set", "nielsen", "--limit", "8", "--samples", "3000", "--starts", "4"]
    args = _cli("-m", "lambert", "-m", "blinn-phong", "-m", "ward", *slow, "--out", str(out), "--workers", "1")
    # a process started with SIGINT ignored (as pytest-xdist workers and background shells do) would
    # inherit that and never see Ctrl-C: give the command the default disposition, as a terminal does
    p = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=_env(), start_new_session=True,
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        t0 = time.time()
        while time.time() - t0 < 300 and p.poll() is None:  # a cold numba cache compiles first
            if (out / "fits").is_dir() and len(list(_fits(out / "fits"))) >= 2:
                break
            time.sleep(0.02)
        assert p.poll() is None, "the batch ended before it could be interrupted"
        os.kill(p.pid, signal.SIGINT)
        _, stderr = p.communicate(timeout=300)
    finally:
        _kill_group(p)
    err = stderr.decode()
    assert p.returncode != 0 and "Traceback" not in err
    assert "interrupted" in err and "--resume" in err
    n = len(list(_fits(out / "fits")))
    assert n >= 2
    # the tables were written from what finished, with blank cells for the rest
    rows = (out / "fit_errors.csv").read_text().strip().splitlines()
    assert len(rows) == 9 and sum(c != "" for r in rows[1:] for c in r.split(",")[1:]) == n


@pytest.mark.parametrize(
    "args, words",
    [
        (("--scheduler", "nonsense"), "tcp://HOST:PORT"),
        (("--samples", "tabel"), "'table'"),
        (("--lobes", "3"), "--lobes"),
        (("--workers", "-1"), "--workers"),
    ],
)
def test_batch_errors_are_one_line(args, words, tmp_path, capsys):
    from brdfkit.cli import main

    rc = main(["fit", "--all-measured", "-m", "lambert", "--set", "nielsen", "--limit", "1", "--out",
               str(tmp_path / "o"), *args])
    err = capsys.readouterr().err
    assert rc == 2 and words in err and len(err.strip().splitlines()) == 1


def test_unreachable_scheduler_is_one_line(tmp_path, capsys, monkeypatch):
    from brdfkit.cli import main

    monkeypatch.setenv("BRDFKIT_DASK_TIMEOUT", "2")
    rc = main(["fit", "--all-measured", "-m", "lambert", "--set", "nielsen", "--limit", "1", "--samples", "100",
               "--out", str(tmp_path / "o"), "--scheduler", f"tcp://127.0.0.1:{_free_port()}"])
    err = capsys.readouterr().err
    assert rc == 2 and "cannot connect" in err and len(err.strip().splitlines()) == 1
