"""One table of simulation settings (include/soadyn/sim/settings.hpp): every setting it declares is a
scenario key, a soadyn run option, a SimulationSettings attribute, a simulate() keyword and a /solver
attribute of the run file, each carrying the value given to it."""
import inspect
import os

import h5py
import pytest

import soadyn
from conftest import SCENARIOS, cli

# a valid value other than the default for each setting; a setting added to the table without a
# value here fails test_every_setting_has_a_test_value
VALUES = {"t_end": 0.04, "output_dt": 0.02, "method": "cvode-bdf", "rtol": 1e-6, "atol": 1e-9, "dt": 0.002,
          "max_step": 0.01, "max_steps": 12345, "dynamics": "dense", "jacobian": "dq", "newton": "simplified",
          "limits": True, "restitution": 0.5, "control_dt": 0.01}


def test_every_setting_has_a_test_value():
    assert set(soadyn.SimulationSettings.names) == set(VALUES)
    defaults = soadyn.SimulationSettings()
    for name, value in VALUES.items():
        assert getattr(defaults, name) != value, f"{name}: the test value is the default"


def test_simulate_keyword_reaches_the_run_file(tmp_path):
    keywords = inspect.signature(soadyn.simulate).parameters
    scene = soadyn.load_scenario(os.path.join(SCENARIOS, "double_pendulum.yaml"))
    for name in soadyn.SimulationSettings.names:
        assert name in keywords, f"simulate() has no keyword for the setting {name}"
    out = tmp_path / "run.h5"
    soadyn.simulate(scene, output=str(out), **VALUES)
    with h5py.File(out, "r") as f:
        solver = f["/solver"].attrs
        for name, value in VALUES.items():
            got = solver[name]
            got = got.decode() if isinstance(got, bytes) else got
            expected = ("true" if value else "false") if isinstance(value, bool) else value
            if isinstance(value, str) or isinstance(value, bool):
                assert got == expected, name
            else:
                assert float(got) == pytest.approx(float(expected), rel=1e-15), name


def test_scenario_key_and_attribute():
    base = open(os.path.join(SCENARIOS, "double_pendulum.yaml")).read()
    assert "simulation:" in base
    lines = "".join(f"\n  {k}: {str(v).lower() if isinstance(v, bool) else v}" for k, v in VALUES.items())
    text = base.replace("simulation:", "simulation:" + lines, 1)
    # the scene's own keys under simulation: come after ours; drop duplicates of ours
    kept, seen, in_sim = [], set(), False
    for line in text.splitlines():
        if line.startswith("simulation:"):
            in_sim = True
        elif line and not line.startswith(" "):
            in_sim = False
        key = line.strip().split(":")[0] if in_sim and line.startswith("  ") and not line.startswith("    ") else None
        if key in seen:
            continue
        if key:
            seen.add(key)
        kept.append(line)
    scene = soadyn.parse_scenario("\n".join(kept) + "\n", "settings.yaml")
    for name, value in VALUES.items():
        assert getattr(scene.settings, name) == value, name
    # the O(N) route's old word is taken and stored as its new one
    scene = soadyn.parse_scenario(base.replace("simulation:", "simulation:\n  dynamics: on", 1), "on.yaml")
    assert scene.settings.dynamics == "aba"


def test_every_setting_is_a_run_option():
    help_text = cli("run", "--help").stdout
    for name in soadyn.SimulationSettings.names:
        assert "--" + name.replace("_", "-") + " " in help_text, name


def test_run_option_refusals_name_the_option(tmp_path):
    p = cli("run", os.path.join(SCENARIOS, "double_pendulum.yaml"), "-o", str(tmp_path / "x.h5"), "--restitution", "2")
    assert p.returncode != 0 and "--restitution: expected a coefficient in [0, 1], got '2'" in p.stderr
    assert not (tmp_path / "x.h5").exists()
    p = cli("run", os.path.join(SCENARIOS, "double_pendulum.yaml"), "-o", str(tmp_path / "x.h5"), "--max-steps", "1.5")
    assert p.returncode != 0 and "--max-steps: expected a whole number, got '1.5'" in p.stderr


