"""Text for messages: values and names echoed back cut to a readable length, units written for people."""
import re
import sys


def shorten(value, limit=80):
    """``repr(value)`` cut to about ``limit`` characters, for error messages."""
    return clip(repr(value), limit)


def clip(text, limit=80):
    """``text`` cut to about ``limit`` characters (a name or path echoed in a message), its
    control characters escaped (a stray line break must not split a one-line error)."""
    text = "".join(ch if ch.isprintable() else repr(ch)[1:-1] for ch in str(text))
    return text if len(text) <= limit else text[:limit - 3] + "..."


def signed(value, digits=4):
    """``value`` with its sign, rounded to ``digits`` decimals; a result that rounds to zero is
    ``+0.0000`` whatever the sign of the roundoff (so transcripts do not flip between runs)."""
    return f"{round(float(value), digits) + 0.0:+.{digits}f}"


def unit_text(unit, plain=None):
    """How ``unit`` (a pint unit string) is written for people: ``"N*m"`` -> ``"N m"``, ``"um"``
    -> ``"µm"`` (``"um"`` where ``plain`` or, by default, where standard output cannot print the
    micro sign); ``"-"`` for none."""
    if not unit:
        return "-"
    text = re.sub(r"\bu(?=[a-zA-Z])", "µ", unit.replace("*", " ").replace("μ", "µ"))     # um -> µm
    if plain is None:
        plain = not _prints_micro()
    return text.replace("µ", "u") if plain else text


def _prints_micro():
    encoding = getattr(sys.stdout, "encoding", None) or "ascii"
    try:
        "µ".encode(encoding)
        return True
    except (UnicodeEncodeError, LookupError):
        return False
