"""Bad input of every kind gives one ScenarioError line naming the key path (and line)."""
import pytest

from tca_casadi import ScenarioError, Simulation, load_scenario

BENDING = "bending_module.yaml"


def load(scenarios, *overrides):
    return load_scenario(scenarios / BENDING, list(overrides))


def test_shipped_scenario_loads_in_si(scenarios):
    scenario = load(scenarios)
    module = scenario.modules[0]
    assert module.length == pytest.approx(0.045, rel=1e-15)
    assert module.actuators[1].route.angle == pytest.approx(2.0943951023931953, rel=1e-15)
    assert scenario.materials["ecoflex30"].shear() == pytest.approx(0.125e6 / 3, rel=1e-15)
    assert scenario.base.orientation.as_quaternion() == pytest.approx((0, 1, 0, 0), abs=1e-15)


def test_override_changes_value(scenarios):
    assert load(scenarios, "bending.tca2.temperature=110 degC").modules[0].actuators[1].temperature == 110


@pytest.mark.parametrize("override, fragments", [
    ("bending.lenght=3", ["modules[bending].lenght", "unknown key 'lenght'", "did you mean 'length'"]),
    ("bending.length=-3 mm", ["modules[bending].length", "greater than 0"]),
    ("bending.length=0", ["modules[bending].length", "greater than 0"]),
    ("bending.tca2.route.kind=strait", ["route", "did you mean 'straight'"]),
    ("bending.tca2.route.radius=4 kg", ["route.radius", "is not a length"]),
    ("bending.tca2.route.radius=4 parsecz", ["route.radius", "unknown unit"]),
    ("bending.material=ecoflex", ["modules[bending].material", "did you mean 'ecoflex30'"]),
    ("bending.tca1.type=nylo", ["actuators[tca1].type", "unknown TCA type", "did you mean 'nylon'"]),
    ("bendng.length=3", ["'bendng'", "did you mean 'bending'"]),
    ("bending.tca2.temperature=.nan", ["temperature", "finite"]),
    ("bending.tca2.temperature=.inf", ["temperature", "finite"]),
    ("gravity=[1, 2]", ["gravity", "expected a list of 3 values"]),
    ("materials.ecoflex30.youngs_modulus=-1 MPa", ["youngs_modulus", "greater than 0"]),
    ("tca_types.nylon.coil_radius=0.3 mm", ["tca_types.nylon", "must be larger than fiber_radius"]),
    ("bending.tca1.route.radius=6 mm", ["actuators[tca1].route", "outside the body"]),
    ("bending.tca1.route.span=[0, 0.05]", ["actuators[tca1].route", "span"]),
    ("bending.cross_section.shape=oval", ["cross_section", "'oval'"]),
    ("solver.degree=20", ["solver.degree"]),
    ("base.orientation.axis=[0, 0, 0]", ["base.orientation", "axis must not be zero"]),
])
def test_bad_override_names_the_key(scenarios, override, fragments):
    with pytest.raises(ScenarioError) as info:
        Simulation.from_file(scenarios / BENDING, [override])
    message = str(info.value)
    assert "\n" not in message
    for fragment in fragments:
        assert fragment in message, message


def test_error_gives_file_and_line(tmp_path, scenarios):
    text = (scenarios / BENDING).read_text().replace("length: \"45 mm\"", "lenght: \"45 mm\"")
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    line = next(i for i, row in enumerate(text.splitlines(), 1) if "lenght" in row)
    assert f"bad.yaml:{line}:" in str(info.value)
    assert "did you mean 'length'" in str(info.value)


@pytest.mark.parametrize("text, fragment", [
    ("name: [unclosed", "malformed YAML"),
    ("- just\n- a list\n", "must be a YAML mapping"),
    ("name: x\nname: y\nmaterials: {}\nmodules: []\n", "duplicate key"),
    ("name: x\nmaterials: {}\nmodules: []\n", "modules"),
    ("name: x\nmodules: []\n", "missing required key 'materials'"),
])
def test_malformed_yaml(tmp_path, text, fragment):
    path = tmp_path / "s.yaml"
    path.write_text(text)
    with pytest.raises(ScenarioError, match=fragment):
        load_scenario(path)


def test_missing_file(tmp_path):
    with pytest.raises(ScenarioError, match="no such scenario file"):
        load_scenario(tmp_path / "nope.yaml")


def test_unknown_load_module(scenarios):
    with pytest.raises(ScenarioError, match="unknown module 'bendin'.*did you mean 'bending'"):
        load(scenarios, "loads=[{name: w, kind: mass, module: bendin, mass: 0.001}]")


def test_envelope_hint_when_outside_section(scenarios):
    with pytest.raises(ScenarioError, match="outside the body.*cross_section.envelope"):
        Simulation.from_file(scenarios / BENDING, ["bending.cross_section={shape: circle, diameter: 4.5 mm}"])
