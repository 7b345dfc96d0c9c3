"""`soadyn sweep` on hostile input: each case a real process on real files, exit status 2 and one
line on stderr naming the file, line:column and the field, never a traceback; limits refused
before anything proportional to them is built; part files and a second sweep into a busy
directory refused naming what is wrong; control characters from files never reach the terminal."""
import json
import os
import re
import subprocess
import sys
import time

import pytest

from conftest import SCENARIOS, SOADYN

from soadyn import ensemble

DP = os.path.join(SCENARIOS, "double_pendulum.yaml")
HEAD = f"scenario: {DP}\nset: {{simulation.t_end: 0.05, simulation.output_dt: 0.01}}\nvary:\n"
LEAF = "  - {path: initial.q.theta1, uniform: [-1.0, 1.0], count: 6}\n"
# each case through the executable and through python3 -m soadyn (what the executable runs)
RUNNERS = {"soadyn": [SOADYN, "sweep"], "python": [sys.executable, "-m", "soadyn", "sweep"]}
CONTROL = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f]")


def sweep(*args, runner="soadyn", timeout=60):
    return subprocess.run(RUNNERS[runner] + [str(a) for a in args], capture_output=True, text=True, timeout=timeout,
                          errors="surrogateescape")


def refused(*args, runner="soadyn", timeout=60):
    """the one line `soadyn sweep` prints for bad input (exit status 2), without 'soadyn: error: '"""
    p = sweep(*args, runner=runner, timeout=timeout)
    assert "Traceback" not in p.stderr, p.stderr
    assert p.returncode == 2, p.stdout + p.stderr
    lines = p.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("soadyn: error: "), p.stderr
    assert not CONTROL.search(lines[0]), repr(lines[0])
    return lines[0][len("soadyn: error: "):]


def write(tmp_path, text, name="bad.sweep.yaml"):
    p = tmp_path / name
    p.write_text(text)
    return str(p)


@pytest.fixture(params=sorted(RUNNERS))
def runner(request):
    return request.param


def test_counts_past_the_limit_are_refused_before_drawing(tmp_path, runner):
    """a count of 10^12, one of 26 digits, and 10^12 cases from four lists of 1000: refused at the
    field (each in well under the time drawing would take, in bounded memory)"""
    f = write(tmp_path, HEAD + "  - {path: simulation.dt, grid: [1.0e-3, 1.0e-2], count: 1000000000000}\n")
    assert refused(f, "-o", tmp_path / "out", runner=runner) == \
        f"{f}:4:58: vary[0].count: 1000000000000 cases, more than the 1000000 a sweep may have"
    f = write(tmp_path, HEAD + "  - {path: simulation.dt, grid: [1.0e-3, 1.0e-2], count: 99999999999999999999999999}\n")
    assert refused(f, "-o", tmp_path / "out", runner=runner) == \
        f"{f}:4:58: vary[0].count: 99999999999999999999999999 cases, more than the 1000000 a sweep may have"
    values = "[" + ", ".join(f"{1e-3 + k * 1e-6:.6g}" for k in range(1000)) + "]"
    f = write(tmp_path, HEAD + "".join(f"  - {{path: {p}, values: {values}}}\n" for p in
                                       ("simulation.dt", "initial.q.theta1", "initial.q.theta2", "simulation.rtol")))
    t0 = time.monotonic()
    assert refused(f, "-o", tmp_path / "out", runner=runner) == \
        f"{f}:4:3: vary: 1000000000000 cases (1000 × 1000 × 1000 × 1000), more than the 1000000 a sweep may have"
    assert time.monotonic() - t0 < 30
    assert not (tmp_path / "out").exists()  # refused before the results directory was made


