"""What a scenario file wrote for a parameter (``"0.5 mm"``), so that results can be shown in the
unit the user gave (issue 35)."""

#: raw scenario lists whose items are addressed by name in a parameter path
NAMED_LISTS = ("modules", "actuators", "loads", "objects", "obstacles")


def written_value(scenario, name, component=None, size=1):
    """The raw value the scenario file wrote for the parameter-layout entry ``name`` (component
    ``component`` of a vector of ``size``), or None where the path does not lead to one value (a
    default, a vector's magnitude). Walks the raw YAML: mapping keys, and items of the named lists
    by their ``name``."""
    current = getattr(scenario, "_raw", None)
    for key in name.split("."):
        if isinstance(current, dict) and key in current:
            current = current[key]
            continue
        lists = [current.get(group) for group in NAMED_LISTS] if isinstance(current, dict) else []
        items = [item for group in lists if isinstance(group, list) for item in group
                 if isinstance(item, dict) and item.get("name") == key]
        if not items:
            return None
        current = items[0]
    if isinstance(current, list):
        current = current[component] if component is not None and len(current) == size else None
    return current if isinstance(current, (str, int, float)) and not isinstance(current, bool) else None
