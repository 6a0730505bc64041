"""Study parameters (studies/parameters.py): scalar paths into the parameter vector, components
and magnitudes of vectors, units, and the errors that name what is wrong."""
import numpy as np
import pytest
from analytic import beam_scenario
from numpy.testing import assert_allclose

from tca_casadi import Simulation
from tca_casadi.errors import ScenarioError
from tca_casadi.studies.parameters import check_range, resolve_parameter, resolve_parameters


@pytest.fixture(scope="module")
def beam():
    return Simulation.from_file(beam_scenario(loads=[{"name": "tip", "kind": "point", "module": "rod", "at": "end",
                                                      "force": [3e-3, 4e-3, 0.0], "frame": "global"}]))


def test_a_component_moves_only_its_entry(beam):
    p = resolve_parameter(beam.robot, beam.params, "tip.force.y")
    assert p.value(beam.params) == 4e-3 and p.unit == "N"
    moved = p.with_value(beam.params, 0.25)
    changed = np.flatnonzero(moved != beam.params)
    assert changed.tolist() == [beam.robot.layout["tip.force"].start + 1] and moved[changed[0]] == 0.25
    assert_allclose(p.vector(beam.params.size)[beam.robot.layout["tip.force"]], [0, 1, 0], rtol=0, atol=0)


def test_a_magnitude_scales_the_vector_along_itself(beam):
    p = resolve_parameter(beam.robot, beam.params, "tip.force.magnitude")
    assert_allclose(p.value(beam.params), 5e-3, rtol=1e-15)
    doubled = p.with_value(beam.params, 1e-2)[beam.robot.layout["tip.force"]]
    assert_allclose(doubled, [6e-3, 8e-3, 0.0], rtol=1e-14, atol=0)


def test_values_with_units_and_the_errors_name_the_path(beam):
    modulus = resolve_parameter(beam.robot, beam.params, "materials.m.youngs_modulus")
    assert modulus.to_si("2 MPa") == 2e6 and modulus.describe(2e6) == "materials.m.youngs_modulus = 2e+06 Pa"
    with pytest.raises(ScenarioError, match=r"value for materials.m.youngs_modulus: "):
        modulus.to_si("3 mm")
    with pytest.raises(ScenarioError, match=r"'tip.force' is a vector of 3: name one component"):
        resolve_parameter(beam.robot, beam.params, "tip.force")
    with pytest.raises(ScenarioError, match=r"'tip.forc' is not a study parameter.*tip.force"):
        resolve_parameter(beam.robot, beam.params, "tip.forc")
    with pytest.raises(ScenarioError, match=r"'tip.force\[1\]' and 'tip.force.y' are the same parameter"):
        resolve_parameters(beam.robot, beam.params, ["tip.force.y", "tip.force[1]"])
    with pytest.raises(ScenarioError, match=r"materials.m.youngs_modulus = -1 Pa: module rod: E = -1 Pa"):
        check_range(beam.robot, modulus, 1e6, -1.0, params=beam.params)