def test_case_count_siblings(tmp_path):
    out = tmp_path / "out"
    bad = {
        "count: -3": "vary[0].count: expected a positive integer, got '-3'",
        "count: 0": "vary[0].count: expected a positive integer, got '0'",
        "count: true": "vary[0].count: expected a positive integer, got 'true'",
        "count: 2.5": "vary[0].count: expected a positive integer, got '2.5'",
        "count: .nan": "vary[0].count: expected a positive integer, got '.nan'",
        "count: 1" + "0" * 5000: "vary[0].count: cannot read this value: Exceeds the limit (4300 digits)",
        "count: [3]": "vary[0].count: expected a positive integer, got a list",
    }
    for text, message in bad.items():
        f = write(tmp_path, HEAD + "  - {path: initial.q.theta1, uniform: [-1.0, 1.0], " + text + "}\n")
        got = refused(f, "-o", out)
        assert got.startswith(f"{f}:4:") and message in got, (text, got)
        assert len(got) < 300, got  # a 5000-digit value is cut short, not echoed whole
    # cases × varied fields past MAX_CASE_VALUES: a zip of 11 fields of 10^6 draws each
    zip11 = "  - zip:\n" + "".join(f"      - {{path: bodies.upper.p{k}, uniform: [1.0, 2.0], count: 1000000}}\n"
                                   for k in range(11))
    f = write(tmp_path, HEAD + zip11)
    assert refused(f, "-o", out) == (f"{f}:5:7: vary[0].zip: 1000000 cases × 11 varied fields = 11000000 values, "
                                     "more than the 10000000 a sweep may hold")
    # a product of groups: the limit holds for every group, named by its place
    f = write(tmp_path, HEAD + "  - product:\n      - {path: 'gravity[0]', grid: [0, 1], count: 1001}\n"
                               "      - {path: 'gravity[1]', grid: [0, 1], count: 1000}\n")
    assert refused(f, "-o", out) == f"{f}:5:7: vary[0].product: 1001000 cases (1001 × 1000), more than the 1000000 a sweep may have"


def test_deep_nesting_is_refused_not_a_recursion_error(tmp_path, runner):
    text, indent = HEAD + "  - zip:\n", "      "
    for _ in range(2000):
        text += indent + "- zip:\n"
        indent += "    "
    f = write(tmp_path, text + indent + "- {path: simulation.dt, values: [0.001]}\n")
    got = refused(f, "-o", tmp_path / "out", runner=runner)
    assert got.startswith(f"{f}:35:129: vary[0].zip[0].zip[0].zip[0]") and "…" in got and len(got) < 250, got
    assert got.endswith("0].zip[0].zip[0]: nested more than 64 levels deep (the most a sweep file or scenario may nest)"), got
    # flow style, a million brackets: the same (the text is scanned, never composed)
    f = write(tmp_path, HEAD + "  - {path: gravity, values: [" + "[" * 10 ** 6 + "]" * 10 ** 6 + "]}\n")
    assert "nested more than 64 levels deep" in refused(f, "-o", tmp_path / "out", runner=runner)


def test_alias_bomb_and_recursive_alias(tmp_path, runner):
    def lol(k):
        return "&l0 [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]" if k == 0 else f"&l{k} [{lol(k - 1)}" + f", *l{k - 1}" * 9 + "]"
    f = write(tmp_path, HEAD + f"  - path: gravity\n    values: [{lol(8)}]\n")  # 10^9 numbers in 9 lines
    t0 = time.monotonic()
    got = refused(f, "-o", tmp_path / "out", runner=runner)
    assert re.fullmatch(re.escape(f) + r":5:\d+: vary\[0\]\.values\[0\]\[0\]\[0\]\[\d\]: expands to more than 10000000 "
                        r"YAML nodes through aliases \(the most a document may hold: an alias bomb\?\)", got), got
    assert time.monotonic() - t0 < 30
    f = write(tmp_path, HEAD + "  - {path: gravity, values: &a [*a]}\n")
    assert refused(f, "-o", tmp_path / "out", runner=runner) == \
        f"{f}:4:33: vary[0].values[0]: the alias *a stands for a node that holds it (a structure without end)"
    # an alias that stays small is a value like any other
    f = write(tmp_path, HEAD + "  - {path: gravity, values: [&g [0.0, 0.0, -9.81], *g]}\n")
    p = sweep(f, "-o", tmp_path / "ok", "--scheduler", "serial", "-q", runner=runner)
    assert p.returncode == 0, p.stderr
    import soadyn
    assert list(soadyn.read_results(str(tmp_path / "ok" / "results.h5"))["gravity"]) == ["[0.0, 0.0, -9.81]"] * 2


