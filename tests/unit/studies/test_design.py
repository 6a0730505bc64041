"""Study designs: what each gives, in which order, and the first-order sensitivity estimator."""
import numpy as np
import pytest
from numpy.testing import assert_allclose

from tca_casadi.errors import ScenarioError
from tca_casadi.studies.batch.design import Axis, build_design, nearest_neighbour_order, snake_order
from tca_casadi.studies.batch.result import first_order_index


def test_grid_is_the_full_product_in_snake_order():
    axes = [Axis("a", "range", 0.0, 1.0, points=3), Axis("b", "range", 10.0, 20.0, points=4),
            Axis("c", "range", -1.0, 1.0, points=2)]
    design = build_design(axes)
    assert design.size == 24
    assert sorted(design.ids.tolist()) == list(range(24))
    expected = {(a, b, c) for a in (0.0, 0.5, 1.0) for b in np.linspace(10, 20, 4) for c in (-1.0, 1.0)}
    assert {tuple(np.round(row, 12)) for row in design.values} == {tuple(np.round(e, 12)) for e in expected}
    steps = np.abs(np.diff(design.values, axis=0)) / np.array([0.5, 10 / 3, 2.0])
    assert np.all(np.sum(steps > 1e-12, axis=1) == 1)           # one coordinate moves at a time ...
    assert_allclose(steps.max(axis=1), 1.0, rtol=0, atol=1e-12)  # ... by one grid step


def test_snake_order_is_a_permutation_with_unit_moves():
    order = snake_order([4, 5])
    assert sorted(order.tolist()) == list(range(20))
    cells = np.array(np.unravel_index(order, (4, 5))).T
    assert np.all(np.abs(np.diff(cells, axis=0)).sum(axis=1) == 1)


@pytest.mark.parametrize("kind", ["sobol", "latin", "random"])
def test_sampling_designs_fill_the_box_and_are_seeded(kind):
    axes = [Axis("a", "range", 25.0, 125.0), Axis("b", "range", -1.0, 1.0)]
    first, again = build_design(axes, kind, 200, seed=3), build_design(axes, kind, 200, seed=3)
    other = build_design(axes, kind, 200, seed=4)
    assert first.size == 200
    assert np.array_equal(first.values, again.values)
    assert not np.array_equal(np.sort(first.values, axis=0), np.sort(other.values, axis=0))
    assert first.values[:, 0].min() >= 25.0 and first.values[:, 0].max() <= 125.0
    assert_allclose(first.values[:, 0].mean(), 75.0, rtol=0, atol=6.0)     # 3 sigma of a random mean
    assert_allclose(first.values[:, 1].mean(), 0.0, rtol=0, atol=0.12)


def test_normal_axis_gives_its_moments():
    design = build_design([Axis("E", "normal", mean=0.125e6, std=0.0125e6)], "sobol", 4096, seed=1)
    assert_allclose(design.values.mean(), 0.125e6, rtol=2e-3)
    assert_allclose(design.values.std(ddof=1), 0.0125e6, rtol=1e-2)


def test_nearest_neighbour_order_is_a_short_tour():
    points = np.random.default_rng(0).random((500, 2))
    order = nearest_neighbour_order(points)
    assert sorted(order.tolist()) == list(range(500))
    tour = np.linalg.norm(np.diff(points[order], axis=0), axis=1).sum()
    shuffled = np.linalg.norm(np.diff(points, axis=0), axis=1).sum()
    assert tour < 0.25 * shuffled          # a random order is about 0.52 per step; greedy ~0.05


def test_listed_values_cross_the_drawn_samples():
    design = build_design([Axis("a", "range", 0.0, 1.0, points=3), Axis("b", "values", values=[1.0, 2.0])])
    assert design.size == 6
    assert {tuple(r) for r in design.values} == {(a, b) for a in (0.0, 0.5, 1.0) for b in (1.0, 2.0)}


