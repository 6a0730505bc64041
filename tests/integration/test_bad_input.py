"""Every bad input is answered cleanly: exit code 2 and one line per problem naming the file,
line and key, never a traceback; and nothing is computed before the output can be written.
Each case is an input a user or a fuzzer really tried (issue 13)."""
import json
import signal
import subprocess
import sys
import time

import pytest

from tca_casadi import cli

BENDING = "scenarios/bending_module.yaml"


def run(capsys, *argv):
    """``(exit code, stdout, stderr)`` of the CLI run in this process."""
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def one_error_line(err):
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("error: ") and "Traceback" not in err, err
    assert len(lines[0]) < 400, lines[0]
    return lines[0]


@pytest.fixture
def bending(scenarios):
    return scenarios / "bending_module.yaml"


@pytest.fixture
def no_solving(monkeypatch):
    """Fail the test if anything is solved (bad output paths must be refused before)."""
    from tca_casadi.simulation import Simulation

    def refuse(*args, **kwargs):
        raise AssertionError("solved before checking the output directory")
    monkeypatch.setattr(Simulation, "solve", refuse)
    monkeypatch.setattr(Simulation, "solve_at", refuse)


# ----------------------------------------------------------------------------- files
def test_a_binary_file(capsys, tmp_path):
    path = tmp_path / "robot.yaml"
    path.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\xff\xfe")
    code, _, err = run(capsys, "validate", path)
    assert code == 2
    assert "not a text (UTF-8) file" in one_error_line(err)


def test_a_yaml_alias_bomb_is_refused_fast(capsys, tmp_path):
    lines = ["a: &a [x, x, x, x, x, x, x, x, x]"]
    lines += [f"{chr(98 + i)}: &{chr(98 + i)} [" + ", ".join([f"*{chr(97 + i)}"] * 9) + "]" for i in range(9)]
    path = tmp_path / "bomb.yaml"
    path.write_text("\n".join(lines) + "\n")
    code, _, err = run(capsys, "solve", path)
    assert code == 2
    assert "aliases are expanded" in one_error_line(err)


@pytest.mark.parametrize("text", ["a: " + "[" * 5000 + "]" * 5000, "a: &x [1, *x]",
                                  "a: !!python/object/apply:os.system ['true']"])
def test_deep_recursive_and_python_tagged_yaml(capsys, tmp_path, text):
    path = tmp_path / "bad.yaml"
    path.write_text(text + "\n")
    code, _, err = run(capsys, "validate", path)
    assert code == 2
    one_error_line(err)


def test_deep_nesting_in_a_set_value(capsys, bending):
    code, _, err = run(capsys, "validate", bending, "--set", "bending.length=" + "[" * 3000)
    assert code == 2
    assert "nested" in one_error_line(err)


@pytest.mark.parametrize("name, message", [("scenarios/bending_module", "no such scenario file"),
                                           ("scenarios", "is a directory")])
def test_missing_path_or_directory(capsys, name, message):
    code, _, err = run(capsys, "solve", name)
    assert code == 2
    assert message in one_error_line(err)


@pytest.mark.parametrize("override, fragment", [
    ("bending.cross_section.diameter=1e300", "out of range"),
    ("bending.length=" + "9" * 400, "too large"),
    ("bending.tca1.temperature=1 1/0", "cannot read the unit '1/0'"),
    ("bending.tca1.temperature=5 m)", "cannot read the unit 'm)'"),
    ("bending.length='5 mm" + " " * 100_000 + "x'", "longer than 200 characters"),
    ("bending.length=" + "x" * 5000, "bending"),
    ("bending.tca2.temperature=200", "above the TCA type's max_temperature (150 degC)"),
    ("bending.tca2.temperature=5", "below the TCA type's min_temperature (15 degC)"),
    ("bending.tca9.temperature=1", "no actuator or key 'tca9' (did you mean 'tca3'?)"),
])
def test_bad_values_give_one_short_line(capsys, bending, override, fragment):
    started = time.perf_counter()
    code, _, err = run(capsys, "validate", bending, "--set", override)
    assert code == 2
    assert fragment in one_error_line(err)
    assert time.perf_counter() - started < 30     # refused, not computed (generous: loaded CI)