def test_every_word_round_trips(tmp_path):
    """The word-valued settings are enums inside the library: each word they take comes back as
    itself from the attribute, a pickle, a scenario key and the run file's /solver."""
    import pickle
    words = soadyn.SimulationSettings.words
    assert set(words) == {"method", "dynamics", "jacobian", "newton"}
    assert words["method"] == soadyn.METHODS and set(words["dynamics"]) == set(soadyn.DYNAMICS)
    assert words["jacobian"] == ("analytic", "dq") and words["newton"] == ("full", "simplified")
    path = os.path.join(SCENARIOS, "double_pendulum.yaml")
    base = "".join(line for line in open(path) if not line.startswith("  method:"))  # its simulation: sets one
    scene = soadyn.load_scenario(path)
    for name, taken in words.items():
        for word in taken:
            s = soadyn.SimulationSettings()
            setattr(s, name, word)
            assert getattr(s, name) == word, (name, word)
            scene.settings.method = "cvode-adams"
            setattr(scene.settings, name, word)
            assert getattr(pickle.loads(pickle.dumps(scene)).settings, name) == word, (name, word)
            sc = soadyn.parse_scenario(base.replace("simulation:", f"simulation:\n  {name}: {word}", 1), "words.yaml")
            assert getattr(sc.settings, name) == word, (name, word)
            kw = {name: word, "t_end": 0.01, "output_dt": 0.01}
            if name != "method":  # a method that reads the setting
                kw["method"] = "implicit-midpoint" if name == "newton" else "cvode-bdf"
            out = tmp_path / f"{name}-{word}.h5"
            assert soadyn.simulate(sc, output=str(out), **kw).summary.method == kw.get("method", word)
            with h5py.File(out, "r") as f:
                got = f["/solver"].attrs[name]
                assert (got.decode() if isinstance(got, bytes) else got) == word, (name, word)
    # an unknown word is refused where it comes in, in the scenario reader's words; the old one is taken
    s = soadyn.SimulationSettings()
    with pytest.raises(soadyn.Error, match=r"^method: unknown method 'rk5'; did you mean 'rk4'\?$"):
        s.method = "rk5"
    with pytest.raises(soadyn.Error, match=r"^jacobian: expected analytic or dq, got 'numeric'"):
        s.jacobian = "numeric"
    assert s.method == "cvode-adams" and s.jacobian == "analytic"
    s.dynamics = "on"
    assert s.dynamics == "aba"


def _stub():
    """soadyn/__init__.pyi as a syntax tree: its SimulationSettings attributes and simulate()'s keywords"""
    import ast
    tree = ast.parse(open(os.path.join(os.path.dirname(soadyn.__file__), "__init__.pyi")).read())
    attributes, keywords = set(), set()
    for node in tree.body:
        if isinstance(node, ast.ClassDef) and node.name == "SimulationSettings":
            attributes = {n.target.id for n in node.body if isinstance(n, ast.AnnAssign)}
        if isinstance(node, ast.FunctionDef) and node.name == "simulate":
            keywords = {a.arg for a in node.args.args + node.args.kwonlyargs}
    return attributes, keywords


def test_every_setting_is_in_the_stub():
    """The .pyi restates the table for type checkers: a setting added to the table and not there fails"""
    attributes, keywords = _stub()
    for name in soadyn.SimulationSettings.names:
        assert name in attributes, f"__init__.pyi: SimulationSettings has no attribute {name}"
        assert name in keywords, f"__init__.pyi: simulate() has no keyword {name}"
    # and nothing the table does not declare
    own = {"names", "words", "integration_names", "sensitivities"}
    assert attributes - own == set(soadyn.SimulationSettings.names)


def test_every_setting_is_a_sweep_path(tmp_path):
    """A sweep varies simulation.<name> for every setting of the table (the scenario parser reads each),
    and its reference run takes the integration settings, whose names come from the table too"""
    from soadyn import ensemble
    names = soadyn.SimulationSettings.names
    integration = soadyn.SimulationSettings.integration_names
    assert set(integration) < set(names)
    assert {"method", "rtol", "atol", "dt", "max_step", "max_steps", "dynamics"} <= set(integration)
    scene = os.path.join(SCENARIOS, "double_pendulum.yaml")

    def word(value):
        return str(value).lower() if isinstance(value, bool) else value
    ref = "".join(f"  {k}: {word(VALUES[k])}\n" for k in integration)
    for name in names:
        fixed = ", ".join(f"simulation.{k}: {v}" for k, v in (("t_end", 0.04), ("output_dt", 0.02), ("method", "cvode-bdf"))
                          if k != name)
        p = tmp_path / f"{name}.sweep.yaml"
        p.write_text(f"scenario: {scene}\nset: {{{fixed}}}\n"
                     f"vary:\n  - {{path: simulation.{name}, values: [{word(VALUES[name])}]}}\nreference:\n{ref}")
        sweep = ensemble.load_sweep(str(p))
        assert sweep.paths == [f"simulation.{name}"] and set(sweep.reference) == set(integration)
