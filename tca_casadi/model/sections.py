"""Cross-section properties and the stiffness ``K = blkdiag(Kbt, Kse)`` (SPEC section 2)."""
import math
from dataclasses import dataclass

import numpy as np

from .arith import vector


@dataclass(frozen=True)
class SectionProperties:
    """Area A [m^2], second moments Ix, Iy [m^4], torsion constant J [m^4]."""
    area: float
    ix: float
    iy: float
    torsion: float


def section_properties(section):
    """:class:`SectionProperties` of a circle or rectangle scenario section."""
    if section.shape == "circle":
        d = section.diameter
        i = math.pi * d**4 / 64.0
        return SectionProperties(math.pi * d**2 / 4.0, i, i, 2.0 * i)
    w, h = section.width, section.height
    ix, iy = w * h**3 / 12.0, h * w**3 / 12.0
    j = ix + iy if section.torsion == "polar" else saint_venant_rectangle(w, h)
    return SectionProperties(w * h, ix, iy, j)


def saint_venant_rectangle(width, height, terms=50):
    """Saint-Venant torsion constant of a solid rectangle [m^4] (series, exact to 1e-12)."""
    a, b = max(width, height), min(width, height)
    n = 2.0 * np.arange(terms) + 1.0
    series = np.sum(np.tanh(n * math.pi * a / (2.0 * b)) / n**5)
    return a * b**3 / 3.0 * (1.0 - 192.0 / math.pi**5 * (b / a) * series)


def stiffness_diagonal(props, youngs, shear):
    """Diagonal of ``K``: ``[E Ix, E Iy, G J, G A, G A, E A]`` (N m^2 and N); the moduli may be
    numbers (a numpy array) or CasADi symbols (a CasADi column)."""
    return vector(youngs * props.ix, youngs * props.iy, shear * props.torsion,
                  shear * props.area, shear * props.area, youngs * props.area)


def outside_point(outline, route, count=400):
    """The body-frame point (3,) of ``route`` farthest outside ``outline`` (``count`` samples),
    or None when the route lies inside (or on) it."""
    points = route.samples(count)
    inside = outline_contains(outline, points[0], points[1])
    return None if np.all(inside) else points[:, np.argmin(inside)]


def outline_contains(outline, x, y, slack=1e-12):
    """True where the body-frame points (x, y) [m] lie inside (or on) the outline."""
    if outline.shape == "circle":
        return np.hypot(x, y) <= outline.diameter / 2.0 * (1 + slack) + slack
    return (np.abs(x) <= outline.width / 2.0 * (1 + slack) + slack) & \
           (np.abs(y) <= outline.height / 2.0 * (1 + slack) + slack)
