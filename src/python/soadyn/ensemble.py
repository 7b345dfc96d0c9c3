"""Ensembles: one scenario run many times over initial conditions, parameters and methods.

A sweep file (YAML) names a base scenario and the fields to vary by path:

    scenario: double_pendulum.yaml          # relative to the sweep file
    seed: 1                                 # the random draws' seed (default 0)
    combine: product                        # vary's entries: product (default) | zip
    set: {simulation.t_end: 2.0}            # fixed changes for every case
    vary:
      - {path: simulation.method, values: [rk4, symplectic-euler]}
      - {path: simulation.dt, grid: [1.0e-3, 1.0e-2], count: 3, scale: log}
      - zip:                                # a group: zip | product, nested freely
          - {path: initial.q.theta1, uniform: [-2, 2], count: 50}
          - {path: initial.q.theta2, normal: [0, 0.5], count: 50}
    reference: {method: cvode-adams, rtol: 1.0e-13, atol: 1.0e-14}

A case edits the scenario's YAML tree and loads it with soadyn.parse_scenario, so every field of
a scenario can vary and every value meets the scenario parser's checks.  Cases run on Dask
distributed (an embedded LocalCluster by default, or any cluster by its scheduler's address) in
batches; each finished batch is written at once to DIR/parts/, so a sweep that is stopped resumes
where it was.  The table of results is DIR/results.h5.
"""
from __future__ import annotations

import functools
import hashlib
import json
import math
import os
import re
import sys
import time
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np
import yaml

from . import _soadyn
from ._soadyn import Error, parse_scenario

RESULT_COLUMNS = ("status", "completed", "initial_energy", "t_reached", "steps", "rhs_evals", "cpu_seconds",
                  "max_energy_balance_error", "final_energy_balance_error", "state_error", "final_state_error", "reference_status")
DISTRIBUTIONS = ("values", "grid", "uniform", "normal", "log_uniform")


# ---------------------------------------------------------------- reading the sweep file

def _yaml12(base):
    """A PyYAML loader whose booleans are YAML 1.2's (true, false) as in the scenario parser: a
    joint named y or n, or dynamics: on, stays a string."""
    class Loader(base):
        pass
    Loader.yaml_implicit_resolvers = {k: [(tag, rx) for tag, rx in v if tag != "tag:yaml.org,2002:bool"]
                                      for k, v in base.yaml_implicit_resolvers.items()}
    Loader.add_implicit_resolver("tag:yaml.org,2002:bool", re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"),
                                 list("tTfF"))
    return Loader


_Loader = _yaml12(yaml.SafeLoader)
_FastLoader = _yaml12(getattr(yaml, "CSafeLoader", yaml.SafeLoader))

class _Doc:
    """A YAML document's nodes, for values and file:line:column messages."""

    def __init__(self, text: str, path: str):
        self.path = path
        self.loader = _Loader(text)
        try:
            self.root = self.loader.get_single_node()
        except yaml.YAMLError as e:
            mark = getattr(e, "problem_mark", None)
            where = f"{path}:{mark.line + 1}:{mark.column + 1}" if mark else path
            raise Error(f"{where}: not valid YAML: {getattr(e, 'problem', e)}") from None

    def where(self, node) -> str:
        m = node.start_mark
        return f"{self.path}:{m.line + 1}:{m.column + 1}"

    def fail(self, node, field: str, message: str):
        raise Error(f"{self.where(node)}: {field}: {message}")

    def value(self, node):
        return self.loader.construct_object(node, deep=True)

    def mapping(self, node, field: str, allowed: Sequence[str]) -> Dict[str, Any]:
        if not isinstance(node, yaml.MappingNode):
            self.fail(node, field, f"expected a mapping, got {_kind(node)}")
        out = {}
        for k, v in node.value:
            key = self.value(k)
            if key not in allowed:
                self.fail(k, f"{field}.{key}" if field else str(key),
                          f"unknown field (expected one of {', '.join(allowed)})")
            if key in out:
                self.fail(k, f"{field}.{key}" if field else str(key), "given twice")
            out[key] = v
        return out

    def number(self, node, field: str, positive=False, integer=False) -> float:
        v = self.value(node)
        ok = isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
        if integer:
            ok = ok and isinstance(v, int) and v >= 1
        elif positive:
            ok = ok and v > 0
        if not ok:
            what = "a positive integer" if integer else "a positive number" if positive else "a finite number"
            self.fail(node, field, f"expected {what}, got {_show(node)}")
        return v

    def pair(self, node, field: str) -> Tuple[float, float]:
        if not isinstance(node, yaml.SequenceNode) or len(node.value) != 2:
            self.fail(node, field, f"expected [a, b], got {_show(node)}")
        return self.number(node.value[0], field + "[0]"), self.number(node.value[1], field + "[1]")


