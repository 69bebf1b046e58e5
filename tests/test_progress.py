"""What a run says while it runs (vpcontact.progress): a line per set-up phase, then a line per time step off
a terminal (throttled when steps are short) or a tqdm bar on one, life lines during long phases and steps, a
study's runs as they start and end; nothing from the Python API unless asked; nothing but its one line from a
case refused during its set-up."""

import fcntl
import io
import json
import os
import pty
import re
import struct
import subprocess
import sys
import termios
import time

import pandas as pd
import pytest
import tomli_w

import vpcontact
from conftest import assert_refused, half_disc_case, rectangle_case, run_cli, snapshot_tree
from vpcontact.progress import Log, StepReport

STAMP = re.compile(r"^\[(\d\d):(\d\d)\] ")
STEP = re.compile(r"^\[\d\d:\d\d\] step (?P<n>[\d,]+)/(?P<total>[\d,]+): t = (?P<t>\S+), (?P<newton>\d+) Newton "
                  r"iterations?, (?P<limit>[\d,]+) nodes at the limit, (?P<compliance>[\d,]+) in compliance"
                  r"(, \d+ step cuts?)? \(\d[\d.e-]* s\)$")


def number(text: str) -> int:
    return int(text.replace(",", ""))


def write(folder, case, name="case.toml"):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / name).write_text(tomli_w.dumps(case))
    return folder / name


def streamed_run(*args, timeout=120):
    """``vpcontact ARGS`` with stderr a pipe (not a terminal), read line by line as the lines come: [(the
    line, when it came, whether the process was still running then)], and the exit status."""
    process = subprocess.Popen([sys.executable, "-m", "vpcontact.cli", *map(str, args)], stdout=subprocess.DEVNULL,
                               stderr=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True)
    lines, deadline = [], time.monotonic() + timeout
    for line in process.stderr:
        lines.append((line.rstrip("\n"), time.monotonic(), process.poll() is None))
        assert time.monotonic() < deadline, "the run takes too long"
    return lines, process.wait(timeout=timeout)


def head(line: str) -> str:
    """What a line is about: the word before its first colon, after the time stamp."""
    return STAMP.sub("", line).split(":")[0].split(" ")[0]


# --- a run on the command line, stderr not a terminal --------------------------------------------------
def test_a_run_off_a_terminal_prints_its_set_up_phases_then_a_line_per_step(tmp_path):
    case = half_disc_case(h=0.1)
    out = tmp_path / "out"
    lines, status = streamed_run("run", write(tmp_path, case), "--out", out)
    assert status == 0, lines
    text = [line for line, _, _ in lines]
    assert all(STAMP.match(line) for line in text), text
    heads = [head(line) for line in text]
    order = [h for i, h in enumerate(heads) if i == 0 or h != heads[i - 1]]  # a long phase: start and end lines
    assert order == ["mesh", "assembly", "method", "factorization", "condensation", "step", "outputs"], text
    summary = json.loads((out / "summary.json").read_text())
    mesh = text[0]
    assert (f"{summary['nodes']:,} nodes, {summary['elements']:,} triangles, {summary['dofs']:,} dofs"
            in mesh), mesh
    assert f", {summary['contact_nodes']:,} contact nodes" in text[heads.index("assembly")]
    method = STAMP.sub("", text[heads.index("method")])
    assert method == f"method: {summary['solver_method']} ({summary['solver_reason']})"
    # the step lines say what history.csv says of their steps
    history = pd.read_csv(out / "history.csv").set_index("step")
    steps = [STEP.match(line) for line in text if head(line) == "step"]
    assert all(steps), text
    numbers = [number(m["n"]) for m in steps]
    assert numbers[0] == 1 and numbers[-1] == 11 and numbers == sorted(set(numbers))
    for m in steps:
        row = history.loc[number(m["n"])]
        assert number(m["total"]) == 11
        assert float(m["t"]) == pytest.approx(row["t"], rel=1e-5)
        assert (int(m["newton"]), number(m["limit"]), number(m["compliance"])) == (
            row["newton_iterations"], row["nodes_at_limit"], row["nodes_in_compliance"])


