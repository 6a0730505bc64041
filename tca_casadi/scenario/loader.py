"""Load a scenario from YAML (or a dict), apply ``--set`` overrides, validate, and report the
first problem as one line: ``FILE:LINE: key.path: what is wrong (did you mean ...?)``."""
import copy
import difflib
import typing
from pathlib import Path

import pydantic
import yaml

from ..errors import ScenarioError
from .checks import check_references
from .overrides import apply_overrides
from .schema import Scenario


class SourceMap:
    """Where each key path of a scenario came from: a file line, or a ``--set`` override."""

    def __init__(self, origin="<scenario>", lines=None):
        self.origin = origin
        self.lines = dict(lines or {})
        self.overridden = {}

    def where(self, path):
        """``FILE:LINE`` (or ``--set PATH=VALUE``) of the longest known prefix of ``path``."""
        path = tuple(path)
        below = [label for overridden, label in self.overridden.items()
                 if overridden[: len(path)] == path]
        if below and path not in self.lines:
            return below[0]
        suffix = f" (after {', '.join(below)})" if below else ""
        for cut in range(len(path), -1, -1):
            if path[:cut] in self.overridden:
                return self.overridden[path[:cut]]
            if path[:cut] in self.lines:
                return f"{self.origin}:{self.lines[path[:cut]]}{suffix}"
        return self.origin


def load_scenario(source, overrides=()):
    """Validated :class:`Scenario` from a YAML path, YAML text or dict, with overrides applied.

    ``overrides`` is a list of ``"dotted.path=value"`` strings or a ``{path: value}`` dict.
    Raises :class:`ScenarioError` with one line naming file, line and key path.
    """
    raw, sources = read_raw(source)
    raw = apply_overrides(raw, overrides, sources)
    scenario = validate(raw, sources)
    return scenario


def read_raw(source):
    """Raw mapping and its :class:`SourceMap` from a path, YAML text or dict."""
    if isinstance(source, dict):
        return copy.deepcopy(source), SourceMap("<dict>")
    if isinstance(source, Path) or (isinstance(source, str) and "\n" not in source
                                    and source.endswith((".yaml", ".yml"))):
        path = Path(source)
        if not path.is_file():
            raise ScenarioError(f"{path}: no such scenario file")
        return _parse_yaml(path.read_text(encoding="utf-8"), str(path))
    if isinstance(source, str):
        return _parse_yaml(source, "<yaml>")
    raise ScenarioError(f"cannot read a scenario from {type(source).__name__}")


def validate(raw, sources):
    """Validate a raw mapping; attach the raw data and source map to the result."""
    try:
        scenario = Scenario.model_validate(raw)
    except pydantic.ValidationError as exc:
        raise ScenarioError(_first_error(exc, raw, sources)) from None
    check_references(scenario, raw, sources)
    scenario._raw = raw
    scenario._sources = sources
    return scenario


# ----------------------------------------------------------------------------- YAML
def _parse_yaml(text, origin):
    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        line = f":{mark.line + 1}" if mark is not None else ""
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise ScenarioError(f"{origin}{line}: malformed YAML: {problem}") from None
    if not isinstance(data, dict):
        raise ScenarioError(f"{origin}: a scenario must be a YAML mapping of keys "
                            f"(name, materials, modules, ...), got {type(data).__name__}")
    lines = {}
    _collect_lines(root, (), lines, origin)
    return data, SourceMap(origin, lines)


def _collect_lines(node, path, lines, origin):
    lines.setdefault(path, node.start_mark.line + 1)
    if isinstance(node, yaml.MappingNode):
        seen = set()
        for key_node, value_node in node.value:
            key = key_node.value
            if key in seen:
                raise ScenarioError(f"{origin}:{key_node.start_mark.line + 1}: "
                                    f"{_format_path(path + (key,), None)}: duplicate key")
            seen.add(key)
            lines[path + (key,)] = key_node.start_mark.line + 1
            _collect_lines(value_node, path + (key,), lines, origin)
    elif isinstance(node, yaml.SequenceNode):
        for index, item in enumerate(node.value):
            _collect_lines(item, path + (index,), lines, origin)


# ----------------------------------------------------------------------------- errors
def _first_error(exc, raw, sources):
    # an unknown (misspelt) key explains a missing one next to it: report it first
    errors = sorted(exc.errors(), key=lambda e: e["type"] != "extra_forbidden")
    error = errors[0]
    path = _data_path(error["loc"], raw)
    message = _message(error, path)
    more = f" (and {len(errors) - 1} more problem{'s' * (len(errors) > 2)})" if len(errors) > 1 else ""
    return f"{sources.where(path)}: {_format_path(path, raw)}: {message}{more}"