def _kind(node) -> str:
    return {yaml.MappingNode: "a mapping", yaml.SequenceNode: "a list"}.get(type(node), f"'{node.value}'")


def _show(node) -> str:
    return f"'{node.value}'" if isinstance(node, yaml.ScalarNode) else _kind(node)


_SEGMENT = re.compile(r"([^.\[\]]+)((?:\[-?\d+\])*)")


def parse_path(path: str) -> List[Any]:
    """'inputs.springs[0].stiffness' -> ['inputs', 'springs', 0, 'stiffness']."""
    tokens: List[Any] = []
    for seg in path.split("."):
        m = _SEGMENT.fullmatch(seg)
        if not m:
            raise ValueError(f"bad path segment '{seg}' (expected name or name[index])")
        tokens.append(m.group(1))
        tokens += [int(i) for i in re.findall(r"\[(-?\d+)\]", m.group(2))]
    return tokens


class Leaf:
    """One varied field: its path and values (drawn at load time, so every run sees the same)."""

    def __init__(self, path: str, values: list, node, index: int, value_nodes=None):
        self.path, self.values, self.node, self.index = path, values, node, index
        self.value_nodes = value_nodes or [node] * len(values)


def _leaf(doc: _Doc, node, field: str, seed: int, counter: List[int]) -> Leaf:
    m = doc.mapping(node, field, ("path", "count", "scale") + DISTRIBUTIONS)
    if "path" not in m:
        doc.fail(node, field, "missing required field 'path'")
    path = doc.value(m["path"])
    if not isinstance(path, str):
        doc.fail(m["path"], field + ".path", f"expected a field path like bodies.upper.mass, got {_show(m['path'])}")
    try:
        parse_path(path)
    except ValueError as e:
        doc.fail(m["path"], field + ".path", str(e))
    kinds = [k for k in DISTRIBUTIONS if k in m]
    if len(kinds) != 1:
        doc.fail(node, field, f"expected exactly one of {', '.join(DISTRIBUTIONS)}, got {len(kinds)}")
    kind = kinds[0]
    index = counter[0]
    counter[0] += 1
    if kind == "values":
        if "count" in m or "scale" in m:
            doc.fail(node, field, "'values' takes no count or scale")
        if not isinstance(m["values"], yaml.SequenceNode) or not m["values"].value:
            doc.fail(m["values"], field + ".values", f"expected a non-empty list, got {_show(m['values'])}")
        return Leaf(path, [doc.value(v) for v in m["values"].value], node, index, m["values"].value)
    if "count" not in m:
        doc.fail(node, field, f"'{kind}' needs a count")
    count = doc.number(m["count"], field + ".count", integer=True)
    a, b = doc.pair(m[kind], f"{field}.{kind}")
    scale = doc.value(m["scale"]) if "scale" in m else "linear"
    if "scale" in m and (kind != "grid" or scale not in ("linear", "log")):
        doc.fail(m["scale"], field + ".scale", "expected linear or log, for a grid only")
    rng = np.random.default_rng([seed, index])  # one stream per varied field: adding one moves no other
    if kind == "grid":
        if scale == "log":
            if a <= 0 or b <= 0:
                doc.fail(m[kind], field + ".grid", f"a log grid needs positive ends, got [{a}, {b}]")
            values = np.geomspace(a, b, count)
        else:
            values = np.linspace(a, b, count)
    elif kind == "uniform":
        if not a < b:
            doc.fail(m[kind], field + ".uniform", f"expected [low, high] with low < high, got [{a}, {b}]")
        values = rng.uniform(a, b, count)
    elif kind == "log_uniform":
        if not 0 < a < b:
            doc.fail(m[kind], field + ".log_uniform", f"expected [low, high] with 0 < low < high, got [{a}, {b}]")
        values = np.exp(rng.uniform(math.log(a), math.log(b), count))
    else:
        if b < 0:
            doc.fail(m[kind].value[1], field + ".normal[1]", f"expected a standard deviation >= 0, got {b}")
        values = rng.normal(a, b, count)
    return Leaf(path, [float(v) for v in values], node, index)


