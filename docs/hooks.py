"""MkDocs hooks: the scenario reference page is generated from the schema at build time
(:func:`tca_casadi.scenario.reference.scenario_reference`), so it cannot drift from what the
loader accepts."""

MARKER = "<!-- scenario reference -->"


def on_page_markdown(markdown, page, **kwargs):
    if MARKER not in markdown:
        return markdown
    from tca_casadi.scenario.reference import scenario_reference
    return markdown.replace(MARKER, scenario_reference())