def test_empty_files_seeds_and_values(tmp_path, runner):
    out = tmp_path / "out"
    for text in ("", "# only a comment\n"):
        f = write(tmp_path, text)
        assert refused(f, "-o", out, runner=runner) == \
            f"{f}:1:1: scenario: missing required field: the sweep file is empty (expected a mapping with scenario and vary)"
    f = write(tmp_path, "---\n")
    assert refused(f, "-o", out, runner=runner) == f"{f}:2:1: expected a mapping, got ''"
    f = write(tmp_path, "- a\n- b\n")
    assert refused(f, "-o", out, runner=runner) == f"{f}:1:1: expected a mapping, got a list"
    seed = "an integer from 0 to 2^64 - 1"
    for value in ("-1", "1.5", "true", str(2 ** 64), ".inf", "[1]"):
        f = write(tmp_path, HEAD.replace("set:", f"seed: {value}\nset:", 1) + LEAF)
        shown = "a list" if value == "[1]" else f"'{value}'"
        assert refused(f, "-o", out, runner=runner) == f"{f}:2:7: seed: expected {seed}, got {shown}", value
    # values JSON cannot carry to the scenario parser, past the first 16 the loader runs
    many = ", ".join(["0.01"] * 20)
    for value, message in ((".nan", "expected a finite number, got nan"), ("2001-12-14", "expected a number, a string, "
                           "or a list or mapping of them, got a date"), ("{[1]: 2}", "cannot read this value: found "
                           "unhashable key")):
        f = write(tmp_path, HEAD + f"  - {{path: simulation.dt, values: [{many}, {value}]}}\n")
        got = refused(f, "-o", out, runner=runner)
        assert got.startswith(f"{f}:4:") and got.endswith(message) and "vary[0].values[20]" in got, got
    f = write(tmp_path, HEAD + "  - {path: simulation.dt, values: [!!python/object/apply:os.system [touch pwned]]}\n")
    got = refused(f, "-o", out, runner=runner)
    assert got.startswith(f"{f}:4:36: vary[0].values[0]: cannot read this value: could not determine a constructor"), got
    assert not os.path.exists("pwned")
    # YAML 1.2's 1e-2 is a number: the message blames the 0, not the 1e-2
    f = write(tmp_path, HEAD + "  - {path: simulation.dt, log_uniform: [0, 1e-2], count: 3}\n")
    assert refused(f, "-o", out, runner=runner) == \
        f"{f}:4:40: vary[0].log_uniform: expected [low, high] with 0 < low < high, got [0, 0.01]"
    # a negative index is not Python's count from the end (it once set the last coordinate)
    for path in ("initial.q[-1]", "inputs[-1].value"):
        f = write(tmp_path, HEAD + f"  - {{path: '{path}', values: [0.5]}}\n")
        got = refused(f, "-o", out, runner=runner)
        assert got.startswith(f"{f}:4:") and "a negative index; entries count from 0" in got, got
    f = write(tmp_path, HEAD + "  - {path: 'initial.q[2]', values: [0.5]}\n")
    assert "initial.q[2]: index out of range (the model has 2)" in refused(f, "-o", out, runner=runner)
    f = write(tmp_path, HEAD + "  - {path: simulation.dt, uniform: [0, 1" + "0" * 400 + "], count: 3}\n")
    assert "vary[0].uniform[1]: expected a finite number, got '1000" in refused(f, "-o", out, runner=runner)
    assert not out.exists()


