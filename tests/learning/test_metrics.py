"""Error measures against hand-computed values."""

import numpy as np
import pytest

from toolpoint.learning.metrics import afv, mape, max_ape, ndei, nrmse, rmse

Y_TRUE = [1.0, 2.0, 3.0, 4.0]
Y_PRED = [1.1, 1.9, 3.2, 3.8]
# errors ±0.1, ±0.2: Σe² = 0.1, mean 0.025; σ_t = sqrt(1.25); Σo² = 29.5
# relative errors 0.1, 0.05, 0.0667, 0.05


def test_rmse():
    assert rmse(Y_TRUE, Y_PRED) == pytest.approx(np.sqrt(0.025), rel=1e-12)


def test_nrmse_and_ndei():
    assert nrmse(Y_TRUE, Y_PRED) == pytest.approx(np.sqrt(0.025 / 1.25), rel=1e-12)  # = sqrt(0.02)
    assert ndei(Y_TRUE, Y_PRED) == nrmse(Y_TRUE, Y_PRED)


def test_afv_uses_sum_of_squared_outputs():
    assert afv(Y_TRUE, Y_PRED) == pytest.approx(1 - 0.1 / 29.5, rel=1e-12)
    assert afv(Y_TRUE, Y_TRUE) == 1.0


def test_mape_and_max_ape_in_percent():
    assert mape(Y_TRUE, Y_PRED) == pytest.approx(100 * (0.1 + 0.05 + 0.2 / 3 + 0.05) / 4, rel=1e-12)
    assert max_ape(Y_TRUE, Y_PRED) == pytest.approx(10.0, rel=1e-12)
    assert mape([-2.0], [-1.0]) == pytest.approx(50.0)  # |t| in the denominator


def test_perfect_fit():
    for f in (rmse, nrmse, mape, max_ape):
        assert f(Y_TRUE, Y_TRUE) == 0.0


@pytest.mark.parametrize("f", [rmse, nrmse, ndei, afv, mape, max_ape])
def test_bad_input(f):
    with pytest.raises(ValueError, match="values"):
        f([1.0, 2.0], [1.0])
    with pytest.raises(ValueError, match="finite"):
        f([1.0, np.nan], [1.0, 2.0])
    with pytest.raises(ValueError, match="empty"):
        f([], [])


def test_undefined_cases():
    with pytest.raises(ValueError, match="zero target"):
        mape([0.0, 1.0], [0.1, 1.0])
    with pytest.raises(ValueError, match="constant targets"):
        nrmse([2.0, 2.0], [1.0, 3.0])
    with pytest.raises(ValueError, match="zero"):
        afv([1.0, 2.0], [0.0, 0.0])
