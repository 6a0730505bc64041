"""MkDocs hooks: the scenario reference page is generated from the schema at build time
(:func:`tca_casadi.scenario.reference.scenario_reference`), so it cannot drift from what the
loader accepts; the gallery's scenario section is written from the rows that
``scripts/gallery.py`` wrote beside the drawings it made of every shipped scenario."""
import json
from pathlib import Path

MARKER = "<!-- scenario reference -->"
GALLERY = "<!-- scenario gallery -->"
ROWS = Path(__file__).parent / "images" / "gallery" / "scenarios.json"


def on_page_markdown(markdown, page, **kwargs):
    if MARKER in markdown:
        from tca_casadi.scenario.reference import scenario_reference
        markdown = markdown.replace(MARKER, scenario_reference())
    if GALLERY in markdown:
        markdown = markdown.replace(GALLERY, scenario_gallery(json.loads(ROWS.read_text())))
    return markdown


def scenario_gallery(rows):
    """Markdown of the gallery's rows (``scripts/gallery.py``): per scenario its drawing, the
    command that solves it, its description and tip."""
    parts = []
    for row in rows:
        tip = ", ".join(f"{v:.3f}" for v in row["tip_mm"])
        state = (f"converged, global balance {row['balance']:.1e} of the forces in play" if row["converged"]
                 else "**did not converge**")
        parts.append(f"### {row['name']}\n\n![{row['title']}](images/gallery/{row['image']})\n\n"
                     f"`{row['command']}`: tip at ({tip}) mm; {state}.\n\n{row['description']}\n")
    return "\n".join(parts)
