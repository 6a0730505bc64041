"""Dotted-path overrides: ``bending.tca2.temperature=100``, ``payload.force=[0,0,-0.02]``,
``base.position=[0,0,0.1]``, ``solver.intervals=32``.

A path's first part is a top-level key, a module name or a load name; inside a module, an
actuator name. Values are read as YAML (so ``100``, ``"45 mm"`` and ``[0, 0, 1]`` all work).
"""
import copy
import difflib

from ..errors import ScenarioError, flag
from .checks import RESERVED, closest
from .schema import Module
from .sources import clip, shorten
from .yaml_safe import parse_value


def parse_override(text):
    """``"a.b=1"`` -> ``("a.b", 1)``."""
    if "=" not in text:
        raise ScenarioError(f"{flag('--set')} {clip(text)}: expected PATH=VALUE, e.g. bending.tca2.temperature=100")
    path, value = text.split("=", 1)
    if not path.strip():
        raise ScenarioError(f"{flag('--set')} {clip(text)}: empty path")
    parsed = parse_value(value, f"{flag('--set')} {clip(path.strip())}") if value.strip() else None
    return path.strip(), parsed


def apply_overrides(raw, overrides, sources=None, label=None):
    """A copy of ``raw`` with every override applied; records their origin in ``sources`` as
    ``LABEL PATH`` (``label``: where the overrides come from, e.g. a timeline event; None: the
    user's own, ``--set`` on the command line)."""
    items = overrides.items() if isinstance(overrides, dict) else [parse_override(o) for o in overrides]
    raw = copy.deepcopy(raw)
    for path, value in items:
        try:
            key_path = resolve(raw, path)
        except ScenarioError as exc:
            if label is None:
                raise
            raise ScenarioError(f"{label} {without_set(str(exc))}") from None
        _assign(raw, key_path, value)
        if sources is not None:             # it replaces any earlier override below it
            for earlier in [k for k in sources.overridden if k[:len(key_path)] == key_path]:
                del sources.overridden[earlier]
            sources.overridden[key_path] = f"{label or flag('--set')} {path}"
    return raw


def without_set(message):
    """An override's error message without its leading ``--set`` (or ``set``): for overrides
    that are not the user's own (a timeline event's, a sequence step's)."""
    return message.removeprefix(f"{flag('--set')} ")


def resolve(raw, dotted):
    """Raw-data key path (tuple of keys and list indices) addressed by a dotted path."""
    parts = dotted.split(".")
    head, rest = parts[0], parts[1:]
    if head in RESERVED or not isinstance(raw, dict):
        return _walk(raw, (head,), rest, dotted)
    for list_key in ("modules", "loads", "objects"):
        for index, item in enumerate(raw.get(list_key) or []):
            if isinstance(item, dict) and item.get("name") == head:
                path = (list_key, index)
                if list_key == "modules" and rest:
                    actuator = _named(item.get("actuators"), rest[0])
                    if actuator is not None:
                        return _walk(raw, path + ("actuators", actuator), rest[1:], dotted)
                    names = [a.get("name") for a in item.get("actuators") or [] if isinstance(a, dict)]
                    if rest[0] not in Module.model_fields and not _close(rest[0], Module.model_fields):
                        raise ScenarioError(
                            f"{flag('--set')} {clip(dotted)}: module {head!r} has no actuator or key "
                            f"{shorten(rest[0])}{closest(rest[0], names + list(Module.model_fields))}")
                return _walk(raw, path, rest, dotted)
    names = [i.get("name") for k in ("modules", "loads", "objects") for i in (raw.get(k) or [])
             if isinstance(i, dict) and isinstance(i.get("name"), str)]
    raise ScenarioError(f"{flag('--set')} {clip(dotted)}: {shorten(head)} is not a top-level key, module, load or object"
                        f"{closest(head, list(RESERVED) + names)}")


def _close(word, options):
    return bool(difflib.get_close_matches(word, list(options), n=1, cutoff=0.75))


def _named(items, name):
    for index, item in enumerate(items or []):
        if isinstance(item, dict) and item.get("name") == name:
            return index
    return None


def _walk(raw, path, rest, dotted):
    node = raw
    for key in path:
        if isinstance(node, dict):
            node = node.get(key)
        elif isinstance(node, list) and isinstance(key, int) and key < len(node):
            node = node[key]
        else:
            node = None
    for part in rest:
        if isinstance(node, list):
            index = _named(node, part)
            if index is None and part.isdigit() and int(part) < len(node):
                index = int(part)
            if index is None:
                names = [i.get("name") for i in node if isinstance(i, dict)]
                raise ScenarioError(f"{flag('--set')} {clip(dotted)}: no item {shorten(part)}{closest(part, names)}")
            path, node = path + (index,), node[index]
        elif isinstance(node, dict) or node is None:
            path, node = path + (part,), (node or {}).get(part)
        else:
            raise ScenarioError(f"{flag('--set')} {clip(dotted)}: cannot go inside the value at {shorten(part)}")
    return path


def _assign(raw, path, value):
    node = raw
    for key in path[:-1]:
        if isinstance(node, dict):
            node = node.setdefault(key, {})
        else:
            node = node[key]
    if isinstance(node, dict):
        node[path[-1]] = value
    elif isinstance(node, list) and isinstance(path[-1], int):
        node[path[-1]] = value
    else:
        raise ScenarioError(f"{flag('--set')} {'.'.join(map(str, path))}: not a mapping")