def test_trailing_spaces_are_read_in_linear_time(bending):
    """The unit regex was quadratic: 40 000 spaces after a quantity took 16 s."""
    from tca_casadi.units import to_si
    started = time.perf_counter()
    assert to_si("5 mm" + " " * 100_000, "length") == pytest.approx(0.005, rel=1e-12)
    assert time.perf_counter() - started < 5


def test_every_problem_is_listed_one_per_line(capsys, bending):
    code, _, err = run(capsys, "validate", bending, "--set", "bending.length=-1",
                       "--set", "bending.cross_section.diameter=0")
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 2 and all(line.startswith("error: ") for line in lines), err
    assert "length" in err and "diameter" in err and "more problem" not in err


def test_a_temperature_beyond_the_range_in_a_sweep(capsys, bending):
    code, _, err = run(capsys, "sweep", bending, "--param", "bending.tca2.temperature", "--from", 25,
                       "--to", 300, "--steps", 3)
    assert code == 2
    assert "validated range [15, 150] degC" in one_error_line(err)


@pytest.mark.parametrize("starts", ["0", "-3"])
def test_inverse_needs_a_start(capsys, bending, starts):
    code, _, err = run(capsys, "inverse", bending, "--starts", starts)
    assert code == 2
    assert "at least 1" in one_error_line(err)


# ----------------------------------------------------------------------------- outputs
def test_output_under_a_file_or_naming_a_file(capsys, bending, tmp_path, no_solving):
    afile = tmp_path / "afile"
    afile.write_text("keep me")
    for target, fragment in ((afile, "not a directory"), (afile / "sub", "cannot write results there")):
        for command in (["solve", bending], ["sweep", bending, "--param", "bending.tca2.temperature",
                                             "--from", 25, "--to", 30]):
            code, _, err = run(capsys, *command, "-o", target)
            assert code == 2
            assert fragment in one_error_line(err)
    assert afile.read_text() == "keep me"


def test_output_holding_a_directory_named_like_a_result(capsys, bending, tmp_path, no_solving):
    (tmp_path / "solution.json").mkdir()
    code, _, err = run(capsys, "solve", bending, "-o", tmp_path)
    assert code == 2
    assert "solution.json is a directory" in one_error_line(err)


@pytest.mark.parametrize("target", ["bad\x00name", "/".join(["a"] * 3000)])
def test_impossible_output_paths(capsys, bending, tmp_path, monkeypatch, no_solving, target):
    monkeypatch.chdir(tmp_path)
    code, _, err = run(capsys, "solve", bending, "-o", target)
    assert code == 2
    assert "cannot write results there" in one_error_line(err)


@pytest.mark.parametrize("name, directory", [("../../escaped", "escaped"), ("/etc/passwd", "etc_passwd"),
                                             ("..", "scenario")])
def test_a_scenario_name_never_chooses_a_directory_outside_results(capsys, bending, tmp_path, monkeypatch,
                                                                   name, directory):
    monkeypatch.chdir(tmp_path)
    code, _, _ = run(capsys, "solve", bending.resolve(), "--set", f"name={name}", "--no-plot")
    assert code == 0
    written = sorted(p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("*") if p.is_file())
    assert written == [f"results/{directory}/arrays.npz", f"results/{directory}/run_solve.json",
                       f"results/{directory}/solution.json"]


def test_no_plot_removes_an_earlier_drawing(capsys, bending, tmp_path):
    (tmp_path / "robot.png").write_bytes(b"an older run's picture")
    code, _, _ = run(capsys, "solve", bending, "-o", tmp_path, "--no-plot")
    assert code == 0
    assert not (tmp_path / "robot.png").exists()
    assert json.loads((tmp_path / "solution.json").read_text())["converged"] is True


# ----------------------------------------------------------------------------- failures
def test_a_failed_solve_reports_the_users_inputs_and_how_far_it_got(capsys, bending, tmp_path):
    code, out, _ = run(capsys, "solve", bending, "--set", "tip_force.force=[0, 0, 5]", "-o", tmp_path,
                       "--no-plot")
    assert code == 1
    assert "NOT CONVERGED" in out
    table = [line.split() for line in out.splitlines() if line.strip().startswith("bending.tca")]
    assert [row[1] for row in table] == ["25.0", "100.0", "100.0"]         # as given, not ramped
    assert "stalled at lambda = " in out and "of 1" in out and "bending.tca2.temperature" in out
    assert "max scaled residual above is at the requested parameters" in out
    saved = json.loads((tmp_path / "solution.json").read_text())
    assert saved["converged"] is False and saved["max_residual"] > 1e-6


