"""Sweeps keep their work when workers die (issue 39): the finished rows are kept, lost rows
are retried a bounded number of times (one point a task) and then reported per row (NaN and
a WorkerLost reason), on every executor; a user function's exception is its row's failure
under on_error="nan". Workers are killed by ``os._exit`` inside the analysis."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import mechsys as ms
from test_sweep import OUTPUTS, T0, build_slider_crank

GRID = {"r": [1.5, 2.0], "L": [5.0, 6.0, 7.0]}


class DieAt:
    """``model.solve(T0)``, but the worker process dies at the point ``L == at`` — every time
    (``once=None``), or only the first time (``once``: a marker file's path)."""

    def __init__(self, at: float, once: str | None = None):
        self.at, self.once = at, once

    def __call__(self, model):
        if model.parameters["L"] == self.at:
            if self.once is None or not Path(self.once).exists():
                if self.once is not None:
                    Path(self.once).write_text("died once")
                os._exit(3)
        return model.solve(T0, solution="velocity")


@pytest.fixture(scope="module")
def serial():
    return ms.sweep(build_slider_crank, GRID, "velocity", OUTPUTS, t=T0)


def _same_rows(df, ref, rows):
    for c in ("r", "L", "x", "v"):
        np.testing.assert_array_equal(df[c].to_numpy()[rows], ref[c].to_numpy()[rows])


def test_output_function_exception_is_a_row_failure(serial):
    """An exception of the user's output function ended the sweep even with on_error='nan'."""
    piston = build_slider_crank().body("piston")

    def x_or_fail(sol):
        x = sol.location(piston.point(0))[0]
        if x > 7.5:
            raise ValueError("too far")
        return x

    m = piston.model
    df = ms.sweep(m, GRID, lambda mm: mm.solve(T0, solution="velocity"),
                  {"x": x_or_fail, "v": OUTPUTS["v"]}, on_error="nan")
    bad = serial["x"].to_numpy() > 7.5
    assert bad.any() and not bad.all()
    assert df["x"].isna().to_numpy().tolist() == bad.tolist()
    assert all("output 'x' raised ValueError: too far" in e for e in df["error"][bad])
    np.testing.assert_array_equal(df["x"].to_numpy()[~bad], serial["x"].to_numpy()[~bad])
    with pytest.raises(ms.MechError, match="output 'x' raised ValueError"):
        ms.sweep(m, GRID, lambda mm: mm.solve(T0, solution="velocity"), {"x": x_or_fail})


def test_process_pool_keeps_finished_rows_when_a_worker_dies(serial):
    """A point that kills its worker every time: the pool broke and every row was lost
    (BrokenProcessPool). Now the other rows are the serial sweep's, bit for bit; the fatal
    points (L = 7) are NaN with a WorkerLost reason."""
    df = ms.sweep(build_slider_crank, GRID, DieAt(7.0), OUTPUTS, executor="processes",
                  workers=2, chunks=2, on_error="nan")
    fatal = (df["L"] == 7.0).to_numpy()
    _same_rows(df, serial, ~fatal)
    assert df["x"].isna().to_numpy().tolist() == fatal.tolist()
    assert all(e.startswith("WorkerLost") and "3 times" in e for e in df["error"][fatal])
    with pytest.raises(ms.MechError, match=r"died 3 times"):
        ms.sweep(build_slider_crank, {"r": [2.0], "L": [7.0]}, DieAt(7.0), OUTPUTS,
                 executor="processes", workers=1)


def test_process_pool_retries_a_transient_loss(serial, tmp_path):
    """A worker lost once (the point succeeds when tried again): every row as serial."""
    df = ms.sweep(build_slider_crank, GRID, DieAt(6.0, str(tmp_path / "died")), OUTPUTS,
                  executor="processes", workers=2, chunks=3)
    assert (tmp_path / "died").exists()
    pd.testing.assert_frame_equal(df, serial, check_exact=True)


def test_dask_keeps_finished_rows_after_killed_worker(serial, tmp_path):
    """Dask gives up on a task whose worker died (``KilledWorker``; here Dask's own retries
    are off, so the first death does it) and every row was lost. Now the finished rows are
    kept and the lost task's points are run again (their payload carried in the task, since
    the scattered copy may have died with the worker): every row as serial, bit for bit."""
    distributed = pytest.importorskip("distributed")
    import dask

    with dask.config.set({"distributed.scheduler.allowed-failures": 0}), \
            distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                     dashboard_address=None, silence_logs=50) as cluster, \
            distributed.Client(cluster) as client:
        df = ms.sweep(build_slider_crank, GRID, DieAt(5.0, str(tmp_path / "died")), OUTPUTS,
                      executor=client, chunks=3)
    assert (tmp_path / "died").exists()
    pd.testing.assert_frame_equal(df, serial, check_exact=True)
