"""Runnable documentation: the fenced blocks of a Markdown text, its ``$ tca-casadi`` transcripts,
and running one in a fresh process, comparing its output with what the text shows (``...``
stands for what varies between runs; an ``error:`` line must be the whole output, exit 2). Used
by the README's test and the documentation site's tutorials."""
import re
import shlex
import shutil
import subprocess
import sys

#: commands not run by the documentation tests, by what they start with or contain: the test
#: command itself, installs, benchmarks and the arm's ``--check`` sequence (CI and ``scripts/``)
SKIPPED = ("pip install", "python3 -m venv", "python -m pytest", "python scripts/bench.py",
           "bash .ci/run", "--check", "mkdocs build")


def fenced_blocks(text):
    """``[(language, text)]`` of every fenced block, in order."""
    blocks, current, language = [], None, None
    for line in text.splitlines():
        if line.startswith("```"):
            if current is None:
                current, language = [], line[3:].strip()
            else:
                blocks.append((language, "\n".join(current) + "\n"))
                current = None
        elif current is not None:
            current.append(line)
    return blocks


def transcripts(text):
    """``(command, expected output lines)`` of every ``$ tca-casadi`` line in plain blocks."""
    out = []
    for kind, block in fenced_blocks(text):
        if kind:
            continue
        lines = block.splitlines()
        for k, line in enumerate(lines):
            if line.startswith("$ "):
                expected = []
                for following in lines[k + 1:]:
                    if following.startswith("$ "):
                        break
                    expected.append(following)
                out.append((line[2:].split("  #")[0].strip(), expected))
    return out


def matches(expected, actual):
    """Whether an output line matches a shown one (``...``: anything)."""
    pattern = "^" + ".*".join(re.escape(part) for part in expected.split("...")) + "$"
    return re.match(pattern, actual) is not None


def run_transcript(workdir, command, expected):
    """Run ``command`` (``tca-casadi ...``) in ``workdir`` in a fresh process; assert its output
    shows every ``expected`` line (or, for ``error:`` lines, is exactly them, exit 2)."""
    argv = shlex.split(command)
    assert argv[0] == "tca-casadi"
    result = subprocess.run([sys.executable, "-m", "tca_casadi.cli", *argv[1:]], cwd=workdir,
                            capture_output=True, text=True, timeout=600)
    output = (result.stdout + result.stderr).rstrip("\n").splitlines()
    errors = [line for line in expected if line.startswith("error:")]
    if errors:
        assert result.returncode == 2 and output == errors, "\n".join(output)
        return
    assert result.returncode in (0, 1), result.stderr
    for line in expected:
        assert any(matches(line, got) for got in output), f"{line!r} not in:\n" + "\n".join(output)


def skipped(command):
    """Whether the documentation tests leave ``command`` to CI or ``scripts/``."""
    return any(part in command for part in SKIPPED)


#: transcripts run (once) by the test that uses their result, in its process, rather than again
#: by the documentation tests: ``{page (from the repository's root): commands}``
RUN_BY_THEIR_TESTS = {
    "docs/robots.md": ("tca-casadi sequence scenarios/arm_pick_and_place_contact.yaml "
                       "-o results/pick_and_place_contact --no-animation",),      # tests/integration/test_bodies.py
    "docs/tutorials/contact.md": ("tca-casadi simulate scenarios/analytic/pinch_lift.yaml --dt 0.002 --set "
                                  "timeline.1.set.gravity=[0,0,-17.81] -o results/pinch_lift_fast --quiet "
                                  "--no-animation",),                            # tests/integration/test_dynamics_bodies.py
}


def run_by_its_test(page, command):
    """Whether ``command`` on ``page`` is in :data:`RUN_BY_THEIR_TESTS`."""
    return command in RUN_BY_THEIR_TESTS.get(page, ())


def run_transcript_here(root, workdir, page, command, keep):
    """Run ``command``, shown on ``page`` (a :data:`RUN_BY_THEIR_TESTS` entry), in this process in
    ``workdir`` (a :func:`fresh_copy` of ``root``); assert its output shows what the page does,
    as :func:`run_transcript` would. ``keep``: the dotted path of the callable that does the
    command's work (e.g. its run function); returns ``(args, value)``: what it was called with
    and returned."""
    import contextlib
    import io
    import os
    import pkgutil
    from unittest import mock
    from tca_casadi import cli
    shown = dict(transcripts((root / page).read_text()))
    assert run_by_its_test(page, command) and command in shown, (page, command)
    original, kept = pkgutil.resolve_name(keep), []
    out, here = io.StringIO(), os.getcwd()
    try:
        os.chdir(workdir)
        with mock.patch(keep, lambda *a, **k: kept.append((a, original(*a, **k))) or kept[-1][1]), \
                contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
            code = cli.main(shlex.split(command)[1:])
    finally:
        os.chdir(here)
    output = out.getvalue().rstrip("\n").splitlines()
    assert code in (0, 1) and len(kept) == 1, "\n".join(output)
    for line in shown[command]:
        assert any(matches(line, got) for got in output), f"{line!r} not in:\n" + "\n".join(output)
    return kept[0]


def run_shell_block(workdir, block):
    """Run every line of a ``bash`` block in ``workdir`` (``tca-casadi`` and ``python`` as this
    interpreter's), each exiting 0, skipping :data:`SKIPPED` lines."""
    for command in [c for c in block.strip().splitlines() if c and not c.startswith("#")]:
        if skipped(command):
            continue
        if command.startswith("python "):
            command = sys.executable + command[len("python"):]
        result = subprocess.run(command.replace("tca-casadi ", f"{sys.executable} -m tca_casadi.cli "),
                                shell=True, cwd=workdir, capture_output=True, text=True, timeout=900)
        assert result.returncode == 0, f"{command}\n{result.stdout[-2000:]}\n{result.stderr[-2000:]}"


def fresh_copy(directory, root):
    """``directory`` holding copies of ``root``'s scenarios, scripts and data, as a fresh clone
    has them (where documented commands run); returns it."""
    for name in ("scenarios", "scripts", "data"):
        shutil.copytree(root / name, directory / name)
    return directory
