"""The README and the documentation's reference pages (``REFERENCE``: the command line, the
Python API at work, the scenario format, tendons and contact, accuracy and speed; the tutorials
run in ``test_docs.py``) are true to the letter: every fenced example runs verbatim from a copy
of the repository, shown outputs match (``...`` stands for what varies between runs), error examples
match exactly, the command-line synopsis matches ``--help``, and every dotted path used in an
example names something in a shipped scenario.

Long runs (the test command itself, installs, benchmarks, the arm's ``--check`` sequence) are
listed in ``transcripts.SKIPPED`` and run elsewhere (CI, ``scripts/``); a long run whose result a
test uses (``transcripts.RUN_BY_THEIR_TESTS``) is run once, by that test, which checks its
transcript."""
import re
from pathlib import Path

import pytest

from tca_casadi import cli

from transcripts import (fenced_blocks, fresh_copy, run_by_its_test, run_shell_block, run_transcript, skipped,
                         transcripts)

ROOT = Path(__file__).resolve().parents[2]
#: the pages this file runs: the README and the reference pages it moved to the documentation
REFERENCE = ["README.md"] + [f"docs/{name}.md" for name in ("commands", "python", "scenario", "robots", "performance")]
README = (ROOT / "README.md").read_text()
COMMANDS = (ROOT / "docs" / "commands.md").read_text()

def _blocks(language):
    """``[(page, text)]`` of every fenced block in ``language`` of the pages, in order."""
    return [(page, text) for page in REFERENCE for kind, text in fenced_blocks((ROOT / page).read_text())
            if kind == language]


def _transcripts():
    """``(page, command, expected output lines)`` of every ``$ tca-casadi`` line in plain blocks."""
    return [(page, command, expected) for page in REFERENCE
            for command, expected in transcripts((ROOT / page).read_text())]


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    """A copy of the repository's scenarios and scripts, as a fresh clone has them."""
    return fresh_copy(tmp_path_factory.mktemp("readme"), ROOT)


STEPS = [t for t in _transcripts() if not skipped(t[1]) and not run_by_its_test(t[0], t[1])]
PYTHON = [(page, k, code) for k, (page, code) in enumerate(_blocks("python"))]


@pytest.mark.parametrize("page, command, expected", STEPS, ids=[f"{p}: {c[:70]}" for p, c, _ in STEPS])
def test_transcript(workdir, page, command, expected):
    run_transcript(workdir, command, expected)


@pytest.mark.parametrize("page, block", _blocks("bash"), ids=[f"{p}: {b.strip().splitlines()[0][:60]}" for p, b in _blocks("bash")])
def test_shell_block(workdir, page, block):
    run_shell_block(workdir, block)


@pytest.mark.parametrize("page, index, code", PYTHON, ids=[f"{p} python {k}" for p, k, _ in PYTHON])
def test_python_block(workdir, page, index, code, monkeypatch):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    monkeypatch.chdir(workdir)
    exec(compile(code, f"{page} python block {index}", "exec"), {"__name__": "readme"})
    plt.close("all")


def test_synopsis_matches_help():
    """Every option a subcommand takes appears in its synopsis line, and no other."""
    block = next(b for kind, b in fenced_blocks(COMMANDS) if kind == "" and b.startswith("tca-casadi [-v] validate"))
    synopsis = {}
    for line in block.splitlines():
        words = line.split()
        if words[:2] == ["tca-casadi", "[-v]"]:
            command = words[2]
        synopsis[command] = synopsis.get(command, "") + " " + line
    parser = cli.build_parser()
    commands = parser._subparsers._group_actions[0].choices
    assert set(synopsis) == set(commands)
    for name, sub in commands.items():
        shown = set(re.findall(r"(?<![\w-])--?[a-z][a-z-]*", synopsis[name])) - {"-v"}
        actions = [set(a.option_strings) for a in sub._actions if a.option_strings and "--help" not in a.option_strings]
        assert all(options & shown for options in actions), (name, [o for o in actions if not o & shown])
        assert shown <= set().union(*actions), (name, shown - set().union(*actions))


def test_dotted_paths_in_examples_exist():
    """``--set``/``--param`` paths and sequence keys used in examples name things that exist in
    the shipped scenarios (module, actuator, load and object names, or top-level keys)."""
    from tca_casadi.scenario import load_scenario
    names = set()
    for path in (ROOT / "scenarios").rglob("*.yaml"):
        scenario = load_scenario(path, allow_code=True)
        names |= {m.name for m in scenario.modules} | {load.name for load in scenario.loads}
        names |= {o.name for o in scenario.objects}
    from tca_casadi.scenario.schema import Scenario
    names |= set(Scenario.model_fields)                      # the top-level keys
    pages = [README] + [page.read_text() for page in (ROOT / "docs").rglob("*.md")]
    used = re.findall(r"--(?:set|param) \"?([A-Za-z_][\w]*)\.", "\n".join(pages))
    assert used and set(used) <= names, set(used) - names


def _rendered_tables(path):
    """``(lines outside every table that look like table rows, rows whose cell count is not
    their header's)`` of a Markdown file, as markdown-it (CommonMark with GFM tables, the
    parser rich and mdformat use) renders it."""
    from markdown_it import MarkdownIt
    text = path.read_text()
    tokens = MarkdownIt("commonmark").enable("table").parse(text)
    covered, uneven = set(), []
    for k, token in enumerate(tokens):
        if token.type == "table_open":
            covered.update(range(*token.map))
        if token.type == "tr_open":
            cells = 0
            for inner in tokens[k + 1:]:
                if inner.type == "tr_close":
                    break
                cells += inner.type in ("th_open", "td_open")
            line = text.splitlines()[token.map[0]]
            written = line.strip().strip("|").count("|") + 1 - line.count("\\|")
            if written != cells:
                uneven.append(token.map[0] + 1)
    stray, fence = [], False
    for number, line in enumerate(text.splitlines()):
        if line.startswith("```"):
            fence = not fence
        elif not fence and line.startswith("|") and number not in covered:
            stray.append(number + 1)
    return stray, uneven


@pytest.mark.parametrize("name", ["README.md"] + sorted(str(p.relative_to(ROOT)) for p in (ROOT / "docs").rglob("*.md")))
def test_markdown_tables_render(name):
    """Every table renders as a table (its separator has as many cells as its header: else
    markdown shows the lines as text) and no row has more or fewer cells than its header."""
    stray, uneven = _rendered_tables(ROOT / name)
    assert not stray, f"{name}: lines {stray} are not inside a rendered table"
    assert not uneven, f"{name}: rows at lines {uneven} have another number of cells than their header"