def test_lines_are_written_as_they_happen_and_short_steps_are_throttled(tmp_path):
    """800 steps of a few milliseconds: the first and the last step, and at most a line a second in between,
    each line read while the run goes on (flushed, not buffered until the end)."""
    case = rectangle_case()
    case["time"]["steps"] = 800
    out = tmp_path / "out"
    lines, status = streamed_run("run", write(tmp_path, case), "--out", out)
    assert status == 0, lines
    steps = [(STEP.match(line), came, running) for line, came, running in lines if head(line) == "step"]
    numbers = [number(m["n"]) for m, _, _ in steps]
    assert numbers[0] == 1 and numbers[-1] == 800 and numbers == sorted(set(numbers))
    wall = json.loads((out / "summary.json").read_text())["wall_time_s"]
    assert len(steps) <= wall + 3, (len(steps), wall)
    assert steps[0][2], "the first step's line came only once the run had ended"
    set_up = [came for line, came, _ in lines if head(line) == "mesh"]
    assert set_up[0] < steps[-1][1] - 0.5 * wall, "the lines came all at once"


def test_a_terminal_gets_the_bar_of_the_steps_below_the_set_up_lines(tmp_path):
    path = write(tmp_path, half_disc_case(h=0.25))
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 120, 0, 0))  # a pty starts 0 columns wide
    process = subprocess.Popen([sys.executable, "-m", "vpcontact.cli", "run", str(path), "--out",
                                str(tmp_path / "out")], stderr=slave, stdout=subprocess.DEVNULL, stdin=subprocess.DEVNULL)
    os.close(slave)
    screen = b""
    while True:
        try:
            chunk = os.read(master, 65536)
        except OSError:  # the other end closed
            break
        if not chunk:
            break
        screen += chunk
    os.close(master)
    assert process.wait(timeout=120) == 0
    screen = screen.decode()
    assert "time steps: 100%|" in screen and "11/11" in screen and "\r" in screen, screen
    assert not re.search(r"\] step \d", screen), screen
    assert screen.index("condensation: ") < screen.index("time steps:") < screen.index("outputs: ")


def test_a_case_refused_in_its_set_up_prints_its_one_line_only(tmp_path):
    """The augmentation is refused when the solver is made: after the mesh, the assembly and the method."""
    path = write(tmp_path, half_disc_case(h=0.25))
    before = snapshot_tree(tmp_path)
    status, _, stderr = run_cli("run", path, "--out", tmp_path / "out", "--set", "solver.augmentation=1e-300")
    assert_refused(status, stderr, "solver.augmentation = 1e-300", untouched=[(tmp_path, before)])


def test_quiet_and_output_progress_false_print_no_progress(tmp_path):
    path = write(tmp_path, half_disc_case(h=0.25))
    assert run_cli("run", path, "--out", tmp_path / "a", "--quiet")[2] == ""
    assert run_cli("run", path, "--out", tmp_path / "b", "--set", "output.progress=false")[2] == ""


# --- the Python API --------------------------------------------------------------------------------
def test_the_python_api_prints_nothing_unless_asked(capfd):
    case = half_disc_case(h=0.25)
    vpcontact.solve(case)
    problem = vpcontact.build_problem(vpcontact.load_case(case))
    vpcontact.solve(problem)
    assert capfd.readouterr() == ("", "")
    vpcontact.solve(case, progress=True)
    out, err = capfd.readouterr()
    assert out == ""
    heads = [head(line) for line in err.splitlines()]
    assert heads[:3] == ["mesh", "assembly", "method"] and "step 11/11: " in err, err


# --- the rules, on a clock of the test's ------------------------------------------------------------
class Clock:
    def __init__(self):
        self.now = 0.0

    def __call__(self):
        return self.now


def quiet_log(hold=0.0):
    clock = Clock()
    stream = io.StringIO()
    return Log(stream, bar=False, hold=hold, watch=False, clock=clock), clock, stream


def step_lines(seconds_per_step: float, total: int) -> list[int]:
    """The steps printed of ``total`` steps of ``seconds_per_step`` each."""
    log, clock, stream = quiet_log()
    with log, log.steps(total) as steps:
        for n in range(1, total + 1):
            steps.started(n, n / total)
            clock.now += seconds_per_step
            steps.finished(StepReport(n, n / total, 2, 1e-12, 0, 5, 0, 0, seconds_per_step))
    return [number(STEP.match(line)["n"]) for line in stream.getvalue().splitlines()]


def test_step_lines_are_at_most_one_a_second_and_one_per_percent_of_the_steps():
    assert step_lines(1 / 256, 2000) == [1, 257, 513, 769, 1025, 1281, 1537, 1793, 2000]  # a line a second
    assert step_lines(1 / 16, 2000) == [1, *range(21, 2000, 20), 2000]  # a line per 1 % (20 steps, 1.25 s)
    assert step_lines(30.0, 5) == [1, 2, 3, 4, 5]  # long steps: each