def _combine(doc: _Doc, nodes, field: str, how: str, seed: int, counter: List[int]):
    """The cases of a group: a list of {path: value} dicts, and its leaves."""
    parts, leaves = [], []
    for k, node in enumerate(nodes):
        f = f"{field}[{k}]"
        if isinstance(node, yaml.MappingNode) and len(node.value) == 1 and doc.value(node.value[0][0]) in ("zip", "product"):
            sub_how = doc.value(node.value[0][0])
            members = node.value[0][1]
            if not isinstance(members, yaml.SequenceNode) or not members.value:
                doc.fail(members, f"{f}.{sub_how}", f"expected a non-empty list of varied fields, got {_show(members)}")
            cases, sub = _combine(doc, members.value, f"{f}.{sub_how}", sub_how, seed, counter)
        else:
            leaf = _leaf(doc, node, f, seed, counter)
            cases, sub = [{leaf.path: v} for v in leaf.values], [leaf]
        parts.append((node, f, cases))
        leaves += sub
    if how == "zip":
        n = len(parts[0][2])
        for node, f, cases in parts[1:]:
            if len(cases) != n:
                doc.fail(node, f, f"zip needs equal lengths: {len(cases)} cases here, {n} in {parts[0][1]}")
        out = [dict(kv for c in combo for kv in c.items()) for combo in zip(*(p[2] for p in parts))]
    else:
        out = [{}]
        for _, _, cases in parts:  # the first entry varies slowest
            out = [dict(a, **b) for a in out for b in cases]
    seen = {}
    for leaf in leaves:
        if leaf.path in seen:
            doc.fail(leaf.node, "path", f"'{leaf.path}' is varied twice (also at {doc.where(seen[leaf.path])})")
        seen[leaf.path] = leaf.node
    return out, leaves


