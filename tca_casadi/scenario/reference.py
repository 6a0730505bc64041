"""The scenario format as Markdown, generated from the schema (:mod:`.schema`): every section
(model), every key with its type, unit, default, allowed range and the description written beside
it in the schema (``#:`` comments). The documentation site builds its scenario reference from
this (``docs/hooks.py``), so the page cannot drift from what the loader accepts.
"""
import inspect
import re
import types
import typing

from annotated_types import Ge, Gt, Le, Lt, MaxLen, MinLen
from pydantic import BaseModel
from pydantic.fields import FieldInfo
from pydantic_core import PydanticUndefined

from ..units import UNIT_OF


def scenario_reference():
    """Markdown (str): one section per model reachable from :class:`~.schema.Scenario`, in the
    order met, each a table ``key | type | unit | default | range | description``."""
    from .schema import Scenario
    order, queue = [], [Scenario]
    while queue:
        model = queue.pop(0)
        if model in order:
            continue
        order.append(model)
        for field in model.model_fields.values():
            queue.extend(m for m in _models_in(field.annotation) if m not in order)
    return "\n".join(_section(model) for model in order)


def _section(model):
    """One model's heading, docstring and table."""
    doc = inspect.cleandoc(model.__doc__ or "")
    lines = [f"### `{model.__name__}` {{#{_anchor(model)}}}", "", _plain(doc), "",
             "| key | type | unit | default | range | description |", "|---|---|---|---|---|---|"]
    notes = field_comments(model)
    for name, field in model.model_fields.items():
        lines.append("| " + " | ".join([f"`{name}`", _type_text(field.annotation), _unit(field) or "",
                                        _default(field), _range(field), _cell(notes.get(name, ""))]) + " |")
    return "\n".join(lines) + "\n"


def field_comments(model):
    """``{field: text}`` of the ``#:`` comments written above each field in the model's source."""
    try:
        source = inspect.getsource(model)
    except (OSError, TypeError):
        return {}
    out, pending = {}, []
    for line in source.splitlines()[1:]:
        stripped = line.strip()
        if stripped.startswith("#:"):
            pending.append(stripped[2:].strip())
            continue
        match = re.match(r"([A-Za-z_][A-Za-z0-9_]*)\s*:", stripped)
        if match and pending:
            out[match.group(1)] = " ".join(pending)
        pending = [] if not stripped.startswith("#") else pending
    return out


# ----------------------------------------------------------------------------- pieces
def _models_in(annotation):
    """The pydantic models inside a type annotation (unions, lists, dicts, Annotated)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    return [m for arg in typing.get_args(annotation) for m in _models_in(arg)]


def _type_text(annotation):
    """A short readable type: models as links, literals as their values."""
    origin, args = typing.get_origin(annotation), typing.get_args(annotation)
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return f"[`{annotation.__name__}`](#{_anchor(annotation)})"
    if origin is typing.Annotated:
        return _type_text(args[0])
    if origin is typing.Literal:
        return " or ".join(f"`{value!r}`".replace("'", '"') for value in args)
    if origin in (typing.Union, types.UnionType):
        shown = [_type_text(a) for a in args if a is not type(None)]
        text = " or ".join(dict.fromkeys(shown))
        return text + (" (optional)" if type(None) in args else "")
    if origin in (list, tuple):
        if origin is tuple and args and args[-1] is not Ellipsis:
            return f"list of {len(args)} {_type_text(args[0])}"
        return f"list of {_type_text(args[0])}" if args else "list"
    if origin is dict:
        return f"mapping name -> {_type_text(args[1])}"
    return {float: "number", int: "integer", str: "text", bool: "true/false"}.get(annotation, str(annotation))


def _unit(field):
    """The unit of a quantity (plain numbers are taken in it; strings may carry any unit of its kind)."""
    for item in _metadata(field):
        kind = getattr(getattr(item, "func", None), "kind", None)
        if kind is not None:
            unit = UNIT_OF.get(kind, "")
            return "" if unit == "-" else unit
    return None


def _metadata(field):
    """Every metadata item of a field and of the Annotated types inside its annotation."""
    items = list(field.metadata)

    def walk(annotation):
        if typing.get_origin(annotation) is typing.Annotated:
            items.extend(annotation.__metadata__)
        for arg in typing.get_args(annotation):
            walk(arg)
    walk(field.annotation)
    out = []
    for item in items:                 # a Field(...) inside an Annotated keeps its bounds as metadata
        out.extend(item.metadata if isinstance(item, FieldInfo) else [item])
    return out


def _range(field):
    """Bounds from ``Field(gt=..., ge=..., ...)`` and lengths."""
    parts = []
    for item in _metadata(field):
        for cls, symbol, attr in ((Gt, ">", "gt"), (Ge, ">=", "ge"), (Lt, "<", "lt"), (Le, "<=", "le"),
                                  (MinLen, "at least", "min_length"), (MaxLen, "at most", "max_length")):
            if isinstance(item, cls):
                value = getattr(item, attr)
                parts.append(f"{symbol} {value:g}" if isinstance(value, float) else f"{symbol} {value}")
    return ", ".join(dict.fromkeys(parts))


def _default(field):
    if field.is_required():
        return "**required**"
    if field.default_factory is not None:
        value = field.default_factory()
        if isinstance(value, BaseModel):
            return "its defaults"
        return "none" if value in ([], {}, ()) else f"`{value!r}`"
    value = field.default
    if value is PydanticUndefined or value is None:
        return "none"
    if isinstance(value, tuple):
        return "`[" + ", ".join(f"{v:g}" if isinstance(v, float) else str(v) for v in value) + "]`"
    if isinstance(value, float):
        return f"`{value:g}`"
    return f"`{value!r}`".replace("'", '"')


def _anchor(model):
    return "model-" + model.__name__.lower()


def _plain(text):
    """A docstring as Markdown: reST double back-quotes to single, roles to their text."""
    text = re.sub(r":[a-z]+:`~?([^`]+)`", r"`\1`", text)
    return text.replace("``", "`")


def _cell(text):
    """Text fit for a table cell."""
    return _plain(text).replace("|", "\\|")


__all__ = ["field_comments", "scenario_reference"]
