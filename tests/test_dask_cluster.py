"""Real Dask processes: `dask scheduler` and `dask worker` subprocesses on 127.0.0.1.

Workers killed mid-batch, a scheduler lost and restarted, a scheduler lost for
good (one line, exit 3, checkpoint intact, resumable on another backend), no
workers (a waiting message), TLS with certificates made here.
"""
from __future__ import annotations

import datetime
import json
import os
import signal
import socket
import subprocess
import sys
import time

import numpy as np
import pytest

distributed = pytest.importorskip("distributed")

from gpmotion import evaluators  # noqa: E402
from gpmotion.inprocess import InProcessEvaluator  # noqa: E402
from gpmotion.evaluators import DaskEvaluator, SchedulerLost  # noqa: E402
from gpmotion.families import make_family  # noqa: E402
from gpmotion.task import get_task  # noqa: E402

pytestmark = pytest.mark.dask

ENV = {**os.environ, "NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _wait_port(port, timeout=30.0):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.1)
    raise RuntimeError(f"nothing listening on {port}")


class Cluster:
    """`dask scheduler` + `dask worker` subprocesses (killed at the end)."""

    def __init__(self, port=None, tls_args=()):
        self.port = port or _free_port()
        self.tls_args = list(tls_args)
        self.procs = []
        self.scheduler = None

    @property
    def address(self):
        return f"{'tls' if self.tls_args else 'tcp'}://127.0.0.1:{self.port}"

    def start_scheduler(self):
        self.scheduler = self._spawn([sys.executable, "-m", "distributed.cli.dask_scheduler",
                                      "--host", "127.0.0.1", "--port", str(self.port),
                                      "--no-dashboard", *self.tls_args])
        _wait_port(self.port)
        return self

    def start_worker(self):
        return self._spawn([sys.executable, "-m", "distributed.cli.dask_worker", self.address,
                            "--nthreads", "1", "--host", "127.0.0.1", "--no-dashboard",
                            *self.tls_args])

    def _spawn(self, cmd):
        p = subprocess.Popen(cmd, env=ENV, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                             start_new_session=True)
        self.procs.append(p)
        return p

    def kill(self, p):
        try:
            os.killpg(p.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        p.wait()

    def close(self):
        for p in self.procs:
            self.kill(p)


@pytest.fixture
def cluster():
    c = Cluster()
    yield c
    c.close()


@pytest.fixture(scope="module")
def problem():
    task = get_task("lamp_hop", seconds=0.3)
    fam = make_family("bsr-time", task)
    rng = np.random.default_rng(7)
    pop = [fam.random(rng) for _ in range(48)]
    return task, fam, pop, InProcessEvaluator(task, fam).evaluate(pop)


def _wait_workers(ev, n, timeout=60):
    ev.client.wait_for_workers(n, timeout=timeout)


def test_real_worker_killed_mid_batch_gives_the_same_result(cluster, problem):
    task, fam, pop, ref = problem
    cluster.start_scheduler()
    cluster.start_worker()
    cluster.start_worker()
    with DaskEvaluator(task, fam, scheduler=cluster.address, chunk_size=4) as ev:
        _wait_workers(ev, 2)
        ev.client.run(evaluators._warm_worker, ev.spec)
        pids = ev.worker_pids()
        killed = []

        def kill_one(ev):
            if not killed:
                pid = sorted(pids.values())[0]
                os.kill(pid, signal.SIGKILL)          # the worker process (its nanny restarts it)
                killed.append(pid)

        ev._hook_after_submit = kill_one
        got = ev.evaluate(pop)
        assert killed
        assert got.costs.tobytes() == ref.costs.tobytes()
        assert got.success.tobytes() == ref.success.tobytes()


@pytest.mark.slow
def test_a_restarted_scheduler_is_reconnected_and_the_batch_resubmitted(cluster, problem, capfd):
    task, fam, pop, ref = problem
    cluster.start_scheduler()
    cluster.start_worker()
    with DaskEvaluator(task, fam, scheduler=cluster.address, chunk_size=4,
                       reconnect_grace=60) as ev:
        _wait_workers(ev, 1)
        done = []

        def restart(ev):
            if not done:
                done.append(1)
                cluster.kill(cluster.scheduler)
                cluster.start_scheduler()
                cluster.start_worker()

        ev._hook_after_submit = restart
        got = ev.evaluate(pop)
        assert got.costs.tobytes() == ref.costs.tobytes()
    err = capfd.readouterr().err
    assert "lost the Dask scheduler" in err and "reconnected" in err


def test_a_scheduler_lost_for_good_is_one_error_after_the_grace(cluster, problem):
    task, fam, pop, _ = problem
    cluster.start_scheduler()
    cluster.start_worker()
    with DaskEvaluator(task, fam, scheduler=cluster.address, chunk_size=4, reconnect_grace=2) as ev:
        _wait_workers(ev, 1)
        ev._hook_after_submit = lambda ev: cluster.kill(cluster.scheduler)
        t0 = time.monotonic()
        with pytest.raises(SchedulerLost, match="did not come back within 2 s"):
            ev.evaluate(pop)
        assert time.monotonic() - t0 < 30


@pytest.mark.slow
def test_no_workers_says_it_is_waiting(cluster, problem, capfd, monkeypatch):
    task, fam, pop, ref = problem
    monkeypatch.setattr(evaluators, "IDLE_POLL", 0.5)
    cluster.start_scheduler()
    with DaskEvaluator(task, fam, scheduler=cluster.address, chunk_size=8) as ev:
        started = []

        def late_worker(ev):                          # the message first, then a worker
            if not started:
                started.append(1)
                time.sleep(1.5)
                ev._report_idle()
                cluster.start_worker()

        ev._hook_after_submit = late_worker
        got = ev.evaluate(pop)
        assert got.costs.tobytes() == ref.costs.tobytes()
    assert "no Dask workers connected" in capfd.readouterr().err


@pytest.mark.slow
def test_cli_scheduler_lost_exits_3_and_resumes_on_a_process_pool(cluster, tmp_path):
    """`gpmotion run --scheduler tcp://...` whose scheduler dies: one line, exit 3, the
    checkpoint intact; `resume --workers 2` finishes it with the in-process result."""
    cluster.start_scheduler()
    cluster.start_worker()
    out = tmp_path / "dask-run"
    args = ["run", "lamp_hop", "--controller", "bsr-time", "--param", "seconds=0.3",
            "--working", "4", "--generations", "25", "--seed", "3", "--no-artifacts"]
    env = {**ENV, "GPMOTION_RECONNECT_GRACE": "2"}
    proc = subprocess.Popen([sys.executable, "-m", "gpmotion.cli", *args, "--out", str(out),
                             "--scheduler", cluster.address],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    t0 = time.monotonic()
    while not (out / "checkpoint.json").exists() and time.monotonic() - t0 < 120:
        time.sleep(0.05)
    cluster.kill(cluster.scheduler)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 3, err
    last = err.strip().splitlines()[-1]
    assert last.startswith("gpmotion: error: lost the Dask scheduler") and "gpmotion resume" in last
    assert "Traceback" not in err and "distributed.client" not in err
    from gpmotion.rundir import RunDir
    assert RunDir(out).load_checkpoint()["evaluations"] > 0          # intact, readable

    from gpmotion.cli import main
    assert main(["resume", str(out), "--workers", "2", "--quiet"]) == 0
    ref = tmp_path / "in-process"
    assert main([*args, "--out", str(ref), "--quiet"]) == 0
    a, b = (json.loads((d / "best.json").read_text()) for d in (out, ref))
    assert a["genome"] == b["genome"] and a["final_cost"] == b["final_cost"]


# ---- TLS -------------------------------------------------------------------------------------

def _certificates(folder):
    """A throwaway CA and a certificate for 127.0.0.1 signed by it (PEM files)."""
    pytest.importorskip("cryptography")
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.x509.oid import NameOID
    import ipaddress
    now = datetime.datetime.now(datetime.timezone.utc)

    def key_pem(k):
        return k.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
                               serialization.NoEncryption())

    ca_key = ec.generate_private_key(ec.SECP256R1())
    ca_name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "gpmotion test CA")])
    ca = (x509.CertificateBuilder().subject_name(ca_name).issuer_name(ca_name)
          .public_key(ca_key.public_key()).serial_number(x509.random_serial_number())
          .not_valid_before(now - datetime.timedelta(minutes=5))
          .not_valid_after(now + datetime.timedelta(days=1))
          .add_extension(x509.BasicConstraints(ca=True, path_length=None), critical=True)
          .sign(ca_key, hashes.SHA256()))
    key = ec.generate_private_key(ec.SECP256R1())
    cert = (x509.CertificateBuilder()
            .subject_name(x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "127.0.0.1")]))
            .issuer_name(ca_name).public_key(key.public_key())
            .serial_number(x509.random_serial_number())
            .not_valid_before(now - datetime.timedelta(minutes=5))
            .not_valid_after(now + datetime.timedelta(days=1))
            .add_extension(x509.SubjectAlternativeName([x509.IPAddress(ipaddress.ip_address("127.0.0.1"))]),
                           critical=False)
            .sign(ca_key, hashes.SHA256()))
    paths = {n: folder / f"{n}.pem" for n in ("ca", "cert", "key")}
    paths["ca"].write_bytes(ca.public_bytes(serialization.Encoding.PEM))
    paths["cert"].write_bytes(cert.public_bytes(serialization.Encoding.PEM))
    paths["key"].write_bytes(key_pem(key))
    return {k: str(v) for k, v in paths.items()}


