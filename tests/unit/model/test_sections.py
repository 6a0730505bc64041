"""Section constants against closed forms."""
import pytest

from tca_casadi.model.sections import saint_venant_rectangle


def test_saint_venant_square_and_thin_strip():
    assert saint_venant_rectangle(1.0, 1.0) == pytest.approx(0.1405770, rel=1e-6)    # classical k1 = 0.1406
    assert saint_venant_rectangle(100.0, 1.0) == pytest.approx(100 / 3 * (1 - 0.630 / 100), rel=1e-3)


