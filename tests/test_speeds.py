"""Cutting, spindle and feed speed (cnclab.cutting.speeds): hand values, inverse, bad input."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cnclab.cutting.speeds import cutting_speed, feed_speed, spindle_speed


def test_hand_values():
    assert float(cutting_speed(10, 3820)) == pytest.approx(10 * 3820 * math.pi / 1000)   # §5.5: ~120 m/min
    assert round(float(cutting_speed(10, 3820))) == 120
    assert float(cutting_speed(10, 5100)) == pytest.approx(160.221, abs=1e-3)          # Table 4-3 (not 1600)
    assert float(cutting_speed(0.0, 5100)) == 0.0                                      # tool tip
    assert [float(feed_speed(fz, 4, 5100)) for fz in (0.08, 0.12, 0.16)] == [1632.0, 2448.0, 3264.0]


@settings(max_examples=200, deadline=None, derandomize=True)
@given(st.floats(1e-3, 100), st.floats(1, 1e5))
def test_spindle_speed_inverts_cutting_speed(d, n):
    assert float(spindle_speed(cutting_speed(d, n), d)) == pytest.approx(n, rel=1e-12)


@settings(max_examples=100, deadline=None, derandomize=True)
@given(st.floats(1e-3, 100), st.floats(1, 1e5), st.floats(1.01, 10))
def test_cutting_speed_linear_in_diameter(d, n, k):
    assert float(cutting_speed(k * d, n)) == pytest.approx(k * float(cutting_speed(d, n)), rel=1e-12)


def test_broadcasting():
    v = cutting_speed(np.array([1.0, 2.0, 3.0])[:, None], np.array([1000.0, 2000.0]))
    assert v.shape == (3, 2)
    assert np.allclose(spindle_speed(v, np.array([1.0, 2.0, 3.0])[:, None]), [[1000.0, 2000.0]] * 3)


@pytest.mark.parametrize("call, name", [
    (lambda: cutting_speed(-1, 1000), "diameter_mm"),
    (lambda: cutting_speed(10, float("nan")), "n_rpm"),
    (lambda: cutting_speed("ten", 1000), "diameter_mm"),
    (lambda: spindle_speed(120, 0.0), "diameter_mm"),
    (lambda: spindle_speed(-5, 10), "v_c_m_min"),
    (lambda: feed_speed(0.1, 2.5, 1000), "teeth"),
    (lambda: feed_speed(0.1, 0, 1000), "teeth"),
    (lambda: feed_speed(-0.1, 4, 1000), "f_z_mm"),
    (lambda: feed_speed(0.1, 4, float("inf")), "n_rpm"),
])
def test_bad_input_names_parameter(call, name):
    with pytest.raises(ValueError, match=rf"^{name} "):
        call()
