"""The TCA law against closed forms (SPEC section 4)."""
import math

import casadi as ca
import numpy as np
import pytest

from tca_casadi.model.laws.tca import TcaLaw
LAW = TcaLaw(coil_radius=0.6e-3, fiber_radius=0.5e-3, pitch_angle=math.radians(30), fiber_length=0.09,
             reference_length=0.045, reference_temperature=25.0,
             untwist_coefficients=(-0.0161, 0.3338, -7.7311), shear_coefficients=(37.58e6, 111.33e6, 0.85e6))


def test_free_stroke_zero_at_reference_and_contracting_when_heated():
    assert LAW.free_stroke(25.0) == 0.0
    expected = 0.09 * 0.6e-3 * math.cos(math.radians(30)) * (LAW.untwist(100.0) - LAW.untwist(25.0))
    assert LAW.free_stroke(100.0) == pytest.approx(expected, rel=1e-14)
    assert LAW.free_stroke(100.0) < 0


def test_untwist_is_the_papers_fit():
    assert LAW.untwist(25.0) == pytest.approx(-0.0161 * 625 + 0.3338 * 25 - 7.7311, rel=1e-14)


def test_residual_vanishes_on_the_law():
    force = 0.02
    stroke = LAW.free_stroke(90.0) + LAW.stretch(force)
    assert LAW.residual(stroke, force, 90.0) == pytest.approx(0.0, abs=1e-12 * LAW.residual_scale)


def test_stretch_is_castigliano():
    force = 0.01
    polar = math.pi * 0.5e-3**4 / 2
    g = 37.58e6 * force**2 + 111.33e6 * force + 0.85e6
    compliance = 0.09 * 0.6e-3**2 * math.cos(math.radians(30))**2 / (g * polar)
    assert LAW.stretch(force) == pytest.approx(force * compliance, rel=1e-13)


def test_shear_modulus_extension_is_positive_and_c1():
    eps = 1e-7
    assert float(LAW.shear_modulus(-0.05)) > 0
    # continuous: the gap across 0 is the slope times 2 eps
    assert float(LAW.shear_modulus(eps)) - float(LAW.shear_modulus(-eps)) == pytest.approx(2 * eps * 111.33e6, rel=1e-3)
    slope_left = (float(LAW.shear_modulus(0.0)) - float(LAW.shear_modulus(-eps))) / eps
    slope_right = (float(LAW.shear_modulus(eps)) - float(LAW.shear_modulus(0.0))) / eps
    assert slope_left == pytest.approx(slope_right, rel=1e-4)
    symbolic = ca.SX.sym("F")
    fn = ca.Function("g", [symbolic], [LAW.shear_modulus(symbolic)])
    assert float(fn(-0.03)) == pytest.approx(float(LAW.shear_modulus(-0.03)), rel=1e-14)


def test_monotone_limit():
    assert LAW.monotone_limit == pytest.approx(math.sqrt(0.85 / 37.58), rel=1e-14)
    f = np.linspace(0.01, 0.3, 400)
    ratio = f / LAW.shear_modulus(f)
    assert f[np.argmax(ratio)] == pytest.approx(LAW.monotone_limit, abs=1e-3)
