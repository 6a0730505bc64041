"""The pieces of the physics against closed forms: TCA law, sections, rotations, collocation."""
import math

import casadi as ca
import numpy as np
import pytest

from tca_casadi.discretisation import CollocationScheme
from tca_casadi.model.rotations import (matrix_to_quaternion, quaternion_product, rotation_matrix,
                                        rotation_numpy)
from tca_casadi.model.sections import saint_venant_rectangle
from tca_casadi.model.tca_law import TcaLaw

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


def test_saint_venant_square_and_thin_strip():
    assert saint_venant_rectangle(1.0, 1.0) == pytest.approx(0.1405770, rel=1e-6)    # classical k1 = 0.1406
    assert saint_venant_rectangle(100.0, 1.0) == pytest.approx(100 / 3 * (1 - 0.630 / 100), rel=1e-3)


@pytest.mark.parametrize("h", [[1, 0, 0, 0], [0.3, -1.2, 0.7, 2.0], [5.0, 0.1, 0.2, -0.3]])
def test_rotation_from_nonunit_quaternion(h):
    R = rotation_numpy(h)
    assert np.allclose(R.T @ R, np.eye(3), atol=1e-14)
    assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-14)
    q = matrix_to_quaternion(R)
    assert np.allclose(np.abs(q @ (np.array(h) / np.linalg.norm(h))), 1.0, atol=1e-12)


def test_quaternion_product_composes_rotations():
    a, b = ca.DM([0.3, -1.2, 0.7, 2.0]), ca.DM([1.0, 0.4, -0.2, 0.1])
    lhs = np.array(rotation_matrix(quaternion_product(a, b)))
    assert np.allclose(lhs, rotation_numpy(a) @ rotation_numpy(b), atol=1e-14)


@pytest.mark.parametrize("kind", ["legendre", "radau"])
@pytest.mark.parametrize("degree", [1, 2, 4, 6])
def test_collocation_scheme_is_exact_on_polynomials(kind, degree):
    scheme = CollocationScheme.create(degree, kind)
    poly = np.poly1d(np.arange(1.0, degree + 2))  # degree d polynomial
    values = poly(scheme.tau)
    assert np.allclose(values @ scheme.C, np.polyder(poly)(scheme.tau), atol=1e-9)
    assert values @ scheme.D == pytest.approx(poly(1.0), rel=1e-12)
    exact_to = 2 * degree - 1 if kind == "legendre" else 2 * degree - 2
    quad_poly = np.poly1d(np.ones(exact_to + 1))
    assert scheme.weights @ quad_poly(scheme.tau[1:]) == pytest.approx(np.polyint(quad_poly)(1.0), rel=1e-12)