@pytest.mark.parametrize("make", [
    lambda: Axis("a", "range", 1.0, 1.0),
    lambda: Axis("a", "range", 2.0, 1.0),
    lambda: Axis("a", "normal", mean=1.0, std=0.0),
    lambda: Axis("a", "normal", mean=1.0, std=-1.0),
    lambda: Axis("a", "range", 0.0, 1.0, points=0),
    lambda: Axis("a", "values", values=[]),
    lambda: build_design([Axis("a", "range", 0.0, 1.0)], "grid", -1),
    lambda: build_design([Axis("a", "normal", mean=0.0, std=1.0)], "grid"),
    lambda: build_design([Axis("a", "range", 0.0, 1.0)], "lattice"),
    lambda: build_design([]),
])
def test_bad_designs_are_one_line_errors(make):
    with pytest.raises(ScenarioError) as error:
        make()
    assert "\n" not in str(error.value)


def test_first_order_indices_of_the_ishigami_function():
    """Ishigami (a = 7, b = 0.1) on [-pi, pi]^3: S1 = 0.3139, S2 = 0.4424, S3 = 0 (analytic)."""
    x = np.random.default_rng(0).uniform(-np.pi, np.pi, (20000, 3))
    y = np.sin(x[:, 0]) + 7 * np.sin(x[:, 1]) ** 2 + 0.1 * x[:, 2] ** 4 * np.sin(x[:, 0])
    indices = [first_order_index(x[:, j], y) for j in range(3)]
    assert_allclose(indices, [0.3139, 0.4424, 0.0], rtol=0, atol=0.02)


def test_first_order_indices_on_a_grid_use_its_levels():
    """y = x1 + 2 x2 on a 7 x 7 grid: S1 = 1/5, S2 = 4/5 exactly (each level averages the other
    input exactly, so no bias correction)."""
    levels = np.linspace(-1, 1, 7)
    x1, x2 = (a.ravel() for a in np.meshgrid(levels, levels, indexing="ij"))
    y = x1 + 2 * x2
    assert_allclose(first_order_index(x1, y, corrected=False), 0.2, rtol=0, atol=1e-12)
    assert_allclose(first_order_index(x2, y, corrected=False), 0.8, rtol=0, atol=1e-12)


def _result_with_tips(tips):
    import pandas as pd
    from tca_casadi.studies.batch.result import StudyResult
    frame = pd.DataFrame({"sample": range(len(tips)), "converged": True, "tip_x [m]": tips[:, 0],
                          "tip_y [m]": tips[:, 1], "tip_z [m]": tips[:, 2]})
    return StudyResult(frame, {}, [])


def test_workspace_hull_of_a_box_a_square_and_a_segment():
    rng = np.random.default_rng(0)
    corners = np.array([[x, y, z] for x in (0, 2e-3) for y in (0, 1e-3) for z in (0, 3e-3)], float)
    inside = rng.random((50, 3)) * [2e-3, 1e-3, 3e-3]
    box = _result_with_tips(np.vstack([corners, inside])).workspace_hull()
    assert box["dimension"] == 3 and len(box["vertices"]) == 8
    assert_allclose(box["volume [m^3]"], 6e-9, rtol=1e-12)
    assert_allclose(box["area [m^2]"], 2 * (2e-6 + 6e-6 + 3e-6), rtol=1e-12)
    tilt = np.array([[1, 0, 0], [0, np.cos(0.3), -np.sin(0.3)], [0, np.sin(0.3), np.cos(0.3)]])
    square = np.array([[x, y, 0] for x in (0, 1e-3) for y in (0, 1e-3)] + [[5e-4, 5e-4, 0]]) @ tilt.T
    flat = _result_with_tips(square).workspace_hull()
    assert flat["dimension"] == 2 and flat["volume [m^3]"] == 0.0
    assert_allclose(flat["area [m^2]"], 1e-6, rtol=1e-12)
    line = _result_with_tips(np.outer(np.linspace(0, 1, 5), [3e-3, 4e-3, 0])).workspace_hull()
    assert line["dimension"] == 1
    assert_allclose(line["length [m]"], 5e-3, rtol=1e-12)
