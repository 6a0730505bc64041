"""Load a scenario from YAML (or a dict), apply ``--set`` overrides, validate, and report every
problem, one line each: ``FILE:LINE: key.path: what is wrong (did you mean ...?)``."""
import copy
import typing
from pathlib import Path

import pydantic

from ..errors import ScenarioError, flag
from .checks import check_references
from .overrides import apply_overrides
from .schema import Scenario
from .sources import SourceMap, clip, did_you_mean, located, shorten
from .yaml_safe import parse_yaml


def load_scenario(source, overrides=(), allow_code=False):
    """Validated :class:`Scenario` from a YAML path, YAML text or dict, with overrides applied.

    ``overrides`` is a list of ``"dotted.path=value"`` strings or a ``{path: value}`` dict.
    ``allow_code``: a scenario whose ``muscle_types`` name a ``custom`` law runs the Python
    module its ``entry_point`` names; such a scenario is refused (before anything is imported)
    unless this is True (the CLI's ``--allow-code``).
    Raises :class:`ScenarioError` naming file, line and key path of every problem.
    """
    raw, sources = read_raw(source)
    raw = apply_overrides(raw, overrides, sources)
    _anchor_law_folders(raw, sources)
    _anchor_mpc_paths(raw, sources)
    if not allow_code:
        refuse_code(raw, sources)
    scenario = validate(raw, sources)
    scenario._allow_code = bool(allow_code)
    check_steps(scenario)
    return scenario


def refuse_code(raw, sources):
    """ScenarioError, one line per custom law, naming the module and file its entry point would
    import (found without importing it), when the scenario would run Python code."""
    from ..catalogue.custom import describe_entry_point
    types = raw.get("muscle_types")
    problems = []
    for name, config in (types.items() if isinstance(types, dict) else ()):
        if isinstance(config, dict) and config.get("kind") == "custom" and isinstance(config.get("entry_point"), str):
            path = ("muscle_types", name, "entry_point")
            folder = config.get("folder") if isinstance(config.get("folder"), str) else None
            problems.append(f"{located(sources, path, raw)}: this scenario runs Python code: "
                            f"{describe_entry_point(config['entry_point'], folder)}; if you trust it, allow it "
                            f"with {flag('--allow-code', 'allow_code=True')}")
    if problems:
        raise ScenarioError("\n".join(problems))


def check_steps(scenario):
    """Every sequence step's and timeline event's ``set:`` applied in order (cumulatively, as
    ``sequence`` and ``simulate`` apply them) on top of the scenario: each path must name a
    value and the scenario each step gives must be valid. One-line errors say which step, the
    file line and the path, with the closest valid name (as ``--set``)."""
    raw, sources, problems = scenario._raw, scenario._sources, []
    for key, items in (("sequence", scenario.sequence or []), ("timeline", scenario.timeline)):
        current, origins = raw, copy.deepcopy(sources)
        for k, item in enumerate(items):
            name = f"{key}[{item.name}]" if key == "sequence" else f"{key}[{k}] (at {item.at:g} s)"
            label = f"{origins.where((key, k, 'set'))}: {name}: set"
            try:
                after = apply_overrides(current, item.set, origins, label=label)
                validate(after, origins)
            except ScenarioError as exc:       # said; the later steps go on from the step before
                problems.extend(str(exc).splitlines())
                continue
            current = after
    if problems:
        raise ScenarioError("\n".join(problems))


def _anchor_law_folders(raw, sources):
    """A custom law's ``folder`` (where its entry point's module is looked for after the Python
    path) made absolute, relative to the scenario file's folder, which is also its default; so
    the scenario keeps finding its law when it travels as a mapping (study workers, timelines)."""
    types = raw.get("muscle_types")
    if not isinstance(types, dict) or sources.origin.startswith("<"):
        return
    here = Path(sources.origin).resolve().parent
    for config in types.values():
        if isinstance(config, dict) and config.get("kind") == "custom":
            folder = config.get("folder")
            if folder is None or isinstance(folder, str):
                config["folder"] = str(here / folder) if folder else str(here)


def _anchor_mpc_paths(raw, sources):
    """An mpc controller's ``path`` (a CSV file) made absolute, relative to the scenario file's
    folder (as a custom law's ``folder``)."""
    if sources.origin.startswith("<"):
        return
    here = Path(sources.origin).resolve().parent
    for module in raw.get("modules") or []:
        for actuator in (module.get("actuators") or []) if isinstance(module, dict) else []:
            drive = actuator.get("drive") if isinstance(actuator, dict) else None
            settings = drive.get("mpc") if isinstance(drive, dict) else None
            if isinstance(settings, dict) and isinstance(settings.get("path"), str):
                settings["path"] = str(here / settings["path"])