def test_non_regular_and_oversized_inputs(tmp_path, runner):
    out = tmp_path / "out"
    fifo = tmp_path / "fifo.yaml"
    os.mkfifo(fifo)
    for scen, kind in (("/dev/zero", "a character device"), (str(fifo), "a FIFO"), (str(tmp_path), "a directory")):
        f = write(tmp_path, f"scenario: {scen}\nvary:\n  - {{path: simulation.dt, values: [0.01]}}\n")
        assert refused(f, "-o", out, runner=runner, timeout=20) == \
            f"{f}:1:11: scenario: cannot read '{scen}': {kind}, not a regular file"
    big = tmp_path / "big.yaml"
    with open(big, "wb") as b:
        b.truncate((16 << 20) + 1)
    f = write(tmp_path, f"scenario: {big}\nvary:\n  - {{path: simulation.dt, values: [0.01]}}\n")
    assert refused(f, "-o", out, runner=runner) == \
        f"{f}:1:11: scenario: cannot read '{big}': 16777217 bytes, more than the 16 MiB a file may have"
    # the sweep file itself
    for path, reason in (("/dev/zero", "a character device, not a regular file"), (str(fifo), "a FIFO, not a regular file"),
                         (str(big), "16777217 bytes, more than the 16 MiB a file may have")):
        assert refused(path, "-o", out, runner=runner, timeout=20) == f"{path}: cannot read the sweep file: {reason}"
    binary = tmp_path / "binary.yaml"
    binary.write_bytes(b"scenario: \xff\xfe\n")
    assert refused(binary, "-o", out, runner=runner) == f"{binary}: cannot read the sweep file: not UTF-8 text (byte 10)"
    # a base scenario nested past the limit is refused by the same scan, before the scenario parser
    deep = tmp_path / "deep.yaml"
    deep.write_text("name: x\nbodies: " + "[" * 5000 + "]" * 5000 + "\n")
    f = write(tmp_path, f"scenario: {deep}\nvary:\n  - {{path: simulation.dt, values: [0.01]}}\n")
    got = refused(f, "-o", out, runner=runner)
    assert got.startswith(f"{f}:1:11: scenario: {deep}:2:72: bodies[0][0][0]") and "…" in got, got
    assert got.endswith("[0][0]: nested more than 64 levels deep (the most a sweep file or scenario may nest)"), got
    assert not out.exists()


@pytest.fixture
def done_sweep(tmp_path):
    """a finished 6-case serial sweep: its file, its directory and its one part"""
    f = write(tmp_path, HEAD + LEAF, "ok.sweep.yaml")
    out = tmp_path / "out"
    p = sweep(f, "-o", out, "--scheduler", "serial", "--batch-size", "6", "-q")
    assert p.returncode == 0, p.stderr
    (part,) = (out / "parts").glob("*.json")
    return f, out, part


@pytest.mark.parametrize("edit, problem", [
    (lambda rows: rows[2].pop("status"), "row 3: missing column 'status'"),
    (lambda rows: rows[1].update(case=99), "row 2: case 99: out of range (the sweep has 6 cases, 0 to 5)"),
    (lambda rows: rows[0].update(case=-1), "row 1: case -1: out of range (the sweep has 6 cases, 0 to 5)"),
    (lambda rows: rows[0].update(case=True), "row 1: case: expected a case number, got true"),
    (lambda rows: rows[4].update(steps="many"), "row 5: case 4: column 'steps': expected an integer, got \"many\""),
    (lambda rows: rows[4].update(completed=1), "row 5: case 4: column 'completed': expected true or false, got 1"),
    (lambda rows: rows[3].update(extra=1), "row 4: unknown column 'extra'"),
    (lambda rows: rows[3].update(cpu_seconds=None), "row 4: case 3: column 'cpu_seconds': expected a number, got null"),
    (lambda rows: rows.clear() or rows.append(7), "row 1: expected a mapping of columns"),
])
def test_a_bad_part_is_named_and_kept(done_sweep, edit, problem):
    f, out, part = done_sweep
    rows = json.loads(part.read_text())
    edit(rows)
    part.write_text(json.dumps(rows))
    before = part.read_bytes()
    assert refused(f, "-o", out, "--scheduler", "serial") == \
        (f"{part}: {problem}: not a part this sweep wrote; run again with --drop-bad-parts to set it aside as "
         f"{part.name}.bad and run its cases again (or remove it)")
    assert part.read_bytes() == before  # neither used nor removed


