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

import functools
import hashlib
import itertools
import json
import math
import os
import re
import stat
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np
import yaml

from . import _soadyn
from ._soadyn import Error, parse_scenario

RESULT_COLUMNS = ("status", "completed", "initial_energy", "t_reached", "steps", "rhs_evals", "cpu_seconds",
                  "max_energy_balance_error", "final_energy_balance_error", "state_error", "final_state_error", "reference_status")
DISTRIBUTIONS = ("values", "grid", "uniform", "normal", "log_uniform")

MAX_CASES = 1_000_000            # cases in one sweep
MAX_CASE_VALUES = 10_000_000     # cases × varied fields: the values the cases hold
MAX_FILE_BYTES = 16 << 20        # a sweep file, a base scenario
MAX_YAML_DEPTH = 64              # nested mappings and lists in a YAML document
MAX_YAML_NODES = 10_000_000      # a YAML document's nodes, each alias counted as what it stands for
MAX_SEED = 2 ** 64 - 1


# ---------------------------------------------------------------- text from files, text to a terminal

_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f\u061c\u200e\u200f\u202a-\u202e\u2066-\u2069\ud800-\udfff]")


def _escape(m) -> str:
    c = ord(m.group())
    if 0xdc80 <= c <= 0xdcff:  # a byte that was not UTF-8 (os.fsdecode's surrogateescape)
        return f"\\x{c - 0xdc00:02x}"
    return f"\\x{c:02x}" if c < 0x100 else f"\\u{c:04x}"


def printable(text: str) -> str:
    """text with every control character (C0, DEL, C1, bidirectional overrides) shown as \\xNN or
    \\uNNNN, as the C++ side's printable(): names and values read from files reach a terminal as
    text, never as escape sequences or line breaks."""
    return _CONTROL.sub(_escape, text)


def _clip(text: str, n: int = 60) -> str:
    """text for a one-line message: printable, and cut to n characters (saying how long it was)"""
    text = printable(text)
    return text if len(text) <= n else f"{text[:n]}… ({len(text)} characters)"


def _field(name: str) -> str:
    """a field's name for a one-line message: printable, its middle left out when long (a field
    2000 groups deep is vary[0].zip[0].zip[0]…zip[0].zip[0])"""
    name = printable(name)
    return name if len(name) <= 80 else f"{name[:45]}…{name[-30:]}"


_KINDS = ((stat.S_ISDIR, "a directory"), (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISFIFO, "a FIFO"), (stat.S_ISSOCK, "a socket"))


