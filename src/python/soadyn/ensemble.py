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

Limits (a file past one is refused, naming file:line:column and the field, before anything
proportional to it is drawn or built): MAX_CASES cases (10^6), MAX_CASE_VALUES varied values
(cases × varied fields, 10^7), MAX_FILE_BYTES for the sweep file and the base scenario (16 MiB,
regular files only: no device, FIFO or directory), MAX_YAML_DEPTH levels of nesting (64) and
MAX_YAML_NODES nodes in a document, each alias counted as the nodes it stands for (10^7: an
alias bomb is refused, not expanded).  The seed is an integer from 0 to 2^64 - 1.
"""
from __future__ import annotations

import hashlib
import itertools
import math
import os
from typing import Any, Dict, List, Optional, Tuple

import numpy as np
import yaml

from . import _soadyn
from ._batched import run_batch  # noqa: F401
from ._cases import RESULT_COLUMNS, _CASE_PREFIX, _text, apply, case_path, parse_path, run_case  # noqa: F401
from ._soadyn import Error, SimulationSettings, parse_scenario
from ._yaml_doc import (MAX_FILE_BYTES, MAX_YAML_DEPTH, MAX_YAML_NODES, _Doc, _FastLoader, _clip, _plain,  # noqa: F401
                        _show, check_yaml, printable, read_text)

DISTRIBUTIONS = ("values", "grid", "uniform", "normal", "log_uniform")

MAX_CASES = 1_000_000            # cases in one sweep
MAX_CASE_VALUES = 10_000_000     # cases × varied fields: the values the cases hold
MAX_SEED = 2 ** 64 - 1
# MAX_FILE_BYTES, MAX_YAML_DEPTH and MAX_YAML_NODES: _yaml_doc.py, which reads the files


# ---------------------------------------------------------------- reading the sweep file

class Leaf:
    """One varied field: its path and values (drawn at load time, so every run sees the same)."""

    def __init__(self, path: str, values: list, node, index: int, value_nodes=None):
        self.path, self.values, self.node, self.index = path, values, node, index
        self.value_nodes = value_nodes or [node] * len(values)


def _leaf_spec(doc: _Doc, node, field: str):
    """A varied field's entry read and checked, nothing drawn: (its mapping, path, kind, count)."""
    m = doc.mapping(node, field, ("path", "count", "scale") + DISTRIBUTIONS)
    if "path" not in m:
        doc.fail(node, field, "missing required field 'path'")
    path = doc.value(m["path"], field + ".path")
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
    if kind == "values":
        if "count" in m or "scale" in m:
            doc.fail(node, field, "'values' takes no count or scale")
        if not isinstance(m["values"], yaml.SequenceNode) or not m["values"].value:
            doc.fail(m["values"], field + ".values", f"expected a non-empty list, got {_show(m['values'])}")
        count = len(m["values"].value)
        if count > MAX_CASES:
            doc.fail(m["values"], field + ".values", f"{count} values, more than the {MAX_CASES} cases a sweep may have")
        return m, path, kind, count
    if "count" not in m:
        doc.fail(node, field, f"'{kind}' needs a count")
    count = doc.integer(m["count"], field + ".count", 1, None, "a positive integer")
    if count > MAX_CASES:
        doc.fail(m["count"], field + ".count", f"{count} cases, more than the {MAX_CASES} a sweep may have")
    return m, path, kind, count


def _leaf(doc: _Doc, node, field: str, seed: int, counter: List[int]) -> Leaf:
    m, path, kind, count = _leaf_spec(doc, node, field)
    index = counter[0]
    counter[0] += 1
    if kind == "values":
        values = []
        for k, v in enumerate(m["values"].value):
            values.append(doc.value(v, f"{field}.values[{k}]"))
            bad = _plain(values[-1])
            if bad:
                doc.fail(v, f"{field}.values[{k}]", bad)
        return Leaf(path, values, node, index, m["values"].value)
    a, b = doc.pair(m[kind], f"{field}.{kind}")
    scale = doc.value(m["scale"], field + ".scale") if "scale" in m else "linear"
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


def _group(doc: _Doc, node, field: str):
    """(how, members) of a group entry {zip: [...]} or {product: [...]}; None for a varied field"""
    if not (isinstance(node, yaml.MappingNode) and len(node.value) == 1):
        return None
    how = doc.value(node.value[0][0], field)
    if how not in ("zip", "product"):
        return None
    members = node.value[0][1]
    if not isinstance(members, yaml.SequenceNode) or not members.value:
        doc.fail(members, f"{field}.{how}", f"expected a non-empty list of varied fields, got {_show(members)}")
    return how, members


def _count(doc: _Doc, node, field: str, how: str, seen: Dict[str, Any]) -> Tuple[int, int]:
    """A group's (cases, varied fields), from the counts and the lengths of the value lists alone:
    checked against MAX_CASES and MAX_CASE_VALUES before anything is drawn or combined.  `node` is
    the group's list of entries; each varied path goes in `seen`."""
    sizes, fields = [], 0
    for k, entry in enumerate(node.value):
        f = f"{field}[{k}]"
        group = _group(doc, entry, f)
        if group:
            n, nf = _count(doc, group[1], f"{f}.{group[0]}", group[0], seen)
        else:
            _, path, _, n = _leaf_spec(doc, entry, f)
            if path in seen:
                doc.fail(entry, "path", f"'{_clip(path)}' is varied twice (also at {doc.where(seen[path])})")
            seen[path] = entry
            nf = 1
        sizes.append((entry, f, n))
        fields += nf
    if how == "zip":
        cases = sizes[0][2]
        for entry, f, n in sizes[1:]:
            if n != cases:
                doc.fail(entry, f, f"zip needs equal lengths: {n} cases here, {cases} in {sizes[0][1]}")
        shown = f"{cases} cases"
    else:
        cases = 1
        for _, _, n in sizes:
            cases *= n
            if cases > MAX_CASES ** 3:  # far past the limit: the exact number would only grow
                break
        factors = [str(n) for _, _, n in sizes]
        shown = f"{cases} cases ({' × '.join(factors)})" if 1 < len(factors) <= 8 else f"{cases} cases"
        if cases > MAX_CASES ** 3:
            shown = f"more than {MAX_CASES ** 3} cases"
    if cases > MAX_CASES:
        doc.fail(node, field, f"{shown}, more than the {MAX_CASES} a sweep may have")
    if cases * fields > MAX_CASE_VALUES:
        doc.fail(node, field, f"{shown} × {fields} varied fields = {cases * fields} values, more than the "
                              f"{MAX_CASE_VALUES} a sweep may hold")
    return cases, fields


