"""``gearfmu tables --scheduler tcp://HOST:PORT``: the table precomputation on a Dask cluster.

Reference: the same scene's tables computed by the local process pool of this process
(:func:`gearfmu.pipeline.compute_tables`, no cluster).  Every film solve is a deterministic
function of its request and the results are placed by request, not by completion order, so the
tables must be identical bit for bit whichever processes solved the films.  The cluster is a
``distributed.LocalCluster`` of two worker processes started here.
"""
from __future__ import annotations

import dask
import numpy as np
import pytest
from distributed import Client, LocalCluster, get_task_stream

from gearfmu import cli, pipeline
from gearfmu.common.executors import make_executor, cluster
from gearfmu.scene.reader import default_scene_path
from gearfmu.tables.mesh_tables import load_tables

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

#: a small lubricated scene: the default pair with smooth EHL, two slices, 8 points per mesh
LUBRICATED = (default_scene_path().read_text()
              .replace('contact_model = "hertz"', 'contact_model = "smooth_ehl"')
              .replace("slices = 44 ", "slices = 2 ")
              .replace("points_per_mesh = 64", "points_per_mesh = 8"))


@pytest.fixture(scope="module")
def dask_cluster():
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as lc, \
            Client(lc) as client:
        yield lc, client


def _arrays(t):
    return {k: v for k, v in vars(t).items() if isinstance(v, np.ndarray)}


def _assert_identical(got, ref):
    a, b = _arrays(got), _arrays(ref)
    assert sorted(a) == sorted(b)
    for k in b:
        assert a[k].shape == b[k].shape and a[k].dtype == b[k].dtype, k
        assert a[k].tobytes() == b[k].tobytes(), f"{k}: max |diff| {np.max(np.abs(a[k] - b[k]))}"


@pytest.mark.parametrize("name", ["lubricated", "default"])
def test_tables_on_a_dask_cluster_equal_the_local_pool(dask_cluster, tmp_path, name):
    lc, client = dask_cluster
    text = LUBRICATED if name == "lubricated" else default_scene_path().read_text()
    assert name == "default" or ('contact_model = "smooth_ehl"' in text and "slices = 2 " in text)
    scene_file = tmp_path / "scene.toml"
    scene_file.write_text(text)
    out = tmp_path / "t.gtab"
    with get_task_stream(client) as ts:
        rc = cli.main(["tables", str(scene_file), "-o", str(out), "-q", "--scheduler", lc.scheduler_address])
    assert rc == 0
    if name == "lubricated":   # the films were solved by the cluster's workers
        assert len(ts.data) > 0 and {t["worker"] for t in ts.data} <= set(client.scheduler_info()["workers"])
    ref = pipeline.compute_tables(pipeline.load(text))    # the local process pool
    _assert_identical(load_tables(out), ref)


def test_cluster_block_replaces_only_the_local_pool(dask_cluster):
    lc, client = dask_cluster
    with cluster(client=client):
        with make_executor(max_workers=2) as ex:
            assert ex.submit(sum, [1, 2]).result() == 3 and type(ex).__module__.startswith("distributed")
        with make_executor() as ex:                         # default size: the cluster, not this machine's CPUs
            assert type(ex).__module__.startswith("distributed")
        with make_executor(max_workers=1) as ex:            # explicitly in-process stays in-process
            assert not type(ex).__module__.startswith("distributed")
    with make_executor(max_workers=2) as ex:                # after the block: the local pool again
        assert not type(ex).__module__.startswith("distributed")


def test_bad_scheduler_is_one_line(capsys):
    with pytest.raises(SystemExit) as e:
        cli.main(["tables", "--scheduler", "localhost:8786"])
    assert e.value.code == 2
    assert "scheduler: expected an address such as 'tcp://127.0.0.1:8786'" in capsys.readouterr().err
    with dask.config.set({"distributed.comm.timeouts.connect": "2s"}):
        rc = cli.main(["tables", "-q", "--scheduler", "tcp://127.0.0.1:1"])  # nothing listens there
    assert rc == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("gearfmu: scheduler: cannot connect to tcp://127.0.0.1:1")
