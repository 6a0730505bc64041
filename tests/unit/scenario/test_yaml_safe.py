"""The bounded YAML reader: what it refuses and what it keeps."""
import pytest

from tca_casadi.errors import ScenarioError
from tca_casadi.scenario.yaml_safe import MAX_DEPTH, parse_value, parse_yaml


def test_lines_of_every_key_are_recorded():
    data, sources = parse_yaml("a: 1\nb:\n  c: [1, 2]\n", "f.yaml")
    assert data == {"a": 1, "b": {"c": [1, 2]}}
    assert sources.lines[("b", "c")] == 3 and sources.where(("b", "c", 1)) == "f.yaml:3"


def test_shared_aliases_within_the_bound_are_read():
    data, _ = parse_yaml("a: &x [1, 2]\nb: *x\n", "f.yaml")
    assert data["b"] == [1, 2]


@pytest.mark.parametrize("text, fragment", [
    ("a: " + "[" * (MAX_DEPTH + 2) + "]" * (MAX_DEPTH + 2), "levels deep"),
    ("a: &x [1, *x]", "recursive"),
    ("a: \x1b", "malformed YAML"),
    ("a: b: c", "malformed YAML"),
    ("a: 1\na: 2", "duplicate key"),
    ("x" * (2 << 20), "larger than 1 MiB")])
def test_refused(text, fragment):
    with pytest.raises(ScenarioError, match=fragment):
        parse_yaml(text, "f.yaml")


def test_a_set_value_names_the_override_not_a_line():
    with pytest.raises(ScenarioError) as info:
        parse_value("[1,", "--set a.b")
    assert str(info.value).startswith("--set a.b: malformed YAML")