def _columns(doc: _Doc, node, field: str, how: str, seed: int, counter: List[int]):
    """A group's varied fields as columns: (leaves, one list of values per leaf, cases)."""
    parts = []
    for k, entry in enumerate(node.value):
        f = f"{field}[{k}]"
        group = _group(doc, entry, f)
        if group:
            parts.append(_columns(doc, group[1], f"{f}.{group[0]}", group[0], seed, counter))
        else:
            leaf = _leaf(doc, entry, f, seed, counter)
            parts.append(([leaf], [leaf.values], len(leaf.values)))
    leaves = [leaf for p in parts for leaf in p[0]]
    if how == "zip":  # _count checked the lengths
        return leaves, [c for p in parts for c in p[1]], parts[0][2]
    # product, the first entry varying slowest: an entry's values each repeated for every case of
    # the entries after it, that block repeated for every case of the entries before it
    total = math.prod(p[2] for p in parts)
    columns, before = [], 1
    for _, cols, n in parts:
        after = total // (before * n)
        for c in cols:
            columns.append(list(itertools.chain.from_iterable(itertools.repeat(v, after) for v in c)) * before)
        before *= n
    return leaves, columns, total


def _combine(doc: _Doc, node, field: str, how: str, seed: int):
    """The cases of the vary list `node`: a list of {path: value} dicts, and its leaves."""
    _count(doc, node, field, how, {})
    leaves, columns, _ = _columns(doc, node, field, how, seed, [0])
    paths = [leaf.path for leaf in leaves]
    return [dict(zip(paths, row)) for row in zip(*columns)], leaves


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
                text = read_text(self.path)
            except ValueError as e:
                raise Error(f"{self.path}: cannot read the sweep file: {e}") from None
        self.text = text
        doc = _Doc(text, self.path)
        if doc.root is None:
            raise Error(f"{self.path}:1:1: scenario: missing required field: the sweep file is empty (expected a "
                        "mapping with scenario and vary)")
        top = doc.mapping(doc.root, "", ("scenario", "seed", "combine", "set", "vary", "reference", "name"))
        if "scenario" not in top:
            doc.fail(doc.root, "scenario", "missing required field (the base scenario's file)")
        scen = doc.value(top["scenario"], "scenario")
        if not isinstance(scen, str):
            doc.fail(top["scenario"], "scenario", f"expected a file name, got {_show(top['scenario'])}")
        self.scenario_path = os.path.join(os.path.dirname(self.path), scen)
        try:
            self.scenario_text = read_text(self.scenario_path)
        except ValueError as e:
            doc.fail(top["scenario"], "scenario", f"cannot read '{_clip(self.scenario_path, 200)}': {e}")
        try:
            check_yaml(self.scenario_text, self.scenario_path)  # the same bounds on nesting and aliases
            base = parse_scenario(self.scenario_text, self.scenario_path)
        except Error as e:
            doc.fail(top["scenario"], "scenario", str(e))
        self.model = base.model
        self.tree = yaml.load(self.scenario_text, Loader=_FastLoader)
        self.name = doc.value(top["name"], "name") if "name" in top else os.path.basename(self.path).split(".")[0]
        self.seed = doc.integer(top["seed"], "seed", 0, MAX_SEED, "an integer from 0 to 2^64 - 1") if "seed" in top else 0
        how = doc.value(top["combine"], "combine") if "combine" in top else "product"
        if how not in ("product", "zip"):
            doc.fail(top["combine"], "combine", f"expected product or zip, got {_show(top['combine'])}")
        self.settings: Dict[str, Any] = {}
        if "set" in top:
            for k, v in doc.mapping(top["set"], "set", _AnyKey()).items():
                self.settings[k] = doc.value(v, f"set.{k}")
                bad = _plain(self.settings[k])
                if bad:
                    doc.fail(v, f"set.{k}", bad)
                self._check(doc, v, f"set.{k}", {k: self.settings[k]})
        if "vary" not in top or not isinstance(top["vary"], yaml.SequenceNode) or not top["vary"].value:
            doc.fail(top.get("vary", doc.root), "vary", "expected a non-empty list of varied fields")
        self.cases, self.leaves = _combine(doc, top["vary"], "vary", how, self.seed)

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
            ref = doc.mapping(top["reference"], "reference", SimulationSettings.integration_names)
            self.reference = {}
            for k, v in ref.items():
                self.reference[k] = doc.value(v, f"reference.{k}")
                bad = _plain(self.reference[k])
                if bad:
                    doc.fail(v, f"reference.{k}", bad)
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


class _AnyKey:
    def __contains__(self, key):
        return isinstance(key, str)

    def __iter__(self):
        return iter(["a field path"])


def load_sweep(path: str) -> Sweep:
    """Read and check a sweep file; raises soadyn.Error with file:line:column: field: message."""
    return Sweep(path)