def _data_path(loc, raw):
    """Drop pydantic's union tags from ``loc`` so that it indexes the raw data."""
    path, node = [], raw
    for part in loc:
        if isinstance(node, dict) and part in node:
            path.append(part)
            node = node[part]
        elif isinstance(node, list) and isinstance(part, int) and part < len(node):
            path.append(part)
            node = node[part]
        elif isinstance(node, (dict, list)):
            if isinstance(part, str) and part in _model_fields_or_empty(loc, path):
                path.append(part)  # a missing key: name it
                node = None
            # otherwise a union tag: skip it
        else:
            break
    return tuple(path)


def _model_fields_or_empty(loc, path):
    model = _model_at(tuple(loc)[: len(path) + 2])
    return set(model.model_fields) if model is not None else set()


def _message(error, path):
    kind, msg = error["type"], error["msg"]
    if kind == "extra_forbidden":
        key = path[-1] if path else error["loc"][-1]
        allowed = _allowed_keys(error["loc"][:-1])
        return f"unknown key {key!r}{_suggest(key, allowed)}"
    if kind == "missing":
        return f"missing required key {error['loc'][-1]!r}"
    if kind == "union_tag_invalid":
        tag, expected = error["ctx"]["tag"], error["ctx"]["expected_tags"]
        options = [t.strip().strip("'") for t in expected.split(",")]
        return f"{error['ctx']['discriminator'].strip(chr(39))} {tag!r} is not one of {expected}{_suggest(tag, options)}"
    if kind == "union_tag_not_found":
        return f"missing key {error['ctx']['discriminator']}"
    if kind == "literal_error":
        given = error.get("input")
        options = [o.strip().strip("'") for o in error["ctx"]["expected"].replace(" or ", ",").split(",")]
        return f"{given!r} is not allowed: expected {error['ctx']['expected']}{_suggest(str(given), options)}"
    if kind == "value_error":
        return msg.removeprefix("Value error, ")
    if kind == "finite_number":
        return "expected a finite number"
    return f"{msg[0].lower()}{msg[1:]} (got {error.get('input')!r})"


def _suggest(word, options):
    close = difflib.get_close_matches(str(word), [str(o) for o in options], n=1, cutoff=0.5)
    if close:
        return f" (did you mean {close[0]!r}?)"
    return f"; valid: {', '.join(sorted(map(str, options)))}" if options else ""


def _allowed_keys(loc):
    model = _model_at(tuple(loc))
    return list(model.model_fields) if model is not None else []


def _model_at(loc):
    """The pydantic model class that validates the mapping at ``loc`` (a pydantic loc)."""
    current = Scenario
    for part in loc:
        current = _step(current, part)
        if current is None:
            return None
    current = _unwrap(current)
    return current if isinstance(current, type) and issubclass(current, pydantic.BaseModel) else None


def _step(annotation, part):
    annotation = _unwrap(annotation)
    if isinstance(annotation, type) and issubclass(annotation, pydantic.BaseModel):
        field = annotation.model_fields.get(part)
        return field.annotation if field is not None else None
    origin = typing.get_origin(annotation)
    args = typing.get_args(annotation)
    if origin is list:
        return args[0]
    if origin is dict:
        return args[1]
    if origin is typing.Union:
        for member in args:
            member = _unwrap(member)
            fields = getattr(member, "model_fields", {})
            for key in ("kind", "shape"):
                literal = fields.get(key)
                if literal is not None and part in typing.get_args(literal.annotation):
                    return member
    return None


def _unwrap(annotation):
    while True:
        origin = typing.get_origin(annotation)
        if origin is typing.Annotated:
            annotation = typing.get_args(annotation)[0]
        elif origin is typing.Union and type(None) in typing.get_args(annotation):
            rest = [a for a in typing.get_args(annotation) if a is not type(None)]
            if len(rest) != 1:
                return annotation
            annotation = rest[0]
        else:
            return annotation


def _format_path(path, raw):
    """``modules[bending].actuators[tca2].route.radius``: list items by name where they have one."""
    text, node = "", raw
    for part in path:
        if isinstance(part, int):
            item = node[part] if isinstance(node, list) and part < len(node) else None
            name = item.get("name") if isinstance(item, dict) else None
            text += f"[{name}]" if isinstance(name, str) else f"[{part}]"
            node = item
        else:
            text += f".{part}" if text else str(part)
            node = node.get(part) if isinstance(node, dict) else None
    return text or "(top level)"


format_path = _format_path
