"""Two Datasets equal bit for bit: the check the executors' and the draws' tests share."""

from __future__ import annotations

import numpy as np
import xarray as xr


def assert_same_data(a: xr.Dataset, b: xr.Dataset) -> None:
    """Every data variable and coordinate bit for bit (NaN where NaN)."""
    assert set(a.data_vars) == set(b.data_vars) and set(a.coords) == set(b.coords)
    for k in list(a.data_vars) + list(a.coords):
        x, y = a[k].values, b[k].values
        assert x.dtype == y.dtype and x.shape == y.shape, k
        if x.dtype.kind == "f":
            assert np.array_equal(x.view(np.uint64), y.view(np.uint64)), k
        else:
            assert np.array_equal(x, y), k