def read_text(path: str, limit: int = MAX_FILE_BYTES) -> str:
    """A regular file's text (UTF-8, at most `limit` bytes); raises ValueError with the reason
    (the caller names the file and what it is for).  Opened without blocking, so a FIFO is refused,
    not waited on, and read to at most limit + 1 bytes, so /dev/zero or a growing file cannot
    fill the memory."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError as e:
        raise ValueError(e.strerror) from None
    except ValueError:  # a NUL in the name
        raise ValueError("the name holds a NUL character") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            kind = next((k for test, k in _KINDS if test(st.st_mode)), "not a regular file")
            raise ValueError(f"{kind}, not a regular file")
        if st.st_size > limit:
            raise ValueError(f"{st.st_size} bytes, more than the {limit >> 20} MiB a file may have")
        with os.fdopen(os.dup(fd), "rb") as f:
            data = f.read(limit + 1)
    except OSError as e:
        raise ValueError(e.strerror) from None
    finally:
        os.close(fd)
    if len(data) > limit:
        raise ValueError(f"more than the {limit >> 20} MiB a file may have")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise ValueError(f"not UTF-8 text (byte {e.start})") from None


# ---------------------------------------------------------------- reading the sweep file

def _yaml12(base):
    """A PyYAML loader whose booleans are YAML 1.2's (true, false) as in the scenario parser: a
    joint named y or n, or dynamics: on, stays a string; and 1e-2 is a number, as in YAML 1.2
    (PyYAML's YAML 1.1 floats need a dot)."""
    class Loader(base):
        pass
    Loader.yaml_implicit_resolvers = {k: [(tag, rx) for tag, rx in v if tag != "tag:yaml.org,2002:bool"]
                                      for k, v in base.yaml_implicit_resolvers.items()}
    Loader.add_implicit_resolver("tag:yaml.org,2002:bool", re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"),
                                 list("tTfF"))
    Loader.add_implicit_resolver("tag:yaml.org,2002:float", re.compile(r"^[-+]?[0-9]+[eE][-+]?[0-9]+$"),
                                 list("-+0123456789"))
    return Loader


_Loader = _yaml12(yaml.SafeLoader)
_FastLoader = _yaml12(getattr(yaml, "CSafeLoader", yaml.SafeLoader))


class _Open:
    """A mapping or list being scanned: its nodes so far, and where in it the scan is."""
    __slots__ = ("mapping", "size", "anchor", "items", "key", "at_key")

    def __init__(self, mapping: bool, anchor: Optional[str]):
        self.mapping, self.size, self.anchor, self.items, self.key, self.at_key = mapping, 1, anchor, 0, "", True

    def label(self, first: bool) -> str:
        if not self.mapping:
            return f"[{self.items}]"
        if self.at_key:
            return " (a key)"
        return self.key if first else "." + self.key


def check_yaml(text: str, path: str):
    """Refuse a YAML document nested more than MAX_YAML_DEPTH deep, or of more than MAX_YAML_NODES
    nodes counting each alias as the nodes it stands for, naming file:line:column and the field
    (vary[0].values[3]).  A scan of the parser's events (libyaml's where PyYAML has it), before
    any composing: PyYAML composes recursively (2000 nested lists end in RecursionError, libyaml's
    composer in a crash), and it shares an alias's node, but whatever walks the values afterwards
    (a JSON dump, a table) expands them: a billion laughs in 9 lines.  Each anchor's size is kept,
    so the scan is linear in the text however the aliases nest."""
    stack: List[_Open] = []
    anchors: Dict[str, int] = {}

    def refuse(event, message: str):
        m = event.start_mark
        field = _field("".join(e.label(k == 0) for k, e in enumerate(stack)))
        raise Error(f"{path}:{m.line + 1}:{m.column + 1}: " + (f"{field}: {message}" if field else message))

    def add(event, size: int, key: str = "?"):
        if not stack:
            return
        top = stack[-1]
        top.size += size
        if top.size > MAX_YAML_NODES:
            refuse(event, f"expands to more than {MAX_YAML_NODES} YAML nodes through aliases (the most a document "
                          "may hold: an alias bomb?)")
        if top.mapping and top.at_key:
            top.key, top.at_key = _clip(key, 40), False
        else:
            top.items += 1
            top.at_key = True

    try:
        for event in yaml.parse(text, Loader=_FastLoader):
            if isinstance(event, yaml.ScalarEvent):
                if event.anchor is not None:
                    anchors[event.anchor] = 1
                add(event, 1, event.value)
            elif isinstance(event, yaml.AliasEvent):
                size = anchors.get(event.anchor)
                if size is None:
                    held = any(e.anchor == event.anchor for e in stack)
                    refuse(event, f"the alias *{_clip(event.anchor, 40)} " + ("stands for a node that holds it (a "
                           "structure without end)" if held else "names no anchor before it"))
                add(event, size)
            elif isinstance(event, yaml.CollectionStartEvent):
                if len(stack) >= MAX_YAML_DEPTH:
                    refuse(event, f"nested more than {MAX_YAML_DEPTH} levels deep (the most a sweep file or "
                                  "scenario may nest)")
                stack.append(_Open(isinstance(event, yaml.MappingStartEvent), event.anchor))
            elif isinstance(event, yaml.CollectionEndEvent):
                done = stack.pop()
                if done.anchor is not None:
                    anchors[done.anchor] = done.size
                add(event, done.size)
            elif isinstance(event, yaml.DocumentEndEvent):
                anchors.clear()
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        where = f"{path}:{mark.line + 1}:{mark.column + 1}" if mark else path
        raise Error(f"{where}: not valid YAML: {printable(str(getattr(e, 'problem', e)))}") from None


class _Doc:
    """A YAML document's nodes, for values and file:line:column messages."""

    def __init__(self, text: str, path: str):
        self.path = path
        check_yaml(text, path)
        self.loader = _Loader(text)
        try:
            self.root = self.loader.get_single_node()
        except yaml.YAMLError as e:
            mark = getattr(e, "problem_mark", None)
            where = f"{path}:{mark.line + 1}:{mark.column + 1}" if mark else path
            raise Error(f"{where}: not valid YAML: {printable(str(getattr(e, 'problem', e)))}") from None

    def where(self, node) -> str:
        m = node.start_mark
        return f"{self.path}:{m.line + 1}:{m.column + 1}"

    def fail(self, node, field: str, message: str):
        field = _field(field)
        raise Error(f"{self.where(node)}: {field}: {message}" if field else f"{self.where(node)}: {message}")

    def value(self, node, field: str = ""):
        """the node as Python data (tags PyYAML's safe loader does not know, or an integer of more
        digits than Python converts, are refused at the node)"""
        try:
            return self.loader.construct_object(node, deep=True)
        except yaml.YAMLError as e:
            self.fail(node, field, f"cannot read this value: {printable(str(getattr(e, 'problem', e)))}")
        except (ValueError, TypeError, OverflowError) as e:
            self.fail(node, field, f"cannot read this value: {printable(str(e))}")

    def mapping(self, node, field: str, allowed: Sequence[str]) -> Dict[str, Any]:
        if not isinstance(node, yaml.MappingNode):
            self.fail(node, field, f"expected a mapping, got {_show(node)}")
        out = {}
        for k, v in node.value:
            key = self.value(k, field)
            name = f"{field}.{key}" if field else str(key)
            if not isinstance(key, str) or key not in allowed:
                self.fail(k, name, f"unknown field (expected one of {', '.join(allowed)})")
            if key in out:
                self.fail(k, name, "given twice")
            out[key] = v
        return out

    def number(self, node, field: str, positive=False) -> float:
        """a finite number (an int or a float, not a boolean), as written"""
        v = self.value(node, field)
        ok = isinstance(v, (int, float)) and not isinstance(v, bool)
        if ok:
            try:
                x = float(v)
            except OverflowError:
                self.fail(node, field, f"expected a finite number, got {_show(node)} (too large)")
            ok = math.isfinite(x) and (x > 0 or not positive)
        if not ok:
            self.fail(node, field, f"expected {'a positive' if positive else 'a finite'} number, got {_show(node)}")
        return v

    def integer(self, node, field: str, low: int, high: Optional[int], what: str) -> int:
        """an integer in [low, high] (high None: no bound; not a float, not a boolean)"""
        v = self.value(node, field)
        if not isinstance(v, int) or isinstance(v, bool) or v < low or (high is not None and v > high):
            self.fail(node, field, f"expected {what}, got {_show(node)}")
        return v

    def pair(self, node, field: str) -> Tuple[float, float]:
        if not isinstance(node, yaml.SequenceNode) or len(node.value) != 2:
            self.fail(node, field, f"expected [a, b], got {_show(node)}")
        return self.number(node.value[0], field + "[0]"), self.number(node.value[1], field + "[1]")


def _show(node) -> str:
    if isinstance(node, yaml.ScalarNode):
        return f"'{_clip(node.value)}'"
    return {yaml.MappingNode: "a mapping", yaml.SequenceNode: "a list"}.get(type(node), "nothing")


def _plain(value, seen=None) -> Optional[str]:
    """None if value is what JSON carries to the scenario parser (a string, a finite number, a
    boolean, null, or lists and string-keyed mappings of them), else what is wrong with it"""
    if isinstance(value, (str, bool, int)) or value is None:
        return None
    if isinstance(value, float):
        return None if math.isfinite(value) else f"expected a finite number, got {value}"
    seen = set() if seen is None else seen
    if id(value) in seen:  # an alias: checked where it was first met
        return None
    seen.add(id(value))
    if isinstance(value, list):
        return next((e for e in (_plain(v, seen) for v in value) if e), None)
    if isinstance(value, dict):
        if not all(isinstance(k, str) for k in value):
            return "expected a mapping with names as keys"
        return next((e for e in (_plain(v, seen) for v in value.values()) if e), None)
    return f"expected a number, a string, or a list or mapping of them, got a {type(value).__name__}"


_SEGMENT = re.compile(r"([^.\[\]]+)((?:\[-?\d+\])*)")


def parse_path(path: str) -> List[Any]:
    """'inputs.springs[0].stiffness' -> ['inputs', 'springs', 0, 'stiffness']."""
    tokens: List[Any] = []
    for seg in path.split("."):
        m = _SEGMENT.fullmatch(seg)
        if not m:
            raise ValueError(f"bad path segment '{_clip(seg)}' (expected name or name[index])")
        tokens.append(m.group(1))
        for i in re.findall(r"\[(-?\d+)\]", m.group(2)):
            # Python's count from the end would silently pick the last coordinate or entry
            if i.startswith("-"):
                raise ValueError(f"{m.group(1)}[{i}]: a negative index; entries count from 0 (write the index itself)")
            tokens.append(int(i))
    return tokens


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
            ref = doc.mapping(top["reference"], "reference", ("method", "rtol", "atol", "dt", "max_step", "max_steps", "dynamics"))
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
    if not 0 <= index < len(names):
        raise ValueError(f"initial.{which}[{index}]: index out of range (the model has {len(names)})")
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
                if not isinstance(node, list) or not 0 <= tok < len(node):
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


def empty_row() -> Dict[str, Any]:
    """A case's row before its run (a refused case keeps it so, with its status)."""
    return {"status": "", "completed": False, "initial_energy": math.nan, "t_reached": math.nan, "steps": 0,
            "rhs_evals": 0, "cpu_seconds": math.nan, "max_energy_balance_error": math.nan,
            "final_energy_balance_error": math.nan, "state_error": math.nan, "final_state_error": math.nan,
            "reference_status": ""}


def compare_reference(row: Dict[str, Any], t: np.ndarray, y: np.ndarray, completed: bool, ref) -> None:
    """The row's state errors: the run's samples (t, y = [q v] per row) against its reference run's
    (t_ref, y_ref, whether it completed): the largest difference over the common output times,
    and at t_end when both completed."""
    t_ref, y_ref, ref_done = ref
    # the samples at common times (a step that does not divide output_dt samples at step
    # times; every run that completes has its last sample at t_end)
    k = np.clip(np.searchsorted(t_ref, t), 0, len(t_ref) - 1)
    same = np.abs(t_ref[k] - t) <= 1e-12 * np.maximum(1.0, np.abs(t))
    if np.any(same):
        diff = np.abs(y[same] - y_ref[k[same]])
        row["state_error"] = float(np.max(diff)) if np.all(np.isfinite(diff)) else math.inf
    if completed and ref_done:
        row["final_state_error"] = float(np.max(np.abs(y[-1] - y_ref[-1])))


def run_case(sweep_tree: dict, model, scenario_path: str, values: Dict[str, Any],
             reference: Optional[Dict[str, Any]] = None, log: Optional[str] = None,
             cache: Optional[dict] = None) -> Dict[str, Any]:
    """One case's row: status, steps, RHS evaluations, CPU time, energy errors, state error
    against the reference run (max over the common output samples, and at t_end)."""
    from . import simulate
    row = empty_row()
    try:
        tree = apply(sweep_tree, model, values)
        scene = parse_scenario(_text(tree), case_path(scenario_path))
        traj = simulate(scene, output=log)
    except (Error, ValueError, TypeError) as e:
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
            compare_reference(row, traj.t, _state(traj), s.completed, ref)
    return row


def run_batch(scenario_text: str, scenario_path: str, settings: Dict[str, Any],
              cases: List[Tuple[int, Dict[str, Any]]], reference: Optional[Dict[str, Any]],
              logs_dir: Optional[str] = None, together: bool = True) -> List[Dict[str, Any]]:
    """A Dask task: run the given (case id, values) and return their rows.  Pure: the same input
    gives the same rows (CPU times aside), whichever worker runs it and however often.  Without
    logs_dir (and with together), the cases that differ only in their initial state run together,
    one library call per such group (soadyn._batched); the rest, and every case with logs_dir,
    one soadyn.simulate each: the rows are the same, bit for bit, either way."""
    tree = yaml.load(scenario_text, Loader=_FastLoader)
    model = parse_scenario(scenario_text, case_path(scenario_path)).model
    cache: dict = {}
    done: Dict[int, Dict[str, Any]] = {}
    if together and not logs_dir:
        from ._batched import run_together
        done = run_together(tree, model, scenario_path, [(cid, dict(settings, **values)) for cid, values in cases],
                            reference, cache)
    rows = []
    for cid, values in cases:
        if cid in done:
            rows.append(done[cid])
            continue
        log = None
        if logs_dir:
            os.makedirs(logs_dir, exist_ok=True)
            log = os.path.join(logs_dir, f"case-{cid:07d}.h5")
        row = run_case(tree, model, scenario_path, dict(settings, **values), reference, log, cache)
        row["case"] = cid
        rows.append(row)
    return rows