def test_tls_cluster_with_certificates(tmp_path, problem):
    """A TLS LocalCluster (encryption required): the evaluator connects with --tls-* files
    and gives the in-process result; without them, or over tcp://, it is refused in one line."""
    from distributed import LocalCluster
    from distributed.security import Security
    task, fam, pop, ref = problem
    pem = _certificates(tmp_path)
    sec = Security(tls_ca_file=pem["ca"], tls_scheduler_cert=pem["cert"], tls_scheduler_key=pem["key"],
                   tls_worker_cert=pem["cert"], tls_worker_key=pem["key"],
                   tls_client_cert=pem["cert"], tls_client_key=pem["key"], require_encryption=True)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                      protocol="tls://", security=sec, dashboard_address=None,
                      scheduler_kwargs={"dashboard": False, "dashboard_address": "127.0.0.1:0"}) as lc:
        address = lc.scheduler_address
        assert address.startswith("tls://127.0.0.1:")
        with DaskEvaluator(task, fam, scheduler=address, tls_ca_file=pem["ca"],
                           tls_cert=pem["cert"], tls_key=pem["key"], chunk_size=8) as ev:
            assert ev.evaluate(pop).costs.tobytes() == ref.costs.tobytes()
        with pytest.raises(ValueError, match="CA certificate"):
            DaskEvaluator(task, fam, scheduler=address)
        with pytest.raises(ValueError, match="not tls://"):
            DaskEvaluator(task, fam, scheduler=address.replace("tls://", "tcp://"),
                          tls_ca_file=pem["ca"], tls_cert=pem["cert"], tls_key=pem["key"])
        with pytest.raises(ValueError, match="cannot reach"):    # plain tcp to a TLS-only port
            DaskEvaluator(task, fam, scheduler=address.replace("tls://", "tcp://"), timeout=3)