class Sweep:
    """A loaded sweep file: the base scenario, the cases and the reference settings.

    cases[i] is {path: value}; settings are the fixed changes; reference maps simulation fields to
    the reference run's values (None: no reference)."""

    path: str = ""
    scenario_path: str = ""
    cases: List[Dict[str, Any]] = []
    paths: List[str] = []
    settings: Dict[str, Any] = {}
    reference: Optional[Dict[str, Any]] = None

    def __init__(self, path: str, text: Optional[str] = None):
        self.path = str(path)
        if text is None:
            try:
                with open(self.path, encoding="utf-8") as f:
                    text = f.read()
            except OSError as e:
                raise Error(f"{self.path}: cannot read the sweep file: {e.strerror}") from None
        self.text = text
        doc = _Doc(text, self.path)
        top = doc.mapping(doc.root, "", ("scenario", "seed", "combine", "set", "vary", "reference", "name"))
        if "scenario" not in top:
            doc.fail(doc.root, "scenario", "missing required field (the base scenario's file)")
        scen = doc.value(top["scenario"])
        if not isinstance(scen, str):
            doc.fail(top["scenario"], "scenario", f"expected a file name, got {_show(top['scenario'])}")
        self.scenario_path = os.path.join(os.path.dirname(self.path), scen)
        try:
            with open(self.scenario_path, encoding="utf-8") as f:
                self.scenario_text = f.read()
        except OSError as e:
            doc.fail(top["scenario"], "scenario", f"cannot read '{self.scenario_path}': {e.strerror}")
        try:
            base = parse_scenario(self.scenario_text, self.scenario_path)
        except Error as e:
            doc.fail(top["scenario"], "scenario", str(e))
        self.model = base.model
        self.tree = yaml.load(self.scenario_text, Loader=_FastLoader)
        self.name = doc.value(top["name"]) if "name" in top else os.path.basename(self.path).split(".")[0]
        self.seed = int(doc.number(top["seed"], "seed")) if "seed" in top else 0
        how = doc.value(top["combine"]) if "combine" in top else "product"
        if how not in ("product", "zip"):
            doc.fail(top["combine"], "combine", f"expected product or zip, got {_show(top['combine'])}")
        self.settings: Dict[str, Any] = {}
        if "set" in top:
            for k, v in doc.mapping(top["set"], "set", _AnyKey()).items():
                self.settings[k] = doc.value(v)
                self._check(doc, v, f"set.{k}", {k: self.settings[k]})
        if "vary" not in top or not isinstance(top["vary"], yaml.SequenceNode) or not top["vary"].value:
            doc.fail(top.get("vary", doc.root), "vary", "expected a non-empty list of varied fields")
        self.cases, self.leaves = _combine(doc, top["vary"].value, "vary", how, self.seed, [0])
        self.paths = [leaf.path for leaf in self.leaves]
        for leaf in self.leaves:
            for f in ("path",) if leaf.path in self.settings else ():
                doc.fail(leaf.node, f, f"'{leaf.path}' is both set and varied")
            # every listed value, or the first draw, must make a scenario that runs
            n = len(leaf.values) if isinstance(leaf.values[0], str) or len(leaf.values) <= 16 else 1
            for v, node in zip(leaf.values[:n], leaf.value_nodes[:n]):
                self._check(doc, node, leaf.path, dict(self.settings, **{leaf.path: v}))
        self.reference = None
        if "reference" in top:
            ref = doc.mapping(top["reference"], "reference", ("method", "rtol", "atol", "dt", "max_step", "max_steps", "dynamics"))
            self.reference = {k: doc.value(v) for k, v in ref.items()}
            self._check(doc, top["reference"], "reference",
                        dict(self.settings, **{f"simulation.{k}": v for k, v in self.reference.items()}))

    def _check(self, doc: _Doc, node, field: str, values: Dict[str, Any]):
        try:
            scene = self.scenario(values, settings=False)
            s = scene.settings
            from . import simulate
            simulate(scene, t_end=min(s.t_end, s.output_dt))  # refuses a bad method or step
        except (Error, ValueError, TypeError) as e:
            message = _CASE_PREFIX.sub("", str(e))  # its line numbers are the edited tree's
            raise Error(f"{doc.where(node)}: {message if message.startswith(field + ':') else field + ': ' + message}") from None

    def fingerprint(self) -> str:
        h = hashlib.sha256()
        for part in (self.text, self.scenario_text, _soadyn.__version__):
            h.update(part.encode())
            h.update(b"\0")
        return h.hexdigest()[:16]

    def scenario(self, case: Dict[str, Any], settings=True):
        """The case's Scenario (raises soadyn.Error or ValueError if its values make a bad scenario)."""
        values = dict(self.settings, **case) if settings else case
        return parse_scenario(_text(apply(self.tree, self.model, values)), case_path(self.scenario_path))


def _text(tree: dict) -> str:
    """A scenario tree as text for the parser: JSON, which is YAML (and 100× faster than PyYAML's dump)."""
    return json.dumps(tree, allow_nan=False)


_CASE_PREFIX = re.compile(r"^.*?<case>:\d+:\d+: ")


def case_path(scenario_path: str) -> str:
    """The name a case's edited scenario is parsed under: beside the base (a relative urdf: holds)."""
    return os.path.join(os.path.dirname(scenario_path), "<case>")


class _AnyKey:
    def __contains__(self, key):
        return isinstance(key, str)

    def __iter__(self):
        return iter(["a field path"])


def load_sweep(path: str) -> Sweep:
    """Read and check a sweep file; raises soadyn.Error with file:line:column: field: message."""
    return Sweep(path)


# ---------------------------------------------------------------- applying a case to the scenario tree