def read_raw(source):
    """Raw mapping and its :class:`SourceMap` from a path, YAML text or dict. A string is a path
    unless it holds a line break or starts with ``{`` (YAML text)."""
    if isinstance(source, dict):
        return copy.deepcopy(source), SourceMap("<dict>")
    if isinstance(source, str) and ("\n" in source or source.lstrip().startswith("{")):
        return _as_mapping(*parse_yaml(source, "<yaml>"))
    if isinstance(source, (str, Path)):
        return _as_mapping(*parse_yaml(_read_file(Path(source)), str(source)))
    raise ScenarioError(f"cannot read a scenario from {type(source).__name__}")


def _read_file(path):
    """The text of a scenario file; one-line errors for a missing file, a directory, a file that
    cannot be read, or one that is not UTF-8 text."""
    name = clip(path)
    try:
        kind = "directory" if path.is_dir() else "file" if path.is_file() else None
        data = path.read_bytes() if kind == "file" else None
    except (OSError, ValueError) as exc:       # permission, a NUL byte, a name too long
        raise ScenarioError(f"{name}: cannot read the scenario file "
                            f"({getattr(exc, 'strerror', None) or exc})") from None
    if kind is None:
        raise ScenarioError(f"{name}: no such scenario file")
    if kind == "directory":
        raise ScenarioError(f"{name}: is a directory, not a scenario file")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise ScenarioError(f"{path}:{line}: not a text (UTF-8) file: byte 0x{data[exc.start]:02x} "
                            f"at offset {exc.start}") from None


def _as_mapping(data, sources):
    if not isinstance(data, dict):
        raise ScenarioError(f"{sources.origin}: a scenario must be a YAML mapping of keys "
                            f"(name, materials, modules, ...), got {type(data).__name__}")
    return data, sources


def validate(raw, sources):
    """Validate a raw mapping; attach the raw data and source map to the result."""
    try:
        scenario = Scenario.model_validate(raw)
    except pydantic.ValidationError as exc:
        raise ScenarioError(_all_errors(exc, raw, sources)) from None
    except RecursionError:
        raise ScenarioError(f"{sources.origin}: the scenario is nested too deeply") from None
    check_references(scenario, raw, sources)
    scenario._raw = raw
    scenario._sources = sources
    return scenario


# ----------------------------------------------------------------------------- errors
#: at most this many problems are listed (then a count of the rest)
MAX_LISTED = 20


def _all_errors(exc, raw, sources):
    """Every problem, one line each; an unknown (misspelt) key first, since it explains a
    missing one next to it."""
    errors = sorted(exc.errors(), key=lambda e: e["type"] != "extra_forbidden")
    lines = []
    for error in errors[:MAX_LISTED]:
        path = _data_path(error["loc"], raw)
        line = f"{located(sources, path, raw)}: {_message(error, path)}"
        if line not in lines:
            lines.append(line)
    if len(errors) > MAX_LISTED:
        lines.append(f"... and {len(errors) - MAX_LISTED} more problems")
    return "\n".join(lines)


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
        return f"unknown key {shorten(key)}{_suggest(key, allowed)}"
    if kind == "missing":
        return f"missing required key {error['loc'][-1]!r}"
    if kind == "union_tag_invalid":
        tag, expected = error["ctx"]["tag"], error["ctx"]["expected_tags"]
        options = [t.strip().strip("'") for t in expected.split(",")]
        return f"{error['ctx']['discriminator'].strip(chr(39))} {shorten(tag)} is not one of {expected}{_suggest(tag, options)}"
    if kind == "union_tag_not_found":
        return f"missing key {error['ctx']['discriminator']}"
    if kind == "literal_error":
        given = error.get("input")
        options = [o.strip().strip("'") for o in error["ctx"]["expected"].replace(" or ", ",").split(",")]
        return f"{shorten(given)} is not allowed: expected {error['ctx']['expected']}{_suggest(str(given), options)}"
    if kind == "value_error":
        return msg.removeprefix("Value error, ")
    if kind == "finite_number":
        return "expected a finite number"
    return f"{msg[0].lower()}{msg[1:]} (got {shorten(error.get('input'))})"


def _suggest(word, options):
    return did_you_mean(word, options, none="", listing="; valid: ")


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


