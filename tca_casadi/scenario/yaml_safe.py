"""YAML read with bounds, so that a hostile or broken file is refused fast with one line:
at most ``MAX_BYTES`` of text, ``MAX_NODES`` nodes once aliases are expanded (a "billion
laughs" file is refused before anything is built), ``MAX_DEPTH`` levels of nesting; only the
safe tags (``!!python/...`` is refused). Every key path's line is recorded for messages."""
import yaml

from ..errors import ScenarioError
from .sources import SourceMap, format_path, shorten

MAX_BYTES = 1 << 20
MAX_NODES = 100_000
MAX_DEPTH = 40


def parse_yaml(text, origin, lines=True):
    """``(data, SourceMap)`` of YAML ``text`` from ``origin`` (a file name or ``<yaml>``);
    ``lines``: name the line in errors."""
    node, loader = _compose(text, origin, lines)
    if node is None:
        return None, SourceMap(origin)
    _check_size(node, (lambda n: f"{origin}:{n.start_mark.line + 1}") if lines else (lambda n: origin))
    lines = {}
    _collect_lines(node, (), lines, origin)
    try:
        data = loader.construct_document(node)
    except yaml.YAMLError as exc:
        raise ScenarioError(_yaml_message(exc, origin)) from None
    finally:
        loader.dispose()
    return data, SourceMap(origin, lines)


def parse_value(text, label):
    """A ``--set`` value read as YAML under the same bounds; ``label`` names it in errors."""
    data, _ = parse_yaml(text, label, lines=False)
    return data


def _compose(text, origin, lines):
    if len(text) > MAX_BYTES:
        raise ScenarioError(f"{origin}: larger than {MAX_BYTES >> 20} MiB: not a scenario")
    try:
        loader = yaml.SafeLoader(text)
        return loader.get_single_node(), loader
    except yaml.YAMLError as exc:
        raise ScenarioError(_yaml_message(exc, origin, lines)) from None
    except RecursionError:
        raise ScenarioError(f"{origin}: nested more than {MAX_DEPTH} levels deep") from None



def _yaml_message(exc, origin, lines=True):
    mark = getattr(exc, "problem_mark", None)
    line = f":{mark.line + 1}" if mark is not None and lines else ""
    problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
    return f"{origin}{line}: malformed YAML: {shorten(problem, 120)}"


def _check_size(root, where):
    """Refuse documents whose alias-expanded size or depth exceed the bounds (memoised on the
    node graph, so this costs the size of the file, not of the expansion)."""
    sizes, depths, open_nodes = {}, {}, set()
    stack = [(root, False)]
    while stack:
        node, done = stack.pop()
        key = id(node)
        if key in sizes:
            continue
        children = _children(node)
        if not done:
            if key in open_nodes:
                raise ScenarioError(f"{where(node)}: an alias refers to the "
                                    "node that contains it (a recursive structure): not a scenario")
            open_nodes.add(key)
            stack.append((node, True))
            stack.extend((child, False) for child in children if id(child) not in sizes)
            continue
        open_nodes.discard(key)
        sizes[key] = 1 + sum(sizes[id(c)] for c in children)
        depths[key] = 1 + max((depths[id(c)] for c in children), default=0)
        if sizes[key] > MAX_NODES:
            raise ScenarioError(f"{where(node)}: more than {MAX_NODES} YAML "
                                "nodes once aliases are expanded: not a scenario")
        if depths[key] > MAX_DEPTH:
            raise ScenarioError(f"{where(node)}: nested more than "
                                f"{MAX_DEPTH} levels deep")


def _children(node):
    if isinstance(node, yaml.MappingNode):
        return [item for pair in node.value for item in pair]
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    return []


def _collect_lines(node, path, lines, origin):
    lines.setdefault(path, node.start_mark.line + 1)
    if isinstance(node, yaml.MappingNode):
        seen = set()
        for key_node, value_node in node.value:
            key = key_node.value
            if key in seen:
                raise ScenarioError(f"{origin}:{key_node.start_mark.line + 1}: "
                                    f"{format_path(path + (key,), None)}: duplicate key")
            seen.add(key)
            lines[path + (key,)] = key_node.start_mark.line + 1
            _collect_lines(value_node, path + (key,), lines, origin)
    elif isinstance(node, yaml.SequenceNode):
        for index, item in enumerate(node.value):
            _collect_lines(item, path + (index,), lines, origin)