def test_local_cluster_is_tls_on_loopback(problem):
    task, fam, pop, ref = problem
    with DaskEvaluator(task, fam, scheduler="local", workers=1, chunk_size=16) as ev:
        assert ev.client.scheduler.address.startswith("tls://127.0.0.1:")
        with pytest.raises(OSError):           # no certificate: the cluster does not talk to us
            distributed.Client(ev.client.scheduler.address.replace("tls://", "tcp://"), timeout=2)


# ---- before anything is created; across backends ----------------------------------------------

RUN = ["run", "lamp_hop", "--controller", "bsr-time", "--param", "seconds=0.3", "--working", "4",
       "--generations", "3", "--seed", "1", "--quiet", "--no-artifacts"]


@pytest.mark.parametrize("address", ["garbage", "tcp://127.0.0.1:99999", "tls://127.0.0.1:8786",
                                     pytest.param("CLOSED", marks=pytest.mark.slow)])   # 10 s timeout
def test_bad_or_unreachable_scheduler_creates_nothing(tmp_path, capsys, address):
    from gpmotion.cli import main
    if address == "CLOSED":
        address = f"tcp://127.0.0.1:{_free_port()}"          # nothing listens there
    out = tmp_path / "never"
    assert main([*RUN, "--out", str(out), "--scheduler", address]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("gpmotion: error:") and "\n" not in err
    assert not out.exists()


def _best(d):
    rec = json.loads((d / "best.json").read_text())
    return rec["genome"], rec["final_cost"]


@pytest.mark.slow
def test_a_run_started_on_dask_resumes_on_a_process_pool_and_back(tmp_path):
    from gpmotion.cli import main
    from gpmotion.run import RunConfig, run
    ref = tmp_path / "ref"
    assert main([*RUN, "--out", str(ref)]) == 0
    cfg = RunConfig(task="lamp_hop", family="bsr-time", seed=1, params={"seconds": "0.3"},
                    search={"n_working": 4, "n_generations": 3}, scheduler="local", workers=1)
    d = tmp_path / "moved"
    run(cfg, d, quiet=True, artifacts=False, max_generations=1)      # stopped after one generation
    assert not (d / "best.json").exists()
    assert main(["resume", str(d), "--workers", "2", "--quiet"]) == 0
    assert _best(d) == _best(ref)
    cfg.scheduler, cfg.workers = None, 0                               # in-process -> Dask
    back = tmp_path / "back"
    run(cfg, back, quiet=True, artifacts=False, max_generations=1)
    assert main(["resume", str(back), "--scheduler", "local", "--workers", "1", "--quiet"]) == 0
    assert _best(back) == _best(ref)
