"""A sweep through a Dask ``LocalCluster`` of two worker processes gives the serial rows (about 2 s;
skipped without ``distributed``)."""

from __future__ import annotations

import numpy as np
import pytest

from isolator.cli.app import main
from isolator.sweep import sweep
from isolator.sweep.output import read_columns

distributed = pytest.importorskip("distributed")

GRID = {"isolators[*].stiffness": [0.6, 1.0, 1.7], "isolators[*].damping": [0.5, 2.0]}


def test_a_dask_cluster_gives_the_serial_rows(tmp_path):
    out = tmp_path / "rows.csv"
    serial = sweep("paper-table-3-2", scale=GRID, workers=1).table()
    cluster = distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1, dashboard_address=None)
    with cluster, distributed.Client(cluster) as client:
        through = sweep("paper-table-3-2", scale=GRID, executor=client.get_executor(), chunk_size=2).table()
        # and from the command line, through the scheduler's address
        status = main(["sweep", "--scale", "isolators[*].stiffness=0.6,1.0,1.7", "--scale",
                       "isolators[*].damping=0.5,2.0", "--scheduler", cluster.scheduler_address, "--out", str(out)])
    assert status == 0
    assert read_columns(out)["settling_time_max"].tolist() == pytest.approx(serial["settling_time_max"].tolist(),
                                                                             rel=1e-12, nan_ok=True)
    for name, values in serial.items():
        if values.dtype == object:
            assert values.tolist() == through[name].tolist(), name
        else:
            np.testing.assert_allclose(through[name], values, rtol=1e-12, atol=0, equal_nan=True, err_msg=name)