def _vector_slot(model, which: str, index: int):
    """(joint name, component or None for a 1-DOF joint, the joint's neutral entries) of q[index]
    or qd[index], from the model's coordinate names (joint, or joint.component)."""
    names = list(model.q_names if which == "q" else model.v_names)
    if not -len(names) <= index < len(names):
        raise ValueError(f"initial.{which}[{index}]: index out of range (the model has {len(names)})")
    index %= len(names)
    joint = names[index] if names[index] in model.joint_names else names[index].rsplit(".", 1)[0]
    if joint == names[index]:
        return joint, None, None
    first = next(k for k, n in enumerate(names) if n.startswith(joint + "."))
    count = sum(1 for n in names if n.startswith(joint + "."))
    neutral = [float(x) for x in model.neutral()[first:first + count]] if which == "q" else [0.0] * count
    return joint, index - first, neutral


class _Copy:
    """A copy of a scenario tree that shares every container it has not edited with the base
    (path copying: an edit copies only the mappings and lists on its path, not the whole tree)."""

    def __init__(self, tree: dict):
        self.root = dict(tree)
        self._own = {id(self.root)}

    def child(self, node, key, default=None):
        """node[key] made this copy's own (node itself must be); `default` (a new container) when
        it is absent or null, None when it is absent and there is no default."""
        value = node.get(key) if isinstance(node, dict) else node[key]
        if value is None and default is not None:
            value = default
        elif isinstance(value, (dict, list)) and id(value) not in self._own:
            value = dict(value) if isinstance(value, dict) else list(value)
        else:
            return value
        node[key] = value
        self._own.add(id(value))
        return value


@functools.lru_cache(maxsize=4096)
def _tokens(path: str) -> Tuple[Any, ...]:
    return tuple(parse_path(path))


def apply(tree: dict, model, values: Dict[str, Any]) -> dict:
    """A copy of the scenario tree with each {path: value} set (the base tree is left unchanged)."""
    out = _Copy(tree)
    for path, value in values.items():
        tokens = _tokens(path)
        if len(tokens) == 3 and tokens[0] == "initial" and tokens[1] in ("q", "qd") and isinstance(tokens[2], int):
            joint, comp, neutral = _vector_slot(model, tokens[1], tokens[2])
            vec = out.child(out.child(out.root, "initial", {}), tokens[1], {})
            if comp is None:
                vec[joint] = value
            else:
                cur = list(vec.get(joint, neutral))
                cur[comp] = value
                vec[joint] = cur
            continue
        node = out.root
        for i, tok in enumerate(tokens):
            last = i == len(tokens) - 1
            where = ".".join(str(t) for t in tokens[:i + 1])
            if isinstance(tok, int):
                if not isinstance(node, list) or not -len(node) <= tok < len(node):
                    raise ValueError(f"{where}: no entry [{tok}] (the scenario has "
                                     f"{len(node) if isinstance(node, list) else 'no list'} here)")
                if last:
                    node[tok] = value
                else:
                    node = out.child(node, tok)
            elif isinstance(node, list):  # a list entry by its name (bodies) or joint (inputs)
                match = [k for k, e in enumerate(node) if isinstance(e, dict) and tok in (e.get("name"), e.get("joint"))]
                if len(match) != 1:
                    names = [str(e.get("name", e.get("joint"))) for e in node if isinstance(e, dict)]
                    raise ValueError(f"{'no' if not match else 'more than one'} entry named '{tok}' "
                                     f"(the scenario has {', '.join(names)})")
                if last:
                    raise ValueError(f"{where} names a whole entry; name a field of it")
                node = out.child(node, match[0])
            elif isinstance(node, dict):
                if last:
                    node[tok] = value
                else:
                    if node.get(tok) is None:
                        if tok in ("initial", "simulation", "q", "qd"):
                            node = out.child(node, tok, {})
                            continue
                        raise ValueError(f"the scenario has no '{where}'")
                    node = out.child(node, tok)
            else:
                raise ValueError(f"'{'.'.join(str(t) for t in tokens[:i])}' is a value, not a mapping or list")
    return out.root