def test_a_part_that_does_not_parse_is_kept_and_can_be_dropped(done_sweep):
    f, out, part = done_sweep
    part.write_bytes(part.read_bytes()[:100])  # cut short
    got = refused(f, "-o", out, "--scheduler", "serial")
    assert got.startswith(f"{part}: not valid JSON (line 1, column ") and "--drop-bad-parts" in got, got
    cut = part.read_bytes()
    p = sweep(f, "-o", out, "--scheduler", "serial", "--drop-bad-parts")
    assert p.returncode == 0, p.stderr
    assert f"set aside {part} (not valid JSON" in p.stderr and "6 cases, 0 already done" in p.stderr
    assert not part.exists() and (part.parent / (part.name + ".bad")).read_bytes() == cut
    import soadyn
    assert list(soadyn.read_results(str(out / "results.h5"))["case"]) == list(range(6))
    # a part symlinked to a device: refused, not read
    part.symlink_to("/dev/zero")
    assert refused(f, "-o", out, "--scheduler", "serial", timeout=20).startswith(
        f"{part}: a character device, not a regular file: not a part this sweep wrote")


def test_two_sweeps_into_one_new_directory(tmp_path):
    """started together: one runs, the other is refused naming it, and nothing of the first is touched"""
    long_leaf = "  - {path: initial.q.theta1, uniform: [-1.0, 1.0], count: 300}\n"
    slow = HEAD.replace("t_end: 0.05", "t_end: 2.0").replace("output_dt: 0.01", "method: rk4, simulation.dt: 1.0e-3, simulation.output_dt: 0.1")
    a = write(tmp_path, slow + long_leaf, "a.sweep.yaml")
    b = write(tmp_path, slow.replace("t_end: 2.0", "t_end: 2.5") + long_leaf, "b.sweep.yaml")
    out = tmp_path / "out"
    procs = {f: subprocess.Popen([SOADYN, "sweep", f, "-o", str(out), "--scheduler", "serial", "-q"],
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for f in (a, b)}
    res = {f: (p.wait(300), p.stderr.read(), p.pid) for f, p in procs.items()}
    (winner,) = [f for f, r in res.items() if r[0] == 0]
    (loser,) = [f for f, r in res.items() if r[0] != 0]
    assert res[loser][0] == 2 and res[winner][1] == "", res
    assert res[loser][1] == f"soadyn: error: {out}: in use by another sweep (pid {res[winner][2]}, {winner}): " \
                            "wait for it to end, or give another -o\n"
    import soadyn
    manifest = json.loads((out / "sweep.json").read_text())
    assert manifest["sweep"] == winner and manifest["fingerprint"] == soadyn.load_sweep(winner).fingerprint()
    assert sorted(os.listdir(out)) == ["parts", "results.h5", "sweep.json", "sweep.lock"]
    assert len(soadyn.read_results(str(out / "results.h5"))["case"]) == 300
    # once the first has ended, the lock is free: the other is refused for what the directory holds
    assert "holds the results of another sweep" in refused(loser, "-o", out, "--scheduler", "serial")


def test_the_lock_names_its_holder_and_is_released(tmp_path):
    """a sweep in progress (here a process holding DIR/sweep.lock as a sweep does) refuses a second"""
    f = write(tmp_path, HEAD + LEAF, "ok.sweep.yaml")
    out = tmp_path / "out"
    out.mkdir()
    holder = subprocess.Popen([sys.executable, "-c", "import fcntl, os, sys, time\n"
                               f"fd = os.open({str(out / 'sweep.lock')!r}, os.O_RDWR | os.O_CREAT)\n"
                               "fcntl.flock(fd, fcntl.LOCK_EX)\n"
                               "os.write(fd, b'pid %d\\nsweep /x/\\x1b[2Jevil\\x07.yaml\\n' % os.getpid())\n"
                               "print('locked', flush=True)\ntime.sleep(60)\n"], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline() == "locked\n"
        assert refused(f, "-o", out) == (f"{out}: in use by another sweep (pid {holder.pid}, /x/\\x1b[2Jevil\\x07.yaml): "
                                         "wait for it to end, or give another -o")
    finally:
        holder.kill()
        holder.wait()
    # the holder gone, its lock is free: a sweep takes it and writes its own pid and file
    p = subprocess.Popen([SOADYN, "sweep", f, "-o", str(out), "--scheduler", "serial", "-q"])
    assert p.wait(120) == 0
    assert (out / "sweep.lock").read_text() == f"pid {p.pid}\nsweep {f}\n"


def test_control_characters_from_files_are_shown_escaped(tmp_path, runner):
    out = tmp_path / "out"
    # a field name, a value and a scenario path from the sweep file
    f = write(tmp_path, HEAD + LEAF.replace("count", '"co\\e[31mu\\rnt"'))
    assert refused(f, "-o", out, runner=runner) == (f"{f}:4:52: vary[0].co\\x1b[31mu\\rnt: unknown field (expected one of "
                                                    "path, count, scale, values, grid, uniform, normal, log_uniform)"
                                                    ).replace("\\r", "\\x0d")
    f = write(tmp_path, HEAD + '  - {path: simulation.method, values: ["rk\\e]0;title\\a4"]}\n')
    got = refused(f, "-o", out, runner=runner)
    assert "\\x1b]0;title\\x074" in got, got
    f = write(tmp_path, 'scenario: "no\\u202ewhere\\n.yaml"\nvary: [{path: simulation.dt, values: [0.01]}]\n')
    got = refused(f, "-o", out, runner=runner)
    assert got.startswith(f"{f}:1:11: scenario: cannot read '") and "no\\u202ewhere\\x0a.yaml" in got, got
    # the manifest of another sweep names it: its text reaches the terminal escaped
    ok = write(tmp_path, HEAD + LEAF, "ok.sweep.yaml")
    out.mkdir()
    (out / "sweep.json").write_text(json.dumps({"fingerprint": "0" * 16, "sweep": "/evil\x1b[2J\nsweep.yaml"}))
    got = refused(ok, "-o", out, runner=runner)
    assert "holds the results of another sweep (/evil\\x1b[2J\\x0asweep.yaml, fingerprint 0000000000000000" in got, got
    # a sweep file named with control characters: its own name is shown escaped too
    odd = write(tmp_path, "", "odd\x1b[1m\n.yaml")
    assert refused(odd, "-o", out, runner=runner).startswith(f"{tmp_path}/odd\\x1b[1m\\x0a.yaml:1:1: scenario: missing")


def test_output_directory_siblings(tmp_path):
    f = write(tmp_path, HEAD + LEAF, "ok.sweep.yaml")
    plain = tmp_path / "a-file"
    plain.write_text("mine\n")
    assert refused(f, "-o", plain) == f"{plain}: cannot make the results directory: File exists"
    assert plain.read_text() == "mine\n"
    out = tmp_path / "out"
    out.mkdir()
    (out / "sweep.json").write_text("{not json")
    assert refused(f, "-o", out).startswith(f"{out}/sweep.json: not a sweep's manifest (")
    (out / "sweep.json").write_text("[1, 2]")
    assert refused(f, "-o", out) == f"{out}/sweep.json: not a sweep's manifest (no fingerprint): give another -o"
    (out / "sweep.json").unlink()
    (out / "sweep.lock").unlink()
    (out / "sweep.lock").symlink_to("/dev/null")
    assert refused(f, "-o", out).startswith(f"{out}/sweep.lock: cannot open the sweep's lock file: ")


def test_limits_are_documented():
    """the named limits, in the module's docstring and in src/python/README.md's sweep section"""
    import soadyn._sweep
    assert (ensemble.MAX_CASES, ensemble.MAX_CASE_VALUES, ensemble.MAX_FILE_BYTES, ensemble.MAX_YAML_DEPTH,
            ensemble.MAX_YAML_NODES) == (10 ** 6, 10 ** 7, 16 << 20, 64, 10 ** 7)
    docs = ensemble.__doc__ + soadyn._sweep.__doc__
    for words in ("10^6", "10^7", "16 MiB", "(64)", "drop-bad-parts", "sweep.lock"):
        assert words in docs, words
    readme = open(os.path.join(os.path.dirname(SCENARIOS), "src", "python", "README.md"), encoding="utf-8").read()
    section = readme[readme.index("## Ensembles: `soadyn sweep`"):]
    section = section[:section.index("\n## ")] if "\n## " in section else section
    for words in ("10⁶ cases", "10⁷ values", "16 MiB", "64 levels", "--drop-bad-parts", "sweep.lock"):
        assert words in section, words