def test_a_sweep_whose_first_step_fails_reports_and_writes(capsys, bending, tmp_path):
    code, out, err = run(capsys, "sweep", bending, "--param", "gravity.magnitude", "--from", 9.81,
                         "--to", "1e7", "--steps", 2, "--min-step", 0.5, "-o", tmp_path, "--quiet")
    assert code == 1, err
    assert "stopped at gravity.magnitude = 9.81" in out
    assert (tmp_path / "sweep.csv").read_text().count("\n") == 2         # header + the start
    assert json.loads((tmp_path / "sweep.json").read_text())["completed"] is False


def _ignore_sigint():
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@pytest.mark.parametrize("ignored", [False, True], ids=["sigint", "sigint-ignored-by-parent"])
@pytest.mark.parametrize("delay", [0.5, 0.85, 1.2])   # in the imports (casadi's at about 0.8 s) and after
def test_ctrl_c_during_start_up_exits_130_with_one_line(scenarios, tmp_path, delay, ignored):
    """Also when started with SIGINT ignored, as a shell's background job is (the CLI takes
    Ctrl-C back once it runs; a Ctrl-C before that is ignored, as the parent asked: the key is
    pressed again, every 0.25 s, until the process ends)."""
    process = subprocess.Popen([sys.executable, "-m", "tca_casadi.cli", "check", str(scenarios / "arm.yaml"),
                                "-o", str(tmp_path)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               preexec_fn=_ignore_sigint if ignored else None)
    time.sleep(delay)
    deadline = time.monotonic() + 60
    while process.poll() is None and time.monotonic() < deadline:
        process.send_signal(signal.SIGINT)
        time.sleep(0.25)
    out, err = process.communicate(timeout=60)
    assert process.returncode == 130, err
    assert err.strip().splitlines()[-1].startswith("interrupted") and "Traceback" not in err, err


@pytest.mark.parametrize("setting, words", [
    ("timeline=[{at: 1 s, set: {BENDING.TCA2.DRIVE.VALUE: 0.5 W}}]",
     ["timeline[0] (at 1 s): set BENDING.TCA2.DRIVE.VALUE", "(did you mean 'bending'?)"]),
    ("timeline=[{at: 1 s, set: {bending.tca2.drive.valu: 0.5 W}}]",
     ["timeline[0] (at 1 s): set bending.tca2.drive.valu", "unknown key 'valu' (did you mean 'value'?)"]),
    ("timeline=[{at: 1 s, set: {bending.tca2.drive.value: 0.5 W}}, {at: 2 s, set: {bending.tca9.temperature: 50}}]",
     ["timeline[1] (at 2 s): set bending.tca9.temperature", "no actuator or key 'tca9'"]),
    ("sequence=[{name: heat, set: {bending.tca2.temprature: 90}}]",
     ["sequence[heat]: set bending.tca2.temprature", "(did you mean 'temperature'?)"]),
    ("sequence=[{name: heat, set: {bending.tca2.temperature: 900}}]",
     ["sequence[heat]: set bending.tca2.temperature", "above the TCA type's max_temperature"]),
])
def test_validate_checks_timeline_and_sequence_paths_when_reading(capsys, bending, setting, words):
    """``validate`` reads every timeline event's and sequence step's paths (applied in order,
    as simulate and sequence apply them) with the same "did you mean" as ``--set``."""
    drive = "bending.tca2.drive={kind: power, value: 0}"
    code, _, err = run(capsys, "validate", bending, "--set", drive, "--set", "duration=10", "--set", setting)
    line = one_error_line(err)
    assert code == 2
    assert all(word in line for word in words), line


def test_every_bad_step_is_listed(capsys, bending):
    code, _, err = run(capsys, "validate", bending, "--set",
                       "sequence=[{name: a, set: {bending.tca2.temprature: 90}}, {name: b, set: {bending.tca3.temperature: 90}},"
                       " {name: c, set: {bendin.tca1.temperature: 30}}]")
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 2, err
    assert "sequence[a]" in lines[0] and "sequence[c]" in lines[1] and "(did you mean 'bending'?)" in lines[1]


# ----------------------------------------------------------------------------- data files
MEASUREMENTS = "bending.tca2.temperature [degC],tip_x [mm]\n40,-1.5\n90,-8.0\n"
HEATING = "t [s],bending.tca2.temperature [degC]\n0,25\n1,30\n2,34\n"
TARGETS = "x [m],y [m],z [m]\n-0.01,0,-0.04\n"
ROWS = "bending.tca2.temperature [degC]\n40\n90\n"
GOOD = {"fit": MEASUREMENTS, "heating": HEATING, "inverse": TARGETS, "rows": ROWS}
BROKEN = {   # what each kind of damage does to a good file, and a word of the answer
    "not utf-8": (lambda text: text.encode()[:-4] + b"\xff\xfe9\n", "not UTF-8 text (byte 0xff"),
    "nul byte": (lambda text: text.replace("\n", "\n\x00", 1).encode(), "a NUL byte"),
    "empty": (lambda text: b"# nothing but a comment\n\n", "is empty"),
    "nan": (lambda text: text.replace("\n40", "\nnan", 1).replace("\n0,", "\nnan,", 1).replace(
        "\n-0.01", "\nnan", 1).encode(), "is not a finite number"),
    "short row": (lambda text: (text + "7\n").encode() if "," in text.splitlines()[0] else (text + "7,8\n").encode(),
                  "values for"),
    "text cell": (lambda text: text.replace("\n40", "\nhot", 1).replace("\n0,", "\nnow,", 1).replace(
        "\n-0.01", "\nleft", 1).encode(), "is not a number"),
}


def _command(kind, path, bending, tmp_path):
    out = ["-o", str(tmp_path / "out"), "--quiet"]
    if kind in ("fit", "heating"):
        drive = ["--set", "bending.tca2.drive={kind: power, value: 0.1}"] if kind == "heating" else []
        param = "tca_types.nylon.thermal.conductance" if kind == "heating" else "materials.ecoflex30.youngs_modulus"
        return ["fit", bending, *drive, "--data", path, "--param", param, *out]
    if kind == "inverse":
        return ["inverse", bending, "--path", path, *out]
    return ["study", bending, "--rows", path, *out]


@pytest.mark.parametrize("kind", sorted(GOOD))
@pytest.mark.parametrize("damage", sorted(BROKEN))
def test_every_data_file_the_cli_reads_answers_damage_in_one_line(capsys, bending, tmp_path, kind, damage, no_solving):
    """``fit --data`` (measurements and heating curves), ``inverse --path``, ``study --rows``:
    bad bytes, NUL, empty, NaN, rows of the wrong length, text: one line naming the file (and
    its line where there is one), exit 2, nothing solved."""
    make, words = BROKEN[damage]
    path = tmp_path / "data.csv"
    path.write_bytes(make(GOOD[kind]))
    code, _, err = run(capsys, *_command(kind, path, bending, tmp_path))
    line = one_error_line(err)
    assert code == 2 and words in line and str(path) in line, line
    if damage not in ("empty",):
        assert " line " in line, line


@pytest.mark.parametrize("kind", sorted(GOOD))
def test_a_huge_data_file_is_refused_unread(capsys, bending, tmp_path, kind, no_solving):
    path = tmp_path / "huge.csv"
    with open(path, "wb") as handle:             # sparse: 101 MiB on paper, nothing on disk
        handle.write(GOOD[kind].encode())
        handle.truncate(101 * 2**20)
    code, _, err = run(capsys, *_command(kind, path, bending, tmp_path))
    line = one_error_line(err)
    assert code == 2 and "is 101 MiB" in line and "at most 100 MiB" in line, line


@pytest.mark.parametrize("kind", sorted(GOOD))
def test_a_data_file_without_its_columns_says_which(capsys, bending, tmp_path, kind, no_solving):
    path = tmp_path / "data.csv"
    path.write_text("a,b\n1,2\n")
    code, _, err = run(capsys, *_command(kind, path, bending, tmp_path))
    line = one_error_line(err)
    assert code == 2 and ("'a'" in line or "column" in line), line


@pytest.mark.parametrize("damage, words", [
    (b'{"sample": 3, "tip_x [m]": 0.1}\n\xff\xfe\n{"sample": 4}\n', "line 3: not UTF-8 text"),
    (b'{"sample": 3}\n{"sample": 4, "tip\n{"sample": 5}\n', "line 3: not a JSON row; the file is damaged"),
    (b'{"sample": 3}\n["no", "sample"]\n', "a row without its sample number"),
])
def test_a_damaged_resume_file_is_one_line(capsys, bending, tmp_path, damage, words):
    """``study --resume`` over a rows file damaged in the middle (a write cut short at its end is
    fine: that sample is solved again)."""
    from tca_casadi.studies.batch.study import PARTIAL
    args = ["study", bending, "--vary", "bending.tca2.temperature=25:125:3", "-o", str(tmp_path), "--quiet", "--no-plot"]
    plan = b'{"plan": "%s", "samples": 3}\n' % _plan_of(capsys, args, tmp_path, PARTIAL)
    first = (tmp_path / "study.csv").read_text()
    (tmp_path / PARTIAL).write_bytes(plan + damage)
    code, _, err = run(capsys, *args, "--resume")
    line = one_error_line(err)
    assert code == 2 and words in line and PARTIAL in line, line
    assert (tmp_path / "study.csv").read_text() == first          # the results of the run before stay


def _plan_of(capsys, args, directory, partial):
    """The plan digest a study writes as its rows file's first line (from an interrupted run)."""
    import json
    from tca_casadi.studies.batch import study as module
    original = module._Stream.close
    module._Stream.close = lambda self: None                      # keep the rows file
    try:
        run(capsys, *args)
    finally:
        module._Stream.close = original
    return json.loads((directory / partial).read_text().splitlines()[0])["plan"].encode()


# ----------------------------------------------------------------------------- out of memory
def _limit_memory(megabytes):
    def limit():
        import resource
        resource.setrlimit(resource.RLIMIT_AS, (megabytes * 2**20, resource.RLIM_INFINITY))
    return limit


def test_running_out_of_memory_is_one_line_and_writes_nothing(bending, tmp_path):
    """2000 intervals under a 768 MiB address-space limit (ulimit -v; a normal solve peaks at
    about 330 MB of address space), in a fresh process: one
    line saying what was too big, what to change and what the limit is; exit 1; the results of
    the run before stay as they were."""
    import os
    out = tmp_path / "out"
    first = subprocess.run([sys.executable, "-m", "tca_casadi.cli", "solve", str(bending), "-o", str(out), "--no-plot"],
                           capture_output=True, text=True)
    assert first.returncode == 0, first.stderr
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    run = subprocess.run([sys.executable, "-m", "tca_casadi.cli", "solve", str(bending), "--set", "solver.intervals=2000",
                          "--set", "solver.refine=off", "-o", str(out), "--no-plot"], capture_output=True, text=True,
                         env=env, preexec_fn=_limit_memory(768), timeout=600)
    assert run.returncode == 1, run.stderr[-2000:]
    line = one_error_line(run.stderr)
    assert line.startswith("error: out of memory while ") and "ulimit -v" in line and "solver.intervals" in line, line
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_a_factorisation_that_runs_out_of_memory_says_its_size(capsys, bending, tmp_path, monkeypatch):
    import scipy.sparse.linalg as spla

    def no_memory(*args, **kwargs):
        raise MemoryError
    monkeypatch.setattr(spla, "splu", no_memory)
    code, _, err = run(capsys, "solve", bending, "-o", tmp_path / "out", "--no-plot")
    line = one_error_line(err)
    assert code == 1 and "out of memory while factorising the Jacobian of 411 unknowns" in line, line
    assert not (tmp_path / "out").exists()


def test_a_ctrl_c_inside_a_c_extension_callback_is_an_interrupt(capsys, monkeypatch):
    """A Ctrl-C that lands while numpy converts a CasADi matrix comes back as a SystemError
    caused by the KeyboardInterrupt (seen in CI): one line, status 130, like any interrupt; any
    other SystemError is not ours to hide."""
    import tca_casadi.cli.run as run

    def interrupted(args):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as exc:
            raise SystemError("<function DM.__array__> returned a result with an exception set") from exc

    def broken(args):
        raise SystemError("something else")
    monkeypatch.setitem(run.COMMANDS, "validate", interrupted)
    assert run.main(["validate", "x.yaml"]) == 130
    assert capsys.readouterr().err.startswith("interrupted: no result of this run was written")
    monkeypatch.setitem(run.COMMANDS, "validate", broken)
    with pytest.raises(SystemError, match="something else"):
        run.main(["validate", "x.yaml"])