# ---------------------------------------------------------------- running cases (on a worker)

def _state(traj) -> np.ndarray:
    return np.hstack([traj.q, traj.v])


def run_case(sweep_tree: dict, model, scenario_path: str, values: Dict[str, Any],
             reference: Optional[Dict[str, Any]] = None, log: Optional[str] = None,
             cache: Optional[dict] = None) -> Dict[str, Any]:
    """One case's row: status, steps, RHS evaluations, CPU time, energy errors, state error
    against the reference run (max over the common output samples, and at t_end)."""
    from . import simulate
    row: Dict[str, Any] = {"status": "", "completed": False, "initial_energy": math.nan, "t_reached": math.nan,
                           "steps": 0, "rhs_evals": 0,
                           "cpu_seconds": math.nan, "max_energy_balance_error": math.nan, "final_energy_balance_error": math.nan,
                           "state_error": math.nan, "final_state_error": math.nan, "reference_status": ""}
    try:
        tree = apply(sweep_tree, model, values)
        scene = parse_scenario(_text(tree), case_path(scenario_path))
        traj = simulate(scene, output=log)
    except (Error, ValueError) as e:
        row["status"] = "refused: " + _CASE_PREFIX.sub("", str(e))
        return row
    s = traj.summary
    row.update(status=s.status, completed=bool(s.completed), t_reached=s.t_reached,
               initial_energy=float(traj.total_energy[0]) if len(traj.t) else math.nan, steps=s.steps,
               rhs_evals=s.rhs_evals, cpu_seconds=s.cpu_seconds, max_energy_balance_error=s.max_energy_balance_error,
               final_energy_balance_error=s.final_energy_balance_error)
    if reference:
        rtree = _Copy(tree)
        rtree.child(rtree.root, "simulation", {}).update(reference)
        key = _text(rtree.root)
        if cache is not None and key in cache:
            rstatus, ref = cache[key]
        else:
            try:
                rtraj = simulate(parse_scenario(key, case_path(scenario_path)))
                rstatus, ref = rtraj.summary.status, (rtraj.t, _state(rtraj), rtraj.summary.completed)
            except (Error, ValueError) as e:
                rstatus, ref = "refused: " + _CASE_PREFIX.sub("", str(e)), None
            if cache is not None:
                cache[key] = (rstatus, ref)
        row["reference_status"] = rstatus
        if ref is not None:
            t_ref, y_ref, ref_done = ref
            y = _state(traj)
            # the samples at common times (a step that does not divide output_dt samples at step
            # times; every run that completes has its last sample at t_end)
            k = np.clip(np.searchsorted(t_ref, traj.t), 0, len(t_ref) - 1)
            same = np.abs(t_ref[k] - traj.t) <= 1e-12 * np.maximum(1.0, np.abs(traj.t))
            if np.any(same):
                diff = np.abs(y[same] - y_ref[k[same]])
                row["state_error"] = float(np.max(diff)) if np.all(np.isfinite(diff)) else math.inf
            if s.completed and ref_done:
                row["final_state_error"] = float(np.max(np.abs(y[-1] - y_ref[-1])))
    return row


def run_batch(scenario_text: str, scenario_path: str, settings: Dict[str, Any],
              cases: List[Tuple[int, Dict[str, Any]]], reference: Optional[Dict[str, Any]],
              logs_dir: Optional[str] = None) -> List[Dict[str, Any]]:
    """A Dask task: run the given (case id, values) and return their rows.  Pure: the same input
    gives the same rows (CPU times aside), whichever worker runs it and however often."""
    tree = yaml.load(scenario_text, Loader=_FastLoader)
    model = parse_scenario(scenario_text, case_path(scenario_path)).model
    cache: dict = {}
    rows = []
    for cid, values in cases:
        log = None
        if logs_dir:
            os.makedirs(logs_dir, exist_ok=True)
            log = os.path.join(logs_dir, f"case-{cid:07d}.h5")
        row = run_case(tree, model, scenario_path, dict(settings, **values), reference, log, cache)
        row["case"] = cid
        rows.append(row)
    return rows
