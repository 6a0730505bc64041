"""Where scenario keys came from (file lines, ``--set`` overrides), how key paths are written
in messages, and the one "did you mean" helper. Imported by the loader and the checks alike."""
import difflib

from ..text import clip, shorten  # noqa: F401  (re-exported: messages cut long values alike)


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
        for cut in range(len(path), -1, -1):           # an override replaced all below it
            if path[:cut] in self.overridden:
                return self.overridden[path[:cut]]
        for cut in range(len(path), -1, -1):
            if path[:cut] in self.lines:
                return f"{self.origin}:{self.lines[path[:cut]]}{suffix}"
        return self.origin


def located(sources, path, raw):
    """``WHERE: PATH`` of a message about the key ``path``: where it came from and its written
    path, once when the two say the same (``--set dynamics.integrator`` is both)."""
    where, written = sources.where(path), format_path(path, raw)
    return where if where.endswith(f" {written}") else f"{where}: {written}"


def format_path(path, raw):
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
    return clip(text, 200) or "(top level)"


def did_you_mean(word, options, none="; none are defined", listing="; known: "):
    """`` (did you mean 'x'?)`` for the closest of ``options``, else the list of them (cut to a
    reasonable length), else ``none``."""
    options = [str(o) for o in options]
    match = difflib.get_close_matches(str(word), options, n=1, cutoff=0.5)
    if not match:                          # the same name in other letter case ('BENDING')
        folded = {o.casefold(): o for o in options}
        match = [folded[m] for m in difflib.get_close_matches(str(word).casefold(), list(folded), n=1, cutoff=0.5)]
    if match:
        return f" (did you mean {match[0]!r}?)"
    if not options:
        return none
    shown, names = "", sorted(options)
    for k, name in enumerate(names):         # as many as fit in about 160 characters
        if len(shown) + len(name) > 160:
            shown += f", ... ({len(names)} in all)"
            break
        shown += (", " if k else "") + name
    return f"{listing}{shown}"