def test_a_long_phase_and_a_long_step_show_life():
    log, clock, stream = quiet_log()
    with log:
        with log.phase("factorization", "A0", estimate=40.0):
            while clock.now < 100.0:
                clock.now += 0.5
                log.tick()
        with log.steps(3) as steps:
            steps.started(1, 0.1)
            for iteration in range(4):
                log.newton(iteration, 10.0 ** -iteration)
                clock.now += 4.0
                log.tick()
            steps.finished(StepReport(1, 0.1, 3, 1e-3, 0, 5, 0, 0, 16.0))
    lines = stream.getvalue().splitlines()
    # the start line, written once the phase has lasted a second; then 10, 20, 40 s of silence
    assert lines[:5] == ["[00:00] factorization: A0 ...",
                         "[00:11] factorization: running for 11.0 s, about 40.0 s expected",
                         "[00:31] factorization: running for 31.0 s, about 40.0 s expected",
                         "[01:11] factorization: running for 1 min 11 s, about 40.0 s expected",
                         "[01:40] factorization: done (1 min 40 s)"], lines
    assert lines[5] == "[01:52] step 1/3 (t = 0.1) running for 12.0 s: Newton iteration 2, residual 1.0e-02", lines
    assert lines[6].startswith("[01:56] step 1/3: t = 0.1, 3 Newton iterations"), lines


def test_the_first_lines_are_held_back_and_dropped_if_the_run_fails_then():
    log, clock, stream = quiet_log(hold=5.0)
    with log.phase("mesh", "a disc"):
        clock.now = 0.5
    log.note("method: condensed")
    clock.now = 4.9
    log.tick()
    assert stream.getvalue() == ""
    clock.now = 5.0
    log.tick()
    assert stream.getvalue() == "[00:00] mesh: a disc (0.5 s)\n[00:00] method: condensed\n"

    log, clock, stream = quiet_log(hold=5.0)
    with pytest.raises(ValueError), log:
        log.note("method: condensed")
        raise ValueError("refused")
    assert stream.getvalue() == ""

    log, clock, stream = quiet_log(hold=5.0)
    with log:
        log.note("method: condensed")
        clock.now = 1.0
        with log.steps(1):
            assert stream.getvalue() == "[00:00] method: condensed\n"  # the loop starts: the set-up went through


# --- studies and adaptive runs ------------------------------------------------------------------------
def test_a_study_logs_each_run_as_it_starts_and_ends(tmp_path):
    (tmp_path / "base.toml").write_text(tomli_w.dumps(rectangle_case()))
    (tmp_path / "study.toml").write_text('base = "base.toml"\n[[vary]]\n"contact.g" = [0.1, 0.2]\n'
                                         '[[runs]]\nid = "stuck"\n"solver.max_iterations" = 1\n'
                                         '"solver.method" = "full"\n"solver.max_step_cuts" = 0\n')
    lines, status = streamed_run("study", tmp_path / "study.toml", "--out", tmp_path / "out", "--workers", "2")
    assert status == 3, lines
    text = [STAMP.sub("", line) for line, _, _ in lines if STAMP.match(line)]
    assert text[0] == "study: 3 runs to do, on 2 worker processes", text
    for run in ("g=0.1", "g=0.2"):
        started, ended = text.index(f"run '{run}' started"), next(
            i for i, line in enumerate(text) if line.startswith(f"run '{run}' complete ("))
        assert started < ended, text
    events = [line for line in text if line.startswith("run 'stuck'")]
    assert [line.split(" (")[0].split(", ")[0] for line in events] == [
        "run 'stuck' started", "run 'stuck' failed", "run 'stuck' started again", "run 'stuck' failed"], events
    assert "to be tried again: step 1 (t = 0.1) failed" in events[1], events
    # the runs end in any order on two workers: the count is of those ended when 'stuck' failed for good
    last = text.index(events[3])
    ended = sum(line.startswith("run '") and " complete (" in line for line in text[:last]) + 1
    assert f"{ended} of 3 runs done, 1 failed" in events[3], text


def test_an_adaptive_run_logs_each_cycle_and_its_refinement(tmp_path):
    case = half_disc_case(h=0.25)
    case["adapt"] = {"cycles": 2}
    lines, status = streamed_run("run", write(tmp_path, case), "--out", tmp_path / "out")
    assert status == 0, lines
    heads = [head(line) for line, _, _ in lines]
    cycles = [STAMP.sub("", line) for line, _, _ in lines if head(line) == "adapt"]
    assert [line.split(",")[0] for line in cycles] == ["adapt: cycle 1 of at most 2", "adapt: cycle 1 complete",
                                                       "adapt: cycle 2 of at most 2", "adapt: cycle 2 complete"]
    second = heads.index("refinement")
    assert heads[second + 1:second + 3] == ["assembly", "adapt"] and heads.count("step") >= 4, heads
