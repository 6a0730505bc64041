"""The documentation site (issue 37): it builds with warnings as errors, its scenario reference
(generated from the schema) names every key of every section with its unit, and every
tutorial's commands and Python run and print what the page shows."""
import json
import subprocess
import sys
import typing
from pathlib import Path

import pytest
from numpy.testing import assert_allclose

from transcripts import (fenced_blocks, fresh_copy, run_by_its_test, run_shell_block, run_transcript, skipped,
                         transcripts)

ROOT = Path(__file__).resolve().parents[2]
#: the pages whose examples run here: every page of the site but the reference pages that
#: test_readme.py runs with the README (getting-started's install lines are skipped)
REFERENCE = {f"{name}.md" for name in ("commands", "python", "scenario", "robots", "performance")}
TUTORIALS = sorted(page for page in (ROOT / "docs").rglob("*.md")
                   if not (page.parent == ROOT / "docs" and page.name in REFERENCE))
#: the rows scripts/gallery.py wrote for the gallery page
GALLERY_ROWS = ROOT / "docs" / "images" / "gallery" / "scenarios.json"


def test_the_site_builds_with_warnings_as_errors(tmp_path):
    run = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(ROOT / "mkdocs.yml"),
                          "-d", str(tmp_path / "site")], capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert run.returncode == 0, run.stderr[-3000:]
    site = tmp_path / "site"
    for page in ("index.html", "scenario/index.html", "api/index.html", "tutorials/solve/index.html",
                 "gallery/index.html", "architecture/index.html"):
        assert (site / page).is_file(), page
    assert not (site / "hooks.py").exists()
    api = (site / "api" / "index.html").read_text()
    assert "doc-class" in api and "InverseStatics" in api and "ContactUnknowns" in api
    gallery = (site / "gallery" / "index.html").read_text()
    for row in json.loads(GALLERY_ROWS.read_text()):           # each shipped scenario, drawn
        assert f"images/gallery/{row['image']}" in gallery and (site / "images" / "gallery" / row["image"]).is_file()


def test_the_gallery_has_every_shipped_scenario_solved_as_it_is_now():
    """scripts/gallery.py drew every shipped scenario; a scenario added, renamed or changed
    since then is caught here (two tips re-solved to 1e-4 mm: the drawings show today's shapes)."""
    sys.path.insert(0, str(ROOT / "scripts"))
    import gallery
    rows = {row["name"]: row for row in json.loads(GALLERY_ROWS.read_text())}
    assert sorted(rows) == sorted(gallery.name_of(path) for path in gallery.shipped())
    assert all(row["converged"] and row["balance"] < 1e-6 for row in rows.values())
    from tca_casadi import Simulation
    for name in ("bending_module", "analytic/tip_load"):
        solution = Simulation.from_file(ROOT / "scenarios" / f"{name}.yaml").solve(warn=False)
        assert_allclose(1e3 * solution.tip_position, rows[name]["tip_mm"], rtol=0, atol=1e-4)


def test_the_gallery_script_quick():
    sys.path.insert(0, str(ROOT / "scripts"))
    import gallery
    assert gallery.main(["--quick"]) == 0


def test_the_scenario_reference_names_every_key_with_its_unit():
    """Every field of every model reachable from Scenario has a row; quantities carry their SI
    unit, bounds their range."""
    from pydantic import BaseModel
    from tca_casadi.scenario.reference import scenario_reference
    from tca_casadi.scenario.schema import Scenario
    text = scenario_reference()
    seen, queue = set(), [Scenario]
    while queue:
        model = queue.pop()
        if model in seen:
            continue
        seen.add(model)
        section = text.split(f"### `{model.__name__}`")[1].split("\n### ")[0]
        for name, field in model.model_fields.items():
            assert f"| `{name}` |" in section, (model.__name__, name)

            def models(annotation):
                if isinstance(annotation, type) and issubclass(annotation, BaseModel):
                    return [annotation]
                return [m for arg in typing.get_args(annotation) for m in models(arg)]
            queue.extend(models(field.annotation))
    assert len(seen) > 30
    assert "| `youngs_modulus` | number | Pa | **required** | > 0 |" in text
    assert "| `ambient_temperature` | number | degC | `25` | >= -273.15 | the air (or body) the TCAs exchange heat" in text


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    return fresh_copy(tmp_path_factory.mktemp("tutorials"), ROOT)


STEPS = [(page.name, command, expected) for page in TUTORIALS for command, expected in transcripts(page.read_text())
         if not skipped(command) and not run_by_its_test(page.relative_to(ROOT).as_posix(), command)]
SHELL = [(page.name, text) for page in TUTORIALS for kind, text in fenced_blocks(page.read_text()) if kind == "bash"]
PYTHON = [(page.name, k, text) for page in TUTORIALS
          for k, text in enumerate(t for kind, t in fenced_blocks(page.read_text()) if kind == "python")]


@pytest.mark.parametrize("page, command, expected", STEPS, ids=[f"{p}: {c[:70]}" for p, c, _ in STEPS])
def test_tutorial_commands_run(workdir, page, command, expected):
    run_transcript(workdir, command, expected)


@pytest.mark.parametrize("page, block", SHELL, ids=[f"{p}: {b.strip().splitlines()[0][:60]}" for p, b in SHELL])
def test_tutorial_shell_blocks_run(workdir, page, block):
    run_shell_block(workdir, block)


@pytest.mark.parametrize("page, index, code", PYTHON, ids=[f"{p} python {k}" for p, k, _ in PYTHON])
def test_tutorial_python_runs(workdir, page, index, code, monkeypatch):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    monkeypatch.chdir(workdir)
    exec(compile(code, f"{page} python block {index}", "exec"), {"__name__": "tutorial"})
    plt.close("all")
