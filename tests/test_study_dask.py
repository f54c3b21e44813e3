"""`gpmotion study run --scheduler ADDR`: a study's searches evaluated on a real
Dask cluster (`dask scheduler` and `dask worker` processes on 127.0.0.1) give
the rows and controllers of the same study run in-process."""
import json

import pytest

from gpmotion.cli import main
from gpmotion.study.ledger import read_rows
from tests.test_dask_cluster import Cluster
from tests.test_study_run import controllers, spec, untimed

pytestmark = pytest.mark.dask


@pytest.fixture
def cluster():
    c = Cluster().start_scheduler()
    c.start_worker()
    c.start_worker()
    yield c
    c.close()


def test_a_study_on_a_dask_cluster_gives_the_in_process_rows(cluster, tmp_path):
    s = spec(tmp_path)
    assert main(["study", "run", str(s), "--out", str(tmp_path / "local"), "--quiet"]) == 0
    assert main(["study", "run", str(s), "--out", str(tmp_path / "dask"), "--quiet",
                 "--scheduler", cluster.address]) == 0
    rows = read_rows(tmp_path / "dask")
    assert len(rows) == 6 and untimed(rows) == untimed(read_rows(tmp_path / "local"))
    assert controllers(tmp_path / "dask") == controllers(tmp_path / "local")
    configs = [json.loads(p.read_text()) for p in (tmp_path / "dask").rglob("config.json")]
    assert len(configs) == 6 and {c["run"]["scheduler"] for c in configs} == {cluster.address}
