"""Text for messages: values and names echoed back cut to a readable length."""


def shorten(value, limit=80):
    """``repr(value)`` cut to about ``limit`` characters, for error messages."""
    return clip(repr(value), limit)


def clip(text, limit=80):
    """``text`` cut to about ``limit`` characters (a name or path echoed in a message)."""
    text = str(text)
    return text if len(text) <= limit else text[:limit - 3] + "..."
